"""One comparison: a :class:`~rpbench.spec.RunSpec` -> one results folder.

:func:`run_comparison` walks the same steps every time: check the presets,
calibrate and simulate each strategy (:func:`simulate_strategy`: the event
log's KPIs by :mod:`rpbench.results.metrics`), solve the offline runs on the
scenario's orders (:func:`solve_offline`), gather the KPI table, write the
folder (:mod:`rpbench.results.folder`) and its report.  Everything
strategy-specific (options, calibration, labels) is read off the strategy
classes and the offline runs (:data:`rpbench.oracle.runs.ORACLE_RUNS`).
"""

from __future__ import annotations

import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.backends import Preset, load_preset
from rpbench.harness import sidecar
from rpbench.harness.outcome import Outcome
from rpbench.harness.strict import require_proven
from rpbench.harness.training import supply_model
from rpbench.model import Structure
from rpbench.oracle import find_candidates, solve_oracle
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.oracle.solve import OracleResult
from rpbench.report import plots
from rpbench.report.comparison import draw_kpi_figure, write_report
from rpbench.report.html import write_html
from rpbench.results import metrics
from rpbench.results.folder import StrategyRun, oracle_kpis, rounds_table, write_folder
from rpbench.results.ratios import with_ratios
from rpbench.results.read import over_budget_in, unproven_in
from rpbench.results.runs import run_label
from rpbench.results.store import check_new_folder, new_results_folder, timestamp
from rpbench.scenarios.base import Scenario
from rpbench.sim.simulator import Capture, SimResult, Simulator
from rpbench.spec import RunEntry, RunSpec, resolve_runs


def run_comparison(
    spec: RunSpec, out: str | Path | None = None, *, scenario: Scenario | None = None, progress: bool | None = None
) -> Outcome:
    """Run every strategy and offline run of ``spec`` and write one new results folder (``out``, or
    ``./rpbench-runs/<stamp>_<scenario>_<preset>``); returns its :class:`~rpbench.harness.outcome.Outcome`
    (the folder, the KPI table, the unproven runs and the runs over the decision budget).

    ``scenario`` is the scenario ``spec.request`` builds (pass it when it is built already);
    ``progress``: a progress bar per strategy (default: when stderr is a terminal).  With
    ``spec.strict``, any round or offline run the solver did not prove optimal is an error, before
    anything is written.  With ``spec.decision_budget_s``, the rounds slower than it are flagged
    (:func:`with_decision_budget`).
    """
    check_new_folder(out)  # a bad --out must fail now, not after the whole simulation
    preset, oracle_preset = checked_presets(spec)
    scenario = scenario if scenario is not None else spec.request.build()
    built = scenario
    # The offline runs, the independent runs the parent has not reached and report.md in a second process,
    # beside the simulations and report.html.
    side = sidecar.start(
        lambda: solve_offline(built, spec.offline, oracle_preset),
        lambda folder, name: write_report(folder, name=name, formats=spec.formats, kpis_drawn=True),
        lambda folder, name: draw_kpi_figure(folder, folder, spec.formats),
        warm_up=plots.warm_up,
        simulate=lambda i: simulate_strategy(built, spec.simulated[i], preset, progress=False, strict=spec.strict),
        runs=len(spec.simulated),
        movable=independent_runs(spec),
    )
    try:
        runs = simulate_all(spec, scenario, preset, progress, side=side)
        offline = side.offline()
        for name, result in offline.items():
            require_proven(
                f"{run_label(name)} (solver preset {result.solver!r})", result.solution.status.value, strict=spec.strict
            )
        table = kpi_table(runs, offline, spec.names)
        with new_results_folder(out, f"{timestamp()}_{scenario.name}_{preset.name}") as (folder, final):
            meta = write_folder(folder, spec, scenario, runs, offline, preset)
            side.report(folder, final.name)
            write_html(folder, name=final.name)
            side.wait()
    finally:
        side.close()
    rounds = rounds_table(runs)
    return Outcome(
        final,
        table,
        unproven=unproven_in(rounds, meta["runs"], spec.names),
        over_budget=over_budget_in(rounds, spec.decision_budget_s),
    )


