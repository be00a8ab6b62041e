"""Parameter sweeps in the layout of the paper's Tables 3-6, run in parallel.

A sweep is a list of points, each a set of parameter overrides; every point
is an ordinary comparison (one results folder) of the sweep's strategies
on the same scenario.  The paper's sweeps are predefined:

* ``patience`` (Table 3): mean patience K in {60, ..., 600} s — the
  passengers' K_p ~ N(K, 10 s) and the planner's K̄ both follow K;
* ``response-rate`` (Table 4): FL's presumed response rate r_w in {0.1, ..., 0.9};
* ``interval`` (Table 5): batch interval Δt in {2, 10, 30, 60} s;
* ``ratio`` (Table 6): order-driver ratio 100:10 and 100:25.

``--over NAME=V1,V2,...`` sweeps any parameter of
:class:`~rpbench.scenarios.base.Params` (or the aliases K, dt, r_w, ratio).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from rpbench import files, results
from rpbench.data import paper
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import ComparisonTask, run_task
from rpbench.harness.outcome import Outcome
from rpbench.harness.parallel import run_tasks
from rpbench.report.comparison import fmt
from rpbench.report.html import write_html
from rpbench.report.plots import sweep_figure
from rpbench.report.tables import booktabs, latex_escape
from rpbench.results import layout
from rpbench.results.folder import write_parent_meta
from rpbench.results.metrics import KPI_LABELS
from rpbench.results.parents import sweep_table
from rpbench.results.runs import markdown_cell, run_label, run_styles
from rpbench.results.store import check_new_folder
from rpbench.scenarios import ScenarioRequest
from rpbench.scenarios.base import Params
from rpbench.spec import DEFAULT_FIGURE_FORMATS, RunSpec

ALIASES = {
    "K": ("patience_mean_s", "planner_patience_s"),
    "dt": ("dt_s",),
    "r_w": ("response_rate",),
    "ratio": ("vehicles_per_100_orders",),
}


@dataclass(frozen=True)
class SweepSpec:
    name: str
    parameter: str  # display name (an alias or a Params field)
    values: tuple[float, ...]
    strategies: tuple[str, ...]
    kpis: tuple[str, ...]
    paper_table: dict | None = None


SWEEPS: dict[str, SweepSpec] = {
    s.name: s
    for s in [
        SweepSpec(
            "patience",
            "K",
            (60, 90, 120, 180, 240, 300, 400, 500, 600),
            ("mb", "rtv", "fl"),
            ("avg_detour_m", "total_saving_km", "avg_response_time_s", "response_rate", "pairing_ratio"),
            paper.TABLE3_K,
        ),
        SweepSpec(
            "response-rate",
            "r_w",
            (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9),
            ("fl",),
            (
                "avg_shared_m",
                "avg_detour_m",
                "total_saving_km",
                "avg_response_time_s",
                "response_rate",
                "pairing_ratio",
            ),
            {k: {"fl": v} for k, v in paper.TABLE4_RW.items()},
        ),
        SweepSpec(
            "interval",
            "dt",
            (2, 10, 30, 60),
            ("mb", "rtv", "fl"),
            ("avg_detour_m", "total_saving_km", "avg_response_time_s", "response_rate", "pairing_ratio"),
            paper.TABLE5_DT,
        ),
        SweepSpec(
            "ratio",
            "ratio",
            (10, 25),
            ("mb", "rtv", "fl"),
            (
                "avg_detour_m",
                "total_saving_km",
                "avg_response_time_s",
                "platform_profit_cny",
                "response_rate",
                "pairing_ratio",
            ),
            paper.TABLE6_RATIO,
        ),
    ]
}


@dataclass(frozen=True)
class SweepPoint:
    label: str  # folder name, e.g. "K=90"
    value: float
    overrides: dict[str, float] = field(default_factory=dict)  # scenario parameters
    options: dict[str, dict[str, float]] = field(default_factory=dict)  # run name -> its options at this point

    def refuse_overrides(self, overrides: Mapping[str, float]) -> None:
        """One error line when ``overrides`` (``--param dt_s=5``) set a parameter this point sets (``--over
        dt=...``): the point's value would silently win."""
        both = sorted(set(overrides) & set(self.overrides))
        if both:
            swept = self.label.rpartition("=")[0]
            raise ParameterError(
                f"--param {both[0]} conflicts with the sweep over {swept}, which sets it at every point; drop one"
            )

    def spec_of(self, spec: RunSpec, request: ScenarioRequest) -> RunSpec:
        """The point's comparison: ``spec`` on ``request`` with the point's parameters and run options.

        A parameter the request overrides already is an error (:meth:`refuse_overrides`)."""
        self.refuse_overrides(request.overrides)
        point = spec.for_request(request.with_overrides(self.overrides))
        for run, values in self.options.items():
            point = point.with_options(run, values)
        return point


