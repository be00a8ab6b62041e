"""Scenario x strategies x preset -> one results folder.

:func:`simulate_strategy` runs one strategy and derives its KPIs from the
event log (:mod:`rpbench.results.metrics`); :func:`run_comparison` runs several on
the same scenario and writes a results folder (:mod:`rpbench.results.store`)
with a report.  The offline oracles join the comparison as runs
(:data:`rpbench.oracle.runs.ORACLE_RUNS`).  Everything strategy-specific
(options, calibration, labels) is read off the strategy classes.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.backends import Preset, load_preset
from rpbench.exceptions import ParameterError
from rpbench.harness.strict import is_strict, require_proven
from rpbench.oracle import find_candidates, solve_oracle
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.plugins import is_spec
from rpbench.results import metrics
from rpbench.results.check import inputs_digest
from rpbench.results.report import with_competitive_ratios, write_report
from rpbench.results.runs import run_label
from rpbench.results.store import check_new_folder
from rpbench.scenarios import ScenarioRequest
from rpbench.scenarios.base import Scenario
from rpbench.sim.simulator import SimResult, Simulator
from rpbench.strategies import REGISTRY as STRATEGY_REGISTRY
from rpbench.strategies import plugin_names, strategy_class
from rpbench.strategies.options import RunOptions


@dataclass
class StrategyRun:
    """One strategy's simulation with its KPIs."""

    name: str
    sim: SimResult
    passengers: pd.DataFrame
    kpis: dict[str, float]
    hourly: pd.DataFrame
    options: RunOptions = field(default_factory=RunOptions)


def parse_strategies(text: str | list[str]) -> list[str]:
    """Run names from ``--strategies`` (strategies and oracles), checked and in order.

    Built-in and entry-point names are case-insensitive (lower-cased here);
    a ``module:Class`` spec keeps its case (Python names are case-sensitive)
    and is the run's name as typed, e.g. its folder ``runs/mypkg.rules:Greedy/``.
    Oracle runs take precedence over plug-ins of the same name.  Plug-in
    classes are resolved here, so an import error is reported before any run.
    """
    items = text.split(",") if isinstance(text, str) else text
    names = [s.strip() if is_spec(s) else s.strip().lower() for s in items if s.strip()]
    if not names:
        raise ParameterError(f"unknown strategy '(none)'; choose from {', '.join(known_runs())}")
    for name in names:
        if name in ORACLE_RUNS or name in STRATEGY_REGISTRY:
            continue
        if not is_spec(name) and name not in plugin_names():
            raise ParameterError(
                f"unknown strategy {name!r}; choose from {', '.join(known_runs())}, "
                "or give a strategy class as MODULE:CLASS (e.g. mypkg.rules:Greedy)"
            )
        strategy_class(name)
    if len(set(names)) != len(names):
        raise ParameterError(f"strategy list {','.join(names)} names a strategy twice")
    return names


def known_runs() -> list[str]:
    """Every run name ``--strategies`` accepts without a ``module:`` prefix (an oracle hides a plug-in's name)."""
    return [*STRATEGY_REGISTRY, *(n for n in plugin_names() if n not in ORACLE_RUNS), *ORACLE_RUNS]


def options_class(name: str) -> type[RunOptions]:
    """The declared options of a strategy or oracle run."""
    return ORACLE_RUNS[name].Options if name in ORACLE_RUNS else strategy_class(name).Options


def parse_run_options(items: list[str], names: list[str]) -> dict[str, RunOptions]:
    """``--opt RUN.NAME=VALUE`` items as typed options per run (every run of ``names`` gets its own).

    RUN is the longest run name of ``names`` that the key starts with,
    followed by a dot: run names may contain dots themselves
    (``--opt mypkg.rules:Greedy.threshold=3``).
    """
    raw: dict[str, dict[str, str]] = {name: {} for name in names}
    for item in items:
        key, sep, value = item.partition("=")
        name, option = split_option_key(key, names)
        if not sep or not name or not option.strip():
            raise ParameterError(f"--opt {item!r}: expected STRATEGY.KEY=VALUE, e.g. rtv.c_ko=large")
        if name not in raw:
            raise ParameterError(f"--opt {item!r}: strategy {name!r} is not in --strategies")
        raw[name][option.strip()] = value
    return {name: options_class(name).parse(name, values) for name, values in raw.items()}


