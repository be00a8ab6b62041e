"""The solver-benchmarking field's summary of a benchmark table (:func:`rpbench.bench.runner.run_benchmark`).

* **Solved**: rows whose ``verdict`` is ``optimal`` (proven, and agreeing with the known values and the
  other presets), out of the instances of the tier.
* **Shifted geometric mean** (Achterberg 2007; Mittelmann's benchmarks) of the fastest run's total time
  (build + solve + extract): ``exp(mean(log(t + s))) - s``.  An unsolved row (any verdict but
  ``optimal``: time limit, wrong answer, error, killed, out of memory) counts at its time limit, the
  field's convention; with no limit the mean is undefined (NaN).  The shift ``s`` is per tier
  (:data:`SHIFTS`, or one given for all): it damps the weight of the instances that solve in almost no
  time, and so grows with the tier's sizes.  ``sgm_ratio`` divides by the tier's best preset (1.00).
* **Repeat spread**: the median over a preset's repeated solves of ``(max - min) / median`` of their
  totals (``total_s_min`` / ``_median`` / ``_max``): how much the best-of-N times can be trusted.
* **Performance profile** (Dolan and Moré 2002): for preset p and instance m, ``r = t_pm / min_p t_pm``
  over the presets that solved m; ``rho_p(tau)`` is the share of instances with ``r <= tau``; an unsolved
  instance never counts.  :func:`performance_profile` tabulates it at every ratio that occurs.

:func:`solver_environment` adds the machine and every solver library's version to
:func:`rpbench.results.store.environment`; :func:`write_outputs` writes a ``rpbench bench --out`` folder.
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Iterable, Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.results import store

#: The tier of an instance whose metadata names none.
NO_TIER = "all"
#: The shift of :func:`shifted_geometric_mean` for a tier :data:`SHIFTS` does not name, in seconds: rpbench's
#: models solve in milliseconds, so a 10 ms shift plays the role the field's 10 s shift plays for MIPs that
#: run for minutes.
SHIFT_S = 0.01
#: The shift of the shifted geometric mean, in seconds, by tier name (:mod:`rpbench.library.sets`): about a
#: tenth of the tier's typical solve.  rpbench's small models solve in milliseconds, so the field's 10 s
#: shift (for MIPs that run for minutes) belongs to XL only.  An unknown tier, or none (``all``), gets
#: :data:`SHIFT_S` (10 ms), as ``rpbench bench --html`` always did.
SHIFTS = {"S": 0.01, "M": 0.1, "L": 1.0, "XL": 10.0, NO_TIER: SHIFT_S}
#: The label of the rows summing up every tier (only when there is more than one).
TOTAL = "total"
#: Times are floored at this before they are divided (an empty model solves in zero time).
TIME_FLOOR_S = 1e-6
SUMMARY_COLUMNS = [
    "tier",
    "preset",
    "instances",
    "solved",
    "wrong",
    "time_limit",
    "memory_limit",
    "error",
    "killed",
    "sgm_s",
    "sgm_ratio",
    "shift_s",
    "repeat_spread",
]
#: Distributions whose versions a benchmark records ("not installed" when absent): the solver libraries of
#: the built-in backends, the tests' matching reference (networkx), and the numeric stack they run on.
SOLVER_PACKAGES = (
    "highspy",
    "ortools",
    "pyomo",
    "cvxpy",
    "pymatching",
    "lap",
    "scipy",
    "networkx",
    "ogdf-python",
    "ogdf-wheel",
    "cppyy",
    "numpy",
    "pandas",
    "numba",
)
NOT_INSTALLED = "not installed"


def solved(table: pd.DataFrame) -> pd.Series:
    """The rows that count as solved: verdict ``optimal`` (proven, and agreeing with the known values and the
    other presets; :func:`with_verdicts` gives an older table its verdicts)."""
    return with_verdicts(table)["verdict"] == "optimal"


def with_verdicts(table: pd.DataFrame) -> pd.DataFrame:
    """A benchmark table with a ``verdict``: a table written before verdicts existed gets ``optimal`` where
    it was proven optimal and agreed with the other presets (no ``agrees``: nothing to disagree with),
    ``wrong`` where a proven optimum disagreed, else its status."""
    if "verdict" in table:
        return table
    agrees = table["agrees"] if "agrees" in table else pd.Series(True, index=table.index)
    disagrees = ~agrees.astype("boolean").fillna(True).astype(bool)
    optimal = table["status"] == "optimal"
    return table.assign(verdict=table["status"].mask(optimal & disagrees, "wrong"))


def shifted_geometric_mean(times: np.ndarray, shift: float = SHIFT_S) -> float:
    """``exp(mean(log(t + s))) - s`` (NaN for no times)."""
    times = np.asarray(times, dtype=float)
    if not len(times):
        return float("nan")
    return float(np.exp(np.mean(np.log(times + shift))) - shift)


def shift_for(tier: str, shift: float | None = None) -> float:
    """The shift of ``tier``: ``shift`` when given, else :data:`SHIFTS` (10 ms for a tier it does not name)."""
    return float(shift) if shift is not None else SHIFTS.get(tier, SHIFT_S)


def sgm_times(table: pd.DataFrame) -> pd.Series:
    """Each row's time in the mean: its fastest total when solved, else its time limit (NaN: none).  A table
    written before the limit was recorded (no ``time_limit_s``) counts an unsolved row at the time it took."""
    if "time_limit_s" not in table:
        return table["total_s"].astype(float)
    return table["total_s"].where(solved(table), table["time_limit_s"]).astype(float)


def summarise(table: pd.DataFrame, shift: float | None = None) -> pd.DataFrame:
    """One row per (tier, preset), :data:`SUMMARY_COLUMNS`, tiers in order of their first instance; rows of
    tier :data:`TOTAL` over every instance follow when there is more than one tier."""
    tiers = list(dict.fromkeys(table["tier"])) if "tier" in table else [NO_TIER]
    tier_of = table["tier"] if "tier" in table else pd.Series(NO_TIER, index=table.index)
    groups = [(t, table[tier_of == t], shift_for(t, shift)) for t in tiers]
    if len(tiers) > 1:
        groups.append((TOTAL, table, shift_for(NO_TIER, shift)))
    rows = []
    for tier, g, s in groups:
        times = sgm_times(g)
        block = []
        for preset, h in g.groupby("preset", sort=True):
            verdicts = h["verdict"]
            block.append(
                {
                    "tier": tier,
                    "preset": preset,
                    "instances": int(h["model"].nunique()),
                    "solved": int((verdicts == "optimal").sum()),
                    **{
                        v: int((verdicts == v).sum())
                        for v in ("wrong", "time_limit", "memory_limit", "error", "killed")
                    },
                    "sgm_s": _sgm(times[h.index].to_numpy(), s),
                    "shift_s": s,
                    "repeat_spread": repeat_spread(h),
                }
            )
        best = np.nanmin([r["sgm_s"] for r in block]) if any(np.isfinite(r["sgm_s"]) for r in block) else np.nan
        for r in block:
            r["sgm_ratio"] = r["sgm_s"] / best if np.isfinite(best) and best > 0 else np.nan
        rows += block
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def _sgm(times: np.ndarray, shift: float) -> float:
    if len(times) == 0 or not np.isfinite(times).all():
        return float("nan")
    return shifted_geometric_mean(np.maximum(times, TIME_FLOOR_S), shift)


def repeat_spread(rows: pd.DataFrame) -> float:
    """Median ``(max - min) / median`` of the totals of the rows solved more than once (NaN: none was)."""
    if "total_s_median" not in rows:
        return float("nan")
    many = rows[(rows["repeats"] > 1) & solved(rows)]
    if many.empty:
        return float("nan")
    spread = (many["total_s_max"] - many["total_s_min"]) / np.maximum(many["total_s_median"], TIME_FLOOR_S)
    return float(np.median(spread))


def performance_ratios(table: pd.DataFrame) -> pd.DataFrame:
    """Instance x preset: time over the fastest solving preset's time (inf: not solved by that preset)."""
    ok = table[solved(table)]
    times = ok.pivot_table(index="model", columns="preset", values="total_s", aggfunc="min")
    times = times.reindex(index=sorted(set(table["model"])), columns=sorted(set(table["preset"])))
    times = np.maximum(times, TIME_FLOOR_S)
    return times.div(times.min(axis=1), axis=0).fillna(np.inf)