def option_target(parameter: str, runs: Sequence[str]) -> tuple[str, str] | None:
    """``RUN.OPTION`` -> (RUN, OPTION) when the sweep parameter names a run's option (the longest run name
    followed by a dot), else None: a scenario parameter."""
    for run in sorted(runs, key=len, reverse=True):
        if parameter.startswith(f"{run}.") and len(parameter) > len(run) + 1:
            return run, parameter[len(run) + 1 :]
    return None


def parameter_fields(parameter: str) -> tuple[str, ...]:
    """The Params fields a sweep parameter sets (aliases expand; unknown names are an error)."""
    if parameter in ALIASES:
        return ALIASES[parameter]
    known = set(Params().as_dict())
    if parameter not in known:
        raise ParameterError(
            f"unknown sweep parameter {parameter!r}; use one of {', '.join(ALIASES)} or a "
            f"parameter name ({', '.join(sorted(known))})"
        )
    return (parameter,)


def expand(parameter: str, values: list[float] | tuple[float, ...], runs: Sequence[str] = ()) -> list[SweepPoint]:
    """One point per value: every field a scenario parameter sets, validated against Params; or, for
    ``RUN.OPTION`` with RUN one of ``runs`` (``fl.tau0_s``), that run's option (checked per point when the
    point's specification is built, before anything runs)."""
    target = option_target(parameter, runs)
    fields = () if target else parameter_fields(parameter)
    if not values:
        raise ParameterError(f"sweep over {parameter!r} has no values")
    points = []
    for v in values:
        label = f"{parameter}={v:g}"
        if target:
            # a whole number stays an int, so an integer option (msa.samples) can be swept; a float option
            # takes the int as its float
            option_value = int(v) if float(v).is_integer() else float(v)
            points.append(SweepPoint(label=label, value=float(v), options={target[0]: {target[1]: option_value}}))
            continue
        overrides = {f: float(v) for f in fields}
        Params().replace(**overrides)  # fail early on out-of-range values
        points.append(SweepPoint(label=label, value=float(v), overrides=overrides))
    if len({p.label for p in points}) != len(points):
        raise ParameterError(f"sweep over {parameter!r} repeats a value")
    return points


def parse_over(text: str) -> tuple[str, list[float]]:
    """``NAME=V1,V2,...`` -> (NAME, values)."""
    name, sep, rest = text.partition("=")
    if not sep or not rest.strip():
        raise ParameterError(f"--over {text!r}: expected NAME=V1,V2,... e.g. dt=2,10,30")
    items = [x.strip() for x in rest.split(",")]
    if "" in items:
        raise ParameterError(f"--over {text!r}: an empty value between commas; give NAME=V1,V2,...")
    try:
        values = [float(x) for x in items]
    except ValueError:
        raise ParameterError(f"--over {text!r}: values must be numbers") from None
    twice = sorted({v for v in values if values.count(v) > 1})
    if twice:
        raise ParameterError(f"--over {text!r}: {twice[0]:g} appears twice; each point once")
    return name.strip(), values