def split_option_key(key: str, names: list[str]) -> tuple[str, str]:
    """``RUN.OPTION`` -> (RUN, OPTION): the longest of ``names`` followed by a dot, else a best guess for
    the error message (up to the first dot; after the colon for a ``module:Class`` spec); OPTION is ``""``
    when there is no dot."""
    for name in sorted(names, key=len, reverse=True):
        if key.startswith(f"{name}."):
            return name, key[len(name) + 1 :]
    colon = key.find(":")
    dot = key.find(".", colon + 1 if colon >= 0 else 0)
    return (key, "") if dot < 0 else (key[:dot], key[dot + 1 :])


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


def simulate_strategy(
    scenario: Scenario,
    name: str,
    preset: Preset,
    *,
    options: RunOptions | None = None,
    progress: bool | None = None,
    canonical_ties: bool = True,
    capture=None,
    strict: bool = False,
) -> StrategyRun:
    """Simulate one strategy and compute its KPIs from the event log (``strict``: an unproven round is an
    error, see :mod:`rpbench.harness.strict`)."""
    cls = strategy_class(name)
    options = options if options is not None else cls.Options()
    strategy = cls(options)
    backend = preset.backend_class()
    if strategy.structure not in backend.exact:
        raise ParameterError(
            f"solver preset {preset.name!r} (backend {preset.backend!r}) does not solve "
            f"{strategy.structure.value} models exactly, which strategy {name!r} needs; "
            "choose another --solver"
        )
    backend.ensure_installed()
    bar = progress_bar(scenario, name, progress)
    try:
        sim = Simulator(
            scenario, strategy, preset, canonical_ties=canonical_ties, progress=bar, capture=capture, strict=strict
        ).run()
    finally:
        if bar is not None:
            bar.close()
    return evaluate(scenario, sim, name, options)


def evaluate(scenario: Scenario, sim: SimResult, name: str, options: RunOptions) -> StrategyRun:
    orders = scenario.orders
    solo = scenario.network.distances()(orders.origin, orders.destination)
    tab = metrics.passenger_table(sim.events, solo, orders.request_s, sim.trajectories)
    occupied = metrics.occupied_distance_m(sim.events, sim.trajectories)
    kpis = metrics.kpis(tab, occupied, scenario.params)
    kpis["wall_s"] = sim.wall_s
    return StrategyRun(name=name, sim=sim, passengers=tab, kpis=kpis, hourly=metrics.hourly(tab), options=options)


def run_comparison(
    scenario: Scenario,
    strategies: list[str],
    preset_name: str,
    *,
    out: str | Path | None = None,
    run_options: dict[str, RunOptions | dict] | None = None,
    progress: bool | None = None,
    request: ScenarioRequest | None = None,
    command: str | None = None,
    oracle_solver: str | None = None,
    strict: bool | None = None,
) -> tuple[Path, pd.DataFrame]:
    """Run every strategy (and oracle) on ``scenario`` and write one results folder.

    ``run_options`` maps a run name to its options (parsed, or a dict of
    values); ``request`` is what the folder records as the scenario's
    arguments.  The oracles are solved with ``oracle_solver`` (a preset
    name), by default the comparison's own preset.  ``strict`` (default:
    the policy of :mod:`rpbench.harness.strict`) makes any round or oracle
    the solver did not prove optimal an error, before anything is written.
    """
    strict = is_strict() if strict is None else strict
    # A bad --out must fail now, not after the whole simulation.
    check_new_folder(out)
    preset = load_preset(preset_name)
    options = {name: _typed(name, (run_options or {}).get(name)) for name in strategies}
    runs: list[StrategyRun] = []
    done: dict[str, StrategyRun] = {}
    for name in strategies:
        if name in ORACLE_RUNS:
            continue
        run = done.get(name)
        if run is None or run.options != options[name]:
            run = simulate_strategy(
                scenario,
                name,
                preset,
                options=calibrated(scenario, name, options[name], preset, done, progress, strict=strict),
                progress=progress,
                strict=strict,
            )
        done[name] = run
        runs.append(run)
    wanted = [n for n in strategies if n in ORACLE_RUNS]
    oracle_results = {}
    if wanted:
        oracle_preset = load_preset(oracle_solver) if oracle_solver else preset
        oracle_results = solve_oracles(scenario, wanted, oracle_preset, options)
    for name, res in oracle_results.items():
        require_proven(f"{run_label(name)} (solver preset {res.solver!r})", res.solution.status.value, strict=strict)
    table = kpi_table(runs, oracle_results, strategies)
    default = f"{results.timestamp()}_{scenario.name}_{preset.name}"
    with results.new_results_folder(out, default) as (folder, final):
        write_folder(
            folder,
            scenario,
            runs,
            oracle_results,
            preset,
            strategies,
            request.meta() if request is not None else {},
            command,
        )
        write_report(folder, name=final.name)
    return final, table