def checked_presets(spec: RunSpec) -> tuple[Preset, Preset]:
    """The comparison's solver presets, loaded, each able to solve the models its runs build (an unknown or
    unable preset is one error line, before anything runs or is written)."""
    preset = load_preset(spec.preset)
    oracle_preset = load_preset(spec.oracle_preset) if spec.oracle_preset else preset
    for entry in spec.simulated:
        preset.require(entry.strategy_class().structure, needed_by=f"strategy {entry.name!r}")
    if spec.offline:
        oracle_preset.require(Structure.PAIRING, needed_by="the offline runs")
    return preset, oracle_preset


@dataclass(frozen=True)
class ComparisonTask:
    """One comparison for a worker process: a day of a multi-day run, a point of a sweep (picklable)."""

    spec: RunSpec
    out: str


def run_task(task: ComparisonTask) -> Outcome:
    """Worker entry point: ``task``'s comparison written to ``task.out``; returns its outcome."""
    return run_comparison(task.spec, task.out, progress=False)


def simulate_all(
    spec: RunSpec, scenario: Scenario, preset: Preset, progress: bool | None, *, side: sidecar.Serial | None = None
) -> list[StrategyRun]:
    """Every simulated run of ``spec``, in order, each calibrated first where its strategy asks for it.

    A calibration run uses the calibrating strategy's default options and is shared with the
    comparison's own column of it (runs are deterministic: once or twice gives the same numbers).  With a
    second process (``side``), the runs it took (:func:`independent_runs`) come from it.
    """
    side = side if side is not None else sidecar.Serial(dict, lambda folder, name: None)
    done: dict[str, StrategyRun] = {}  # by strategy source: calibration runs and default-option columns
    by_index: dict[int, StrategyRun] = {}
    for index, entry in enumerate(spec.simulated):
        if not side.claim(index):
            continue
        entry = calibrated(entry, scenario, preset, done, progress, strict=spec.strict)
        reuse = done.get(entry.source)
        run = reuse if reuse is not None and reuse.options == entry.options else None
        if run is None:
            run = simulate_strategy(scenario, entry, preset, progress=progress, strict=spec.strict)
        if run.name != entry.name:
            run = dataclasses.replace(run, name=entry.name)
        done.setdefault(entry.source, run)
        by_index[index] = run
    by_index.update(side.simulated())
    runs = [by_index[index] for index in range(len(spec.simulated))]
    if spec.decision_budget_s is not None:
        runs = [with_decision_budget(run, spec.decision_budget_s) for run in runs]
    return runs


def independent_runs(spec: RunSpec) -> list[int]:
    """The simulated runs of ``spec`` that need nothing from another run, by index: no calibration to wait
    for, no other run calibrated by their strategy, and no twin (the same strategy and options) whose
    simulation the parent would share."""
    entries = spec.simulated
    waits = []  # per run: the source of the strategy that calibrates it, or None
    for entry in entries:
        cls = entry.strategy_class()
        by = cls.calibrated_by
        waits.append(resolve_runs([by])[0].source if by is not None and cls.needs_calibration(entry.options) else None)
    references = {source for source in waits if source is not None}
    twins = [(e.source, e.options) for e in entries]
    return [
        index
        for index, entry in enumerate(entries)
        if waits[index] is None and entry.source not in references and twins.count((entry.source, entry.options)) == 1
    ]


def with_decision_budget(run: StrategyRun, budget_s: float) -> StrategyRun:
    """``run`` with its rounds slower than ``budget_s`` flagged: the ``over_budget`` column of its rounds and
    the KPI :data:`~rpbench.results.metrics.BUDGET_KPI` (read off the recorded rounds: nothing is re-run)."""
    flags = metrics.over_budget(run.sim.rounds, budget_s)
    sim = dataclasses.replace(run.sim, rounds=run.sim.rounds.assign(over_budget=flags))
    return dataclasses.replace(run, sim=sim, kpis={**run.kpis, metrics.BUDGET_KPI: float(flags.sum())})