def run_sweep(
    sweep: SweepSpec,
    points: list[SweepPoint],
    spec: RunSpec,
    out: str | None = None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | None = None,
) -> Outcome:
    """One comparison of ``spec`` per point (its request with the point's overrides), in parallel, then the
    sweep table and report; returns the folder's outcome (its table: the sweep table, tidy point, run, kpi,
    value; its children: the points).  The data folder is resolved once, here, for every worker.  ``progress``: a
    bar over the points (default: when stderr is a terminal)."""
    check_new_folder(out)
    request = spec.request.resolved()
    default = f"{results.timestamp()}_sweep-{sweep.name}_{request.name}_{spec.preset}"
    with results.new_results_folder(out, default) as (tmp, final):
        tasks = [ComparisonTask(p.spec_of(spec, request), str(tmp / p.label)) for p in points]
        done = run_tasks(
            run_task, tasks, workers=workers, scheduler=scheduler, label=f"sweep {sweep.name}", progress=progress
        )
        write_parent_meta(
            tmp,
            "sweep",
            [p.label for p in points],
            {
                "sweep": sweep.name,
                "parameter": sweep.parameter,
                "points": [
                    {"label": p.label, "value": p.value, "overrides": p.overrides, "options": p.options} for p in points
                ],
                "strategies": spec.names,
                "kpis": list(sweep.kpis),
                "scenario": request.name,
                "scenario_args": request.meta(),
                "preset": spec.preset,
                "command": spec.command,
                **({"decision_budget_s": spec.decision_budget_s} if spec.decision_budget_s is not None else {}),
            },
        )
        table = sweep_table(tmp)
        table.to_csv(tmp / layout.SWEEP, index=False)
        write_sweep_report(tmp, name=final.name, formats=spec.formats)
        write_html(tmp, name=final.name)
    return Outcome(tmp, table, children=tuple(done)).moved_to(final)


def write_sweep_report(parent: Path, name: str | None = None, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS) -> Path:
    """``report.md`` of a sweep folder in the layout of the paper's Tables 3-6, with plots (in ``formats``)."""
    meta = results.read_meta(parent)
    table = sweep_table(parent)
    spec = SWEEPS.get(meta["sweep"])
    kpis = meta["kpis"]
    runs = meta["strategies"]
    args = meta.get("scenario_args", {})
    paper_table = (spec.paper_table if spec is not None else None) or {}
    with_paper = bool(paper_table) and paper.table2_applies(meta["scenario"], args.get("date"), args.get("sample"))
    lines = [
        f"# rpbench sweep `{meta['sweep']}` over {meta['parameter']}",
        "",
        f"- scenario `{meta['scenario']}` ({', '.join(f'{k}={v}' for k, v in args.items() if v is not None)}), "
        f"solver preset `{meta['preset']}`",
        f"- rpbench {meta['versions']['rpbench']}, commit `{meta.get('git_commit')}`",
        "",
    ]
    if meta.get("command"):
        lines += ["Command:", "", f"    {meta['command']}", ""]
    if with_paper:
        lines += ["Each cell: rpbench (paper). The paper's values are shown for comparison only.", ""]
    styles = run_styles(results.read_meta(parent / meta["points"][0]["label"])) if meta["points"] else {}
    head = [meta["parameter"]] + [
        f"{KPI_LABELS.get(k, k).split(' (')[0]} {run_label(r, styles)}" for k in kpis for r in runs
    ]
    lines += ["| " + " | ".join(map(markdown_cell, head)) + " |", "|---|" + "---:|" * (len(head) - 1)]
    body = []
    for p in meta["points"]:
        sel = table[table["label"] == p["label"]].set_index(["kpi", "run"])["value"]
        cells = [f"{p['value']:g}"]
        for k in kpis:
            for r in runs:
                cell = fmt(k, sel.get((k, r), float("nan")))
                if with_paper:
                    ref = paper_table.get(_paper_key(p["value"]), {}).get(r, {}).get(k, float("nan"))
                    cell += f" ({fmt(k, ref)})"
                cells.append(cell)
        body.append(cells)
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    caption = f"rpbench sweep {meta['sweep']} over {meta['parameter']}" + (" (paper in brackets)" if with_paper else "")
    latex = [[latex_escape(cell) for cell in row] for row in [head, *body]]
    (parent / layout.TABLE_TEX).write_text(booktabs(latex[0], latex[1:], caption=caption, what="the sweep table"))
    plot = sweep_figure(
        table[table["run"].isin(runs)],
        meta["parameter"],
        kpis,
        parent / "sweep.png",
        f"sweep {meta['sweep']}",
        styles,
        formats=formats,
    )
    lines += [
        f"![sweep]({plot.name})",
        "",
        "Each point is an ordinary results folder: `rpbench check PATH/<point>`, PATH being the path to "
        f"`{name or parent.name}`, the folder holding this report.",
        "",
    ]
    path = parent / "report.md"
    files.write_text(path, "\n".join(lines))
    return path


def _paper_key(value: float):
    return int(value) if float(value).is_integer() else value