def _typed(name: str, options: RunOptions | dict | None) -> RunOptions:
    if isinstance(options, RunOptions):
        return options
    return options_class(name).parse(name, options)


def calibrated(
    scenario: Scenario,
    name: str,
    options: RunOptions,
    preset: Preset,
    done: dict[str, StrategyRun],
    progress: bool | None,
    *,
    strict: bool = False,
) -> RunOptions:
    """``options`` completed from a run of the strategy's ``calibrated_by`` strategy on the same scenario.

    The calibration run uses that strategy's default options and is shared
    with the comparison's own column of it (runs are deterministic, so
    running it once or twice gives the same numbers).
    """
    cls = strategy_class(name)
    if cls.calibrated_by is None or not cls.needs_calibration(options):
        return options
    reference = cls.calibrated_by
    default = strategy_class(reference).Options()
    ref = done.get(reference)
    if ref is None or ref.options != default:
        ref = simulate_strategy(scenario, reference, preset, options=default, progress=progress, strict=strict)
        done[reference] = ref
    hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
    return cls.calibrate(options, ref.kpis, ref.hourly, hours)


def solve_oracles(scenario: Scenario, names: list[str], preset: Preset, options: dict[str, RunOptions]) -> dict:
    """The oracle runs over the scenario's orders, sharing one candidate enumeration when the rules agree."""
    out = {}
    cache: dict = {}
    for name in names:
        run = ORACLE_RUNS[name]
        rules = run.rules(scenario.params, options[name])
        if rules not in cache:
            cache[rules] = find_candidates(scenario.network.distances(), scenario.orders, rules)
        out[name] = solve_oracle(scenario, run.variant, preset, candidates=cache[rules])
    return out


def oracle_kpis(result) -> dict[str, float]:
    """The numeric KPIs of an oracle result (solver facts go to meta.json)."""
    return {
        k: float(v)
        for k, v in result.kpis().items()
        if isinstance(v, (int, float, np.number)) and not isinstance(v, bool) and k not in ("variant",)
    }


def kpi_table(runs: list[StrategyRun], oracle_results: dict, order: list[str]) -> pd.DataFrame:
    """Wide table: KPI rows x run columns (in the requested order), with the competitive ratio."""
    cols = {r.name: r.kpis for r in runs}
    for name, res in oracle_results.items():
        cols[name] = oracle_kpis(res)
    return with_competitive_ratios(pd.DataFrame({name: cols[name] for name in order if name in cols}))