def performance_profile(table: pd.DataFrame) -> pd.DataFrame:
    """Columns ``preset``, ``tau``, ``fraction``: for every preset, at 1 and at every finite ratio any preset
    reached, the share of instances it solved within ``tau`` times the fastest preset's time."""
    ratios = performance_ratios(table)
    n = len(ratios)
    finite = ratios.to_numpy()[np.isfinite(ratios.to_numpy())]
    taus = np.unique(np.concatenate([[1.0], finite]))
    rows = [
        {"preset": str(p), "tau": float(tau), "fraction": float((ratios[p] <= tau).sum() / n) if n else 0.0}
        for p in ratios.columns
        for tau in taus
    ]
    return pd.DataFrame(rows, columns=["preset", "tau", "fraction"])


def profile_steps(profile: pd.DataFrame) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """A profile table as :func:`rpbench.report.html.figures.profile_figure` draws it: per preset the
    ratios where its share rises and the share at each."""
    out = {}
    for preset, g in profile.groupby("preset", sort=True):
        tau, share = g["tau"].to_numpy(), g["fraction"].to_numpy()
        rises = np.diff(np.concatenate([[0.0], share])) > 0
        out[str(preset)] = (tau[rises], share[rises])
    return out


# ------------------------------------------------------------------ environment
def solver_environment(packages: Iterable[str] = SOLVER_PACKAGES) -> dict[str, Any]:
    """:func:`rpbench.results.store.environment` with the CPU model and logical cores in ``machine``, and
    ``versions`` of rpbench, Python and every package of ``packages`` ("not installed" when absent)."""
    env = store.environment()
    machine = dict(env["machine"])
    machine["cpu_model"] = cpu_model()
    machine["logical_cores"] = os.cpu_count()
    versions = {k: (v if v is not None else NOT_INSTALLED) for k, v in env["versions"].items()}
    for pkg in packages:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = NOT_INSTALLED
    return {**env, "machine": machine, "versions": versions}


