"""``rpbench evaluate``: a protocol's (day, seed) comparisons, in parallel, then its leaderboard.

An evaluation folder holds one ordinary results folder per (day, seed) — each written whole or not at all,
and checkable with ``rpbench check`` — plus ``units.csv`` (day, seed, run, kpi, value: every child's
KPIs), ``leaderboard.csv`` and ``paired.csv`` (:mod:`rpbench.report.leaderboard`), report.md and
report.html.  A second invocation on the same folder runs only the children that are missing (an
interrupted evaluation resumes), and refuses a folder of another protocol or of another decision budget
(every unit's ``rounds_over_budget`` counts against the same one).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rpbench import results
from rpbench.exceptions import ParameterError, ResultsError, out_named
from rpbench.harness.comparison import ComparisonTask, checked_presets, run_task
from rpbench.harness.outcome import Outcome
from rpbench.harness.parallel import run_tasks
from rpbench.protocols import Protocol
from rpbench.report.evaluation import unit_name, write_evaluation_report, write_evaluation_tables
from rpbench.report.html import write_html
from rpbench.results import layout
from rpbench.results.folder import write_parent_meta
from rpbench.results.store import DEFAULT_PARENT, remove_stale_partials
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import DEFAULT_FIGURE_FORMATS, RunSpec


def units_of(protocol: Protocol, request: ScenarioRequest) -> list[tuple[str | None, int]]:
    """The protocol's (day, seed) units: its dates (a dated scenario) times its seeds."""
    try:
        dates: list[str | None] = list(request.dates(protocol.dates)) if protocol.dates else [None]
    except ParameterError as exc:
        raise ParameterError(f"protocol {protocol.name!r}: {str(exc).removeprefix('--')}") from None
    return [(d, s) for d in dates for s in protocol.seeds]


def run_evaluation(
    protocol: Protocol,
    out: str | os.PathLike | None = None,
    *,
    data_dir: str | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    command: str | None = None,
    decision_budget_s: float | None = None,
    progress: bool | None = None,
    formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
) -> Outcome:
    """Run (or resume) ``protocol`` into ``out``; returns the folder's outcome (its table: the leaderboard; its
    children: the units, those found already written with ``fresh`` false).

    ``decision_budget_s``: flag the rounds slower than it in every unit (the simulation is unchanged);
    ``progress``: a bar over the units (default: when stderr is a terminal); ``formats``: the figures' formats
    (:func:`rpbench.spec.figure_formats`)."""
    request = ScenarioRequest(protocol.scenario, sample=protocol.sample, data_dir=data_dir).resolved()
    spec = RunSpec.of(
        request, list(protocol.strategies), preset=protocol.preset, oracle_preset=protocol.oracle_preset,
        command=command, decision_budget_s=decision_budget_s, formats=formats,
    )  # fmt: skip
    checked_presets(spec)  # an unknown or unable preset fails before the folder exists
    units = units_of(protocol, request)
    names = [unit_name(d, s) for d, s in units]
    folder = Path(out) if out is not None else Path.cwd() / DEFAULT_PARENT / f"evaluate-{protocol.name}"
    record = protocol.record()
    if folder.exists():
        _check_resumable(folder, record, decision_budget_s)
        # Units whose writer died (SIGKILL, power loss) left .UNIT.partial-PID folders: a dead PID's are swept
        # however young, since only a process running this evaluation writes here.
        remove_stale_partials(folder, older_than_s=0)
    else:
        try:
            folder.mkdir(parents=True)
        except OSError as exc:
            raise ResultsError(f"cannot create evaluation folder {str(folder)!r}: {exc.strerror or exc}") from None
        fields: dict[str, Any] = {"protocol": record, "strategies": spec.names, "command": command}
        if decision_budget_s is not None:
            fields["decision_budget_s"] = decision_budget_s
        write_parent_meta(folder, "evaluate", names, fields)
    tasks = [
        ComparisonTask(spec.for_request(request.replace(date=d, seed=s)), str(folder / name))
        for (d, s), name in zip(units, names, strict=True)
    ]
    todo = [task for task in tasks if not (Path(task.out) / layout.KPIS).is_file()]
    try:
        ran = run_tasks(
            run_task, todo, workers=workers, scheduler=scheduler, label=f"evaluate {protocol.name}", progress=progress
        )
    except BaseException:
        # Interrupted or failed: the units written stay (a rerun resumes); those the stopped workers were
        # writing are removed, so the folder holds only whole units.
        remove_stale_partials(folder, older_than_s=0)
        raise
    fresh = {Path(o.folder).name: o for o in ran}
    children = tuple(fresh.get(name) or Outcome.read(folder / name) for name in names)
    board = write_evaluation_tables(folder)
    write_evaluation_report(folder, folder.name, formats=spec.formats)
    write_html(folder, folder.name)
    return Outcome(folder, board, children=children)


def _check_resumable(folder: Path, record: dict, decision_budget_s: float | None) -> None:
    if not folder.is_dir() or not (folder / layout.META).is_file():
        raise ParameterError(f"{out_named(folder)} exists and is not an evaluation folder to resume")
    meta = results.read_meta(folder)
    if meta.get("kind") != "evaluate" or not isinstance(meta.get("protocol"), dict):
        raise ParameterError(f"{out_named(folder)} exists and is not an evaluation folder to resume")
    theirs = meta["protocol"]
    if theirs.get("digest") != record["digest"]:
        raise ParameterError(
            f"{out_named(folder)} holds protocol {theirs.get('name')!r} version {theirs.get('version')} "
            f"(digest {theirs.get('digest')}), not {record['name']!r} version {record['version']} "
            f"(digest {record['digest']}): choose another folder"
        )
    theirs_budget = meta.get("decision_budget_s")
    if theirs_budget != decision_budget_s:
        raise ParameterError(
            f"{out_named(folder)} was evaluated with {_budget_text(theirs_budget)}, not "
            f"{_budget_text(decision_budget_s)}: resume it with the same --decision-budget, or choose another folder"
        )


def _budget_text(budget: object) -> str:
    return "no decision budget" if budget is None else f"a decision budget of {budget} s"