def bound_by_hour(pairs: pd.DataFrame) -> pd.DataFrame:
    """The upper bound's matching split by the hour of each pair's earlier request (``hourly.csv`` rows of run
    ``bound``; only the saving column: per hour this is a description of the matching, not itself a bound)."""
    hour = (np.minimum(pairs["first_request_s"], pairs["second_request_s"]) // 3600).astype(int)
    saving = pairs["saving_m"].groupby(hour).sum() / 1000.0
    return pd.DataFrame({"hour": saving.index, "total_saving_km": saving.to_numpy(), "run": "bound"})


def write_folder(
    folder: Path,
    scenario: Scenario,
    runs: list[StrategyRun],
    oracle_results: dict,
    preset: Preset,
    strategies: list[str],
    scenario_args: dict[str, Any],
    command: str | None,
) -> None:
    orders = scenario.orders
    solo = scenario.network.distances()(orders.origin, orders.destination)
    pd.DataFrame(
        {
            "order_id": orders.order_id,
            "request_s": orders.request_s,
            "origin": orders.origin,
            "destination": orders.destination,
            "patience_s": orders.patience_s,
            "solo_m": solo,
        }
    ).to_csv(folder / "orders.csv.gz", index=False)
    results.save_network(folder / "network.npz", scenario.network)
    pd.DataFrame({"vehicle": np.arange(len(scenario.fleet)), "initial_node": scenario.fleet.initial_node}).to_csv(
        folder / "fleet.csv.gz", index=False
    )
    tidy, rounds, hourly = [], [], []
    meta_runs = {}
    for r in runs:
        d = folder / "runs" / r.name
        d.mkdir(parents=True)
        r.sim.events.to_csv(d / "events.csv.gz", index=False)
        results.save_trajectories(d / "trajectories.npz", r.sim.trajectories)
        tidy += [{"run": r.name, "kpi": k, "value": v} for k, v in r.kpis.items()]
        rounds.append(r.sim.rounds.assign(run=r.name))
        hourly.append(r.hourly.assign(run=r.name))
        meta_runs[r.name] = {
            "kind": "simulation",
            "options": r.options.as_dict(),
            "wall_s": r.sim.wall_s,
            "end_s": r.sim.end_s,
            "rounds_solved": len(r.sim.rounds),
        }
    bound = oracle_results.get("bound")
    if bound is not None:  # the competitive ratio of every strategy run (docs/bound.md)
        bound_km = oracle_kpis(bound)["total_saving_km"]
        tidy += [
            {
                "run": r.name,
                "kpi": "competitive_ratio_bound",
                "value": r.kpis["total_saving_km"] / bound_km if bound_km else float("nan"),
            }
            for r in runs
        ]
    for name, res in oracle_results.items():
        d = folder / "runs" / name
        d.mkdir(parents=True)
        res.pairs.to_csv(d / "pairs.csv.gz", index=False)
        tidy += [{"run": name, "kpi": k, "value": v} for k, v in oracle_kpis(res).items()]
        facts = res.kpis()
        meta_runs[name] = {
            "kind": "oracle",
            "variant": res.variant,
            "solver": res.solver,
            "status": facts["status"],
            "rules": dataclasses.asdict(res.rules),
            "objective_m": facts["objective_m"],
            "bound_m": facts["bound_m"],
            "gap": facts["gap"],
            "candidates": res.n_candidates,
            "evaluated": res.n_evaluated,
            "unit_m": res.model.unit_m,
            "timings_s": res.timings,
        }
    pd.DataFrame(tidy).to_csv(folder / "kpis.csv", index=False)
    if rounds:
        pd.concat(rounds, ignore_index=True).to_csv(folder / "rounds.csv.gz", index=False)
    if hourly and bound is not None:
        hourly.append(bound_by_hour(bound.pairs))
    if hourly:
        pd.concat(hourly, ignore_index=True).to_csv(folder / "hourly.csv", index=False)
    meta = {
        "rpbench_results": 1,
        "command": command,
        "scenario": {
            "name": scenario.name,
            "label": scenario.label,
            "synthetic": scenario.synthetic,
            "args": scenario_args,
            "seed": scenario.seed,
            "start_time": scenario.start_time,
            "horizon_s": scenario.horizon_s,
            "provenance": scenario.provenance,
            "summary": {k: v for k, v in scenario.summary().items() if k != "params"},
            "network_hash": scenario.network.content_hash,
        },
        "params": scenario.params.as_dict(),
        "preset": preset.as_dict(),
        "strategies": strategies,
        "runs": meta_runs,
        # What `rpbench check` holds the folder to (docs/guarantees.md): every run folder written, and the
        # SHA-256 of the inputs, parameters and run options, so that a deleted run or an edit is caught.
        "manifest": {"runs": list(meta_runs)},
        "inputs_digest": inputs_digest(folder, scenario.params.as_dict(), meta_runs),
        **results.environment(),
        "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }
    results.write_json(folder / "meta.json", meta)