def cpu_model(cpuinfo: Path = Path("/proc/cpuinfo")) -> str | None:
    """The CPU's model name from ``/proc/cpuinfo`` (Linux), else what :func:`platform.processor` says."""
    try:
        text = cpuinfo.read_text(errors="replace")
    except OSError:
        text = ""
    for key in ("model name", "Model", "Hardware", "cpu model", "Processor"):
        for line in text.splitlines():
            name, sep, value = line.partition(":")
            if sep and name.strip() == key and value.strip():
                return value.strip()
    return platform.processor() or None


# ------------------------------------------------------------------ printing
def format_summary(summary: pd.DataFrame) -> str:
    """A plain-text table of :func:`summarise`: solved / instances, the shifted geometric mean (ms) and its
    ratio to the tier's best preset, the shift, the failures."""
    head = (
        f"{'tier':<8} {'preset':<14} {'solved':>9} {'SGM ms':>12} {'SGM/best':>9} {'shift ms':>9} "
        f"{'spread':>7}  failures"
    )
    lines = [head, "-" * len(head)]
    for _, r in summary.iterrows():
        lines.append(
            f"{r['tier']:<8} {r['preset']:<14} {r['solved']:>4}/{r['instances']:<4} {_ms(r['sgm_s']):>12} "
            f"{_ratio(r['sgm_ratio']):>9} {1e3 * r['shift_s']:>9g} {_pct(r['repeat_spread']):>7}  {_failures(r)}"
        )
    return "\n".join(lines)


def _failures(r: Mapping[str, Any]) -> str:
    parts = [f"{r[k]} {k}" for k in ("wrong", "time_limit", "memory_limit", "error", "killed") if r[k]]
    return ", ".join(parts) or "-"


def _ms(seconds: float) -> str:
    return "-" if not np.isfinite(seconds) else f"{1e3 * seconds:,.3f}"


