"""``rpbench check`` of a ``rpbench bench --out`` folder, from its own files.

The folder's claims are recomputed from ``results.csv`` (one row per instance and preset) and the known
values it was judged against (``known.solu``, a copy of the lines of the ``.solu`` files the bench read),
with this module's own code, not the bench's:

* ``manifest`` — every file meta.json lists is there;
* ``environment`` — environment.json names the machine (platform, CPU, cores), the versions of rpbench
  and of every solver library, and the settings the bench ran with;
* ``known-values`` — every instance named in ``known.solu`` was benchmarked;
* ``verdict`` (per preset) — each row's verdict is the one its status and objective earn against the
  known value and the optima the other presets proved (instances/README.md, "The bench report");
* ``summary`` — summary.csv is the per-(tier, preset) count of verdicts, shifted geometric mean of the
  time (unsolved rows at their time limit), its ratio to the tier's best preset and the repeat spread;
* ``profile`` — profile.csv is the Dolan-Moré performance profile of the solved rows;
* ``report`` — report.md shows the summary's solved counts.

An unreadable folder (a file missing or unparseable, a column missing) is a :class:`ResultsError`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.check.core import FOLDER, FolderResult, RunCheck
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.report.bench import TOTAL
from rpbench.results.solu import Known, read_solu

#: The meta.json ``kind`` of a bench folder.
KIND = "bench"
KNOWN_FILE = "known.solu"
REQUIRED_RESULT_COLUMNS = (
    "model",
    "tier",
    "preset",
    "status",
    "objective",
    "recorded",
    "verdict",
    "total_s",
    "total_s_min",
    "total_s_median",
    "total_s_max",
    "repeats",
    "time_limit_s",
)
CHECKED_SUMMARY_COLUMNS = ("tier", "preset", "instances", "solved", "sgm_s", "sgm_ratio", "shift_s", "repeat_spread")
FAILURES = ("wrong", "time_limit", "memory_limit", "error", "killed")
#: What environment.json must name.
MACHINE_KEYS = ("platform", "cpu_model")
#: Objectives are integral sums written in full; this absorbs only a decimal rendering's last digit.
RTOL = 1e-9
#: Times and means are floored here before logarithms and ratios (as the bench does: a zero-time solve).
FLOOR_S = 1e-6


def check_bench(folder: Path) -> FolderResult:
    """Check a bench folder; an unreadable one is a :class:`FolderResult` with ``error`` set."""
    out = FolderResult(str(folder))
    try:
        with np.errstate(all="ignore"):
            out.folder_check, out.runs = _audit(Path(folder))
    except RpbenchError as exc:
        out.error = one_line(exc)
    return out


def _audit(folder: Path) -> tuple[RunCheck, list[RunCheck]]:
    meta = results.read_meta(folder)
    own = RunCheck(FOLDER)
    listed = meta.get("files")
    if not isinstance(listed, list) or not all(isinstance(f, str) for f in listed):
        raise ResultsError(f"{str(folder / 'meta.json')!r}: 'files' must list the folder's files")
    own.checked["manifest"] = len(listed)
    for name in listed:
        if not (folder / name).is_file():
            own.fail("manifest", f"{name} is listed in meta.json but missing")
    table = _results(folder / "results.csv")
    known = _known(folder, meta)
    _check_environment(folder / "environment.json", own)
    own.checked["known-values"] = len(known)
    for name in sorted(set(known) - set(table["model"])):
        own.fail("known-values", f"{KNOWN_FILE} names {name!r}, which was not benchmarked")
    runs = []
    for preset, rows in table.groupby("preset", sort=True):
        run = RunCheck(f"preset {preset}")
        run.checked["verdict"] = len(rows)
        for i, r in rows.iterrows():
            want = expected_verdict(table, int(i), known.get(str(r["model"])))
            if want != r["verdict"]:
                run.fail("verdict", f"{r['model']}: verdict {r['verdict']!r}, but its answer earns {want!r}")
        runs.append(run)
    summary = _read(folder / "summary.csv", CHECKED_SUMMARY_COLUMNS)
    _check_summary(table, summary, own)
    _check_profile(table, _read(folder / "profile.csv", ("preset", "tau", "fraction")), own)
    _check_report(folder / "report.md", summary, own)
    return own, runs


# ------------------------------------------------------------------ reading
def _read(path: Path, columns: tuple[str, ...]) -> pd.DataFrame:
    if not path.is_file():
        raise ResultsError(f"bench folder file {str(path)!r} is missing")
    table = results.read_csv(path)
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ResultsError(f"bench folder file {str(path)!r} lacks the column(s) {', '.join(missing)}")
    return table


def _results(path: Path) -> pd.DataFrame:
    table = _read(path, REQUIRED_RESULT_COLUMNS)
    for name in ("model", "tier", "preset", "status", "verdict"):
        table[name] = table[name].fillna("").astype(str)
    for name in set(REQUIRED_RESULT_COLUMNS) - {"model", "tier", "preset", "status", "verdict"}:
        number = pd.to_numeric(table[name], errors="coerce")
        if (number.isna() & table[name].notna()).any():
            raise ResultsError(f"bench folder file {str(path)!r}: column {name!r} holds text, not numbers")
        table[name] = number.astype(float)
    if table.duplicated(["model", "preset"]).any():
        raise ResultsError(f"bench folder file {str(path)!r}: an instance appears twice for one preset")
    return table.reset_index(drop=True)


def _known(folder: Path, meta: dict[str, Any]) -> dict[str, Known]:
    name = meta.get("known_values")
    if name is None:
        return {}
    if name != KNOWN_FILE or not (folder / KNOWN_FILE).is_file():
        raise ResultsError(f"{str(folder / 'meta.json')!r}: known_values names {name!r}, which is not in the folder")
    try:
        return read_solu(folder / KNOWN_FILE)
    except RpbenchError as exc:
        raise ResultsError(one_line(exc)) from None


def _check_environment(path: Path, own: RunCheck) -> None:
    if not path.is_file():
        raise ResultsError(f"bench folder file {str(path)!r} is missing")
    try:
        env = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ResultsError(f"{str(path)!r} is not valid JSON: {one_line(exc)}") from None
    own.checked["environment"] = 1
    if not isinstance(env, dict):
        own.fail("environment", "environment.json does not hold an object")
        return
    machine, versions, bench = env.get("machine"), env.get("versions"), env.get("bench")
    if not isinstance(machine, dict) or any(not machine.get(k) for k in MACHINE_KEYS):
        own.fail("environment", f"environment.json's machine lacks {' or '.join(MACHINE_KEYS)}")
    elif not (machine.get("logical_cores") or machine.get("cpus")):
        own.fail("environment", "environment.json's machine lacks its number of cores")
    if not isinstance(versions, dict) or not versions.get("rpbench") or len(versions) < 2:
        own.fail("environment", "environment.json lacks the versions of rpbench and of the solver libraries")
    if not isinstance(bench, dict) or "presets" not in bench or "time_limit_s" not in bench:
        own.fail("environment", "environment.json lacks the bench's settings (presets, time limits)")


# ------------------------------------------------------------------ verdicts
def _same(a: float, b: float) -> bool:
    return abs(a - b) <= RTOL * max(1.0, abs(b))


def _exceeds(a: float, b: float) -> bool:
    return a > b and not _same(a, b)


def expected_verdict(table: pd.DataFrame, i: int, known: Known | None) -> str:
    """The verdict row ``i`` of a bench table earns (the rules of instances/README.md, "The bench report"):
    a failure stays a failure; an answer that contradicts the known value, or (without a proven optimum on
    file) the optimum another preset proved or the one recorded with the instance, is ``wrong``; otherwise
    the status speaks."""
    r = table.loc[i]
    status = str(r["status"])
    if status in ("error", "killed", "memory_limit"):
        return status
    same_model = table[(table["model"] == r["model"]) & (table.index != i) & (table["status"] == "optimal")]
    others = [float(v) for v in same_model["objective"] if math.isfinite(v)]
    if math.isfinite(r["recorded"]):
        others.append(float(r["recorded"]))
    tag = known.kind if known is not None else "unkn"
    value = known.value if known is not None else None
    if status == "infeasible":
        if tag == "inf":
            return "optimal"
        return "wrong" if tag in ("opt", "best") or others else "infeasible"
    objective = float(r["objective"])
    if not math.isfinite(objective):  # stopped without a solution
        return status if status in ("time_limit", "feasible") else "error"
    if tag == "inf":
        return "wrong"
    proven = status == "optimal"
    if tag == "opt" and value is not None and ((proven and not _same(objective, value)) or _exceeds(objective, value)):
        return "wrong"
    if tag == "best" and value is not None and proven and _exceeds(value, objective):
        return "wrong"
    if tag == "bound" and value is not None and _exceeds(objective, value):
        return "wrong"
    if tag != "opt" and others:
        if proven and not all(_same(objective, v) for v in others):
            return "wrong"
        if not proven and all(_exceeds(objective, v) for v in others):
            return "wrong"
    if proven:
        return "optimal"
    return status if status in ("time_limit", "feasible") else "feasible"


# ------------------------------------------------------------------ summary and profile
def _sgm(times: np.ndarray, shift: float) -> float:
    if len(times) == 0 or not np.isfinite(times).all():
        return float("nan")
    return float(np.exp(np.log(np.maximum(times, FLOOR_S) + shift).mean()) - shift)


def _close(a: float, b: float) -> bool:
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.isnan(a) == math.isnan(b) and (math.isnan(a) or a == b)
    return abs(a - b) <= 1e-9 * max(1.0, abs(b))


def _check_summary(table: pd.DataFrame, summary: pd.DataFrame, own: RunCheck) -> None:
    tiers = list(dict.fromkeys(table["tier"]))
    groups = [(t, table[table["tier"] == t]) for t in tiers]
    if len(tiers) > 1:
        groups.append((TOTAL, table))
    want = {(t, p) for t, g in groups for p in set(g["preset"])}
    have = {(str(t), str(p)) for t, p in zip(summary["tier"], summary["preset"], strict=True)}
    own.checked["summary"] = len(want)
    for t, p in sorted(want ^ have):
        own.fail("summary", f"summary.csv {'lacks' if (t, p) in want else 'adds'} the row of tier {t}, preset {p}")
    rows = {(str(r["tier"]), str(r["preset"])): r for _, r in summary.iterrows()}
    for tier, g in groups:
        solved = g["verdict"] == "optimal"
        times = g["total_s"].where(solved, g["time_limit_s"]).to_numpy(dtype=float)
        sgm: dict[str, float] = {}
        for preset, h in g.groupby("preset", sort=True):
            row = rows.get((str(tier), str(preset)))
            if row is None:
                continue
            counts = {"instances": h["model"].nunique(), "solved": int((h["verdict"] == "optimal").sum())}
            counts |= {v: int((h["verdict"] == v).sum()) for v in FAILURES if v in summary.columns}
            for key, n in counts.items():
                if int(row[key]) != n:
                    own.fail("summary", f"tier {tier}, {preset}: {key} {int(row[key])}, but results.csv has {n}")
            shift = float(row["shift_s"])
            if not (math.isfinite(shift) and shift >= 0):
                own.fail("summary", f"tier {tier}, {preset}: shift {row['shift_s']!r} is not a number >= 0")
                continue
            sgm[str(preset)] = _sgm(times[(g["preset"] == preset).to_numpy()], shift)
            if not _close(float(row["sgm_s"]), sgm[str(preset)]):
                own.fail(
                    "summary",
                    f"tier {tier}, {preset}: shifted geometric mean {row['sgm_s']} s, recomputed "
                    f"{sgm[str(preset)]:.6g} s",
                )
            spread = _spread(h)
            if not _close(float(row["repeat_spread"]), spread):
                own.fail("summary", f"tier {tier}, {preset}: repeat spread {row['repeat_spread']}, recomputed {spread}")
        finite = [v for v in sgm.values() if math.isfinite(v)]
        best = min(finite) if finite else float("nan")
        for preset, v in sgm.items():
            ratio = v / best if finite and best > 0 else float("nan")
            got = float(rows[(str(tier), preset)]["sgm_ratio"])
            if not _close(got, ratio):
                own.fail("summary", f"tier {tier}, {preset}: ratio to the best {got}, recomputed {ratio:.6g}")


def _spread(rows: pd.DataFrame) -> float:
    many = rows[(rows["repeats"] > 1) & (rows["verdict"] == "optimal")]
    if many.empty:
        return float("nan")
    rel = (many["total_s_max"] - many["total_s_min"]) / np.maximum(many["total_s_median"], FLOOR_S)
    return float(np.median(rel.to_numpy()))


def _check_profile(table: pd.DataFrame, profile: pd.DataFrame, own: RunCheck) -> None:
    models = sorted(set(table["model"]))
    presets = sorted(set(table["preset"]))
    solved = table[table["verdict"] == "optimal"]
    best = np.maximum(solved.groupby("model")["total_s"].min(), FLOOR_S)
    ratio = {
        p: {
            str(r["model"]): max(float(r["total_s"]), FLOOR_S) / float(best[r["model"]])
            for _, r in solved[solved["preset"] == p].iterrows()
        }
        for p in presets
    }
    own.checked["profile"] = len(profile)
    if sorted(set(profile["preset"].astype(str))) != presets and len(profile):
        own.fail("profile", "profile.csv's presets are not the benchmarked ones")
        return
    taus = sorted({1.0, *(v for d in ratio.values() for v in d.values())})
    if len(profile) != len(presets) * len(taus) and models:
        own.fail("profile", f"profile.csv has {len(profile)} points, expected {len(presets)} presets x {len(taus)}")
    for _, r in profile.iterrows():
        p, tau = str(r["preset"]), float(r["tau"])
        share = sum(v <= tau for v in ratio.get(p, {}).values()) / len(models) if models else 0.0
        if not _close(float(r["fraction"]), share):
            own.fail("profile", f"{p} at tau {tau:.6g}: fraction {r['fraction']}, recomputed {share:.6g}")


def _check_report(path: Path, summary: pd.DataFrame, own: RunCheck) -> None:
    if not path.is_file():
        raise ResultsError(f"bench folder file {str(path)!r} is missing")
    text = path.read_text(encoding="utf-8", errors="replace")
    own.checked["report"] = len(summary)
    for _, r in summary.iterrows():
        solved = f"{int(r['solved'])} / {int(r['instances'])}"
        row = f"| {r['tier']} | {r['preset']} | {solved} |"
        if not any(line.startswith(row) for line in text.splitlines()):
            own.fail("report", f"report.md does not show tier {r['tier']}, {r['preset']} solving {solved}")