def calibrated(
    entry: RunEntry,
    scenario: Scenario,
    preset: Preset,
    done: dict[str, StrategyRun],
    progress: bool | None,
    *,
    strict: bool = False,
) -> RunEntry:
    """``entry`` with its options completed from a run of its strategy's ``calibrated_by`` strategy on the same
    scenario (``done``: runs already made, by strategy source; the calibration run is added to it)."""
    cls = entry.strategy_class()
    if cls.calibrated_by is None or not cls.needs_calibration(entry.options):
        return entry
    (reference,) = resolve_runs([cls.calibrated_by])  # its default options
    ref = done.get(reference.source)
    if ref is None or ref.options != reference.options:
        ref = simulate_strategy(scenario, reference, preset, progress=progress, strict=strict)
        done[reference.source] = ref
    hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
    return dataclasses.replace(entry, options=cls.calibrate(entry.options, ref.kpis, ref.hourly, hours))


def simulate_strategy(
    scenario: Scenario,
    entry: RunEntry | str,
    preset: Preset,
    *,
    progress: bool | None = None,
    canonical_ties: bool = True,
    capture: Capture | None = None,
    strict: bool = False,
) -> StrategyRun:
    """Simulate one strategy run and compute its KPIs from the event log (``entry``: a run entry, or a
    built-in strategy name with its default options; ``strict``: an unproven round is an error)."""
    if isinstance(entry, str):
        (entry,) = resolve_runs([entry])
    cls = entry.strategy_class()
    strategy = cls(entry.options)
    preset.require(strategy.structure, needed_by=f"strategy {entry.name!r}")
    supply_model(strategy, scenario, progress=progress)
    bar = progress_bar(scenario, entry.name, progress)
    try:
        sim = Simulator(
            scenario, strategy, preset, canonical_ties=canonical_ties, progress=bar, capture=capture, strict=strict
        ).run()
    finally:
        if bar is not None:
            bar.close()
    return evaluate_run(scenario, sim, entry, label=entry.label_of(cls.label), color=entry.color_of(cls.color))


def evaluate_run(scenario: Scenario, sim: SimResult, entry: RunEntry, *, label: str, color: str | None) -> StrategyRun:
    """A simulation's KPIs (the paper's Table 2 rows) from its event log and odometers."""
    orders = scenario.orders
    solo = scenario.network.distances()(orders.origin, orders.destination)
    tab = metrics.passenger_table(sim.events, solo, orders.request_s, sim.trajectories)
    occupied = metrics.occupied_distance_m(sim.events, sim.trajectories)
    kpis = metrics.kpis(tab, occupied, scenario.params)
    kpis.update(metrics.decision_kpis(sim.rounds, scenario.params.dt_s))
    kpis["wall_s"] = sim.wall_s
    return StrategyRun(
        name=entry.name,
        sim=sim,
        passengers=tab,
        kpis=kpis,
        hourly=metrics.hourly(tab),
        options=entry.options,
        source=entry.source,
        label=label,
        color=color,
    )


def solve_offline(scenario: Scenario, entries: list[RunEntry], preset: Preset) -> dict[str, OracleResult]:
    """The offline runs over the scenario's orders, sharing one candidate enumeration where the rules agree."""
    out = {}
    candidates: dict = {}
    for entry in entries:
        run = ORACLE_RUNS[entry.name]
        rules = run.rules(scenario.params, entry.options)
        if rules not in candidates:
            candidates[rules] = find_candidates(scenario.network.distances(), scenario.orders, rules)
        out[entry.name] = solve_oracle(scenario, run.variant, preset, candidates=candidates[rules])
    return out


def kpi_table(runs: list[StrategyRun], offline: dict[str, OracleResult], order: list[str]) -> pd.DataFrame:
    """Wide table: KPI rows x run columns (in ``order``), with the ratio and bracket rows
    (:mod:`rpbench.results.ratios`)."""
    cols = {r.name: r.kpis for r in runs}
    for name, result in offline.items():
        cols[name] = oracle_kpis(result)
    return with_ratios(pd.DataFrame({name: cols[name] for name in order if name in cols}), [r.name for r in runs])


def progress_bar(scenario: Scenario, label: str, enabled: bool | None):
    """A tqdm bar over simulated seconds on stderr (off when stderr is not a terminal)."""
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(
        total=scenario.horizon_s,
        desc=f"{label:>6}",
        unit="sim s",
        leave=False,
        file=sys.stderr,
        bar_format="{desc} {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}]",
    )