def _ratio(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{x:.2f}"


def _pct(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{100 * x:.0f}%"


# ------------------------------------------------------------------ the --out folder
def write_outputs(
    folder: Path,
    table: pd.DataFrame,
    *,
    title: str,
    settings: Mapping[str, Any],
    shift: float | None = None,
    env: Mapping[str, Any] | None = None,
    known_values: str | None = None,
) -> dict[str, Path]:
    """Write ``results.csv`` (the rows), ``summary.csv``, ``profile.csv``, ``profile.png`` (with SVG and PDF
    beside it), ``environment.json`` (the machine, the versions and ``settings``), ``report.md`` and
    ``meta.json`` (kind ``bench``, every file of the folder, ``known_values``: the name of the known-values
    file the caller already wrote there, or None) into ``folder``; return them by name.  ``rpbench check``
    recomputes the verdicts, the summary and the profile from these files
    (:mod:`rpbench.check.bench`)."""
    from rpbench.report.plots import profile_figure
    from rpbench.spec import FIGURE_FORMATS

    env = dict(env if env is not None else solver_environment())
    summary = summarise(table, shift)
    profile = performance_profile(table)
    paths = {name: folder / name for name in ("results.csv", "summary.csv", "profile.csv", "environment.json")}
    table.to_csv(paths["results.csv"], index=False)
    summary.to_csv(paths["summary.csv"], index=False)
    profile.to_csv(paths["profile.csv"], index=False)
    store.write_json(paths["environment.json"], {**env, "bench": dict(settings)})
    paths["profile.png"] = profile_figure(
        profile, folder / "profile.png", f"Performance profile: {title}", formats=FIGURE_FORMATS
    )
    paths["profile.svg"] = folder / "profile.svg"
    paths["report.md"] = folder / "report.md"
    paths["report.md"].write_text(bench_markdown(table, summary, env, settings, title), encoding="utf-8")
    paths["meta.json"] = folder / "meta.json"
    listed = sorted(p.name for p in folder.iterdir() if p.is_file())
    meta = {"kind": "bench", "rpbench_version": env.get("versions", {}).get("rpbench"), "files": listed}
    store.write_json(paths["meta.json"], {**meta, "known_values": known_values})
    return paths


def bench_markdown(
    table: pd.DataFrame,
    summary: pd.DataFrame,
    env: Mapping[str, Any],
    settings: Mapping[str, Any],
    title: str,
) -> str:
    """``report.md`` of a benchmark: machine and versions, settings, the per-preset summary, the profile
    figure, every solve."""
    machine, versions = env.get("machine", {}), env.get("versions", {})
    lines = [f"# rpbench bench: {title}", ""]
    if settings.get("command"):
        lines += ["```", str(settings["command"]), "```", ""]
    cores = machine.get("logical_cores", machine.get("cpus"))
    lines += [
        "## Machine and versions",
        "",
        *_md_table(
            ["", ""],
            [
                ["platform", str(machine.get("platform"))],
                ["CPU", f"{machine.get('cpu_model') or machine.get('processor')} ({cores} logical cores)"],
                ["memory", f"{machine.get('memory_gib')} GiB"],
                ["Python", str(versions.get("python"))],
                ["rpbench", f"{versions.get('rpbench')} (commit {env.get('git_commit') or 'unknown'})"],
                ["run at", str(env.get("created"))],
            ],
        ),
        "",
        "Libraries: "
        + ", ".join(f"{k} {v}" for k, v in sorted(versions.items()) if k not in ("python", "rpbench"))
        + ".",
        "",
        "## Settings",
        "",
        *(f"- {k.replace('_', ' ')}: {_setting(v)}" for k, v in settings.items() if k != "command"),
        "",
        "## Per preset",
        "",
        *_md_table(
            ["tier", "preset", "solved", "SGM (ms)", "SGM / best", "shift (ms)", "repeat spread", "failures"],
            [
                [
                    str(r["tier"]),
                    str(r["preset"]),
                    f"{r['solved']} / {r['instances']}",
                    _ms(r["sgm_s"]),
                    _ratio(r["sgm_ratio"]),
                    f"{1e3 * r['shift_s']:g}",
                    _pct(r["repeat_spread"]),
                    _failures(r),
                ]
                for _, r in summary.iterrows()
            ],
        ),
        "",
        "Solved: verdict `optimal` (proven, and agreeing with the known values and the other presets). "
        "SGM: shifted geometric mean of the fastest run's build + solve + extract time, an unsolved instance "
        "counted at its time limit; SGM / best: over the tier's fastest preset. Repeat spread: median over the "
        "repeated solves of (max - min) / median of their times.",
        "",
        "## Performance profile",
        "",
        "![performance profile](profile.png)",
        "",
        "For each preset, the share of instances it solved within τ times the fastest preset's time (Dolan "
        "and Moré); the values are in `profile.csv`.",
        "",
        "## Every solve",
        "",
        *_md_table(
            ["model", "tier", "preset", "status", "verdict", "objective", "total ms (min / median / max)", "message"],
            [
                [
                    str(r["model"]),
                    str(r["tier"]),
                    str(r["preset"]),
                    str(r["status"]),
                    f"**{r['verdict']}**" if r["verdict"] == "wrong" else str(r["verdict"]),
                    "-" if pd.isna(r["objective"]) else f"{r['objective']:.0f}",
                    " / ".join(_ms(r[c]) for c in ("total_s_min", "total_s_median", "total_s_max")),
                    r["message"],
                ]
                for _, r in table.iterrows()
            ],
        ),
        "",
    ]
    return "\n".join(lines)


def _md_table(head: list[str], rows: Iterable[list[Any]]) -> list[str]:
    out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    return out + ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in rows]


def _md_cell(value: Any) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return ""
    return str(value).replace("|", "\\|").replace("\n", " ")


def _setting(value: Any) -> str:
    if value is None:
        return "none"
    if isinstance(value, Mapping):
        return ", ".join(f"{k} {_setting(v)}" for k, v in value.items()) or "none"
    if isinstance(value, (list, tuple)):
        return ", ".join(map(str, value)) or "none"
    return json.dumps(value) if isinstance(value, bool) else str(value)
