"""Scenario x strategies x preset -> one results folder.

:func:`simulate_strategy` runs one strategy and derives its KPIs from the
event log (:mod:`rpbench.metrics`); :func:`run_comparison` runs several on
the same scenario and writes a results folder (:mod:`rpbench.results`)
with a report.  The offline oracles join the comparison as runs named
``oracle1``/``oracle2`` (the seed's pair rules, ALGORITHMS.md A18) and
``oracle1-enroute`` (Oracle-1 that may also pair an order with one already
riding, in either pick-up order: the bound on en-route pooling that the
seed's rules lack, §4.2).
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

from . import metrics, results
from .exceptions import ParameterError
from .report import with_competitive_ratios, write_report
from .scenario import Scenario
from .sim import SimResult, Simulator
from .solver_presets import Preset, load_preset
from .strategies import REGISTRY as STRATEGY_REGISTRY
from .strategies import make_strategy

#: Oracle run name -> (variant, pair-rule flags).
ORACLE_RUNS = {"oracle1": (1, {}), "oracle2": (2, {}),
               "oracle1-enroute": (1, {"allow_enroute": True, "both_pickup_orders": True})}
ORACLES = tuple(ORACLE_RUNS)


@dataclass
class StrategyRun:
    """One strategy's simulation with its KPIs."""

    name: str
    sim: SimResult
    passengers: pd.DataFrame
    kpis: dict[str, float]
    hourly: pd.DataFrame
    options: dict[str, Any] = field(default_factory=dict)


def parse_strategies(text: str | list[str]) -> list[str]:
    names = [s.strip().lower() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    known = list(STRATEGY_REGISTRY) + list(ORACLES)
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise ParameterError(f"unknown strategy {unknown[0] if unknown else '(none)'!r}; "
                             f"choose from {', '.join(known)}")
    if len(set(names)) != len(names):
        raise ParameterError(f"strategy list {','.join(names)} names a strategy twice")
    return names


def progress_bar(scenario: Scenario, label: str, enabled: bool | None):
    """A tqdm bar over simulated seconds on stderr (off when stderr is not a terminal)."""
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return None
    from tqdm import tqdm
    return tqdm(total=scenario.horizon_s, desc=f"{label:>6}", unit="sim s", leave=False, file=sys.stderr,
                bar_format="{desc} {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} sim s [{elapsed}<{remaining}]")


def simulate_strategy(scenario: Scenario, name: str, preset: Preset, *, options: dict[str, Any] | None = None,
                      progress: bool | None = None, canonical_ties: bool = True, capture=None) -> StrategyRun:
    """Simulate one strategy and compute its KPIs from the event log."""
    strategy = make_strategy(name, **(options or {}))
    backend = preset.make_backend()
    if not backend.supports(strategy.structure):
        raise ParameterError(f"solver preset {preset.name!r} (backend {preset.backend!r}) does not solve "
                             f"{strategy.structure.value} models exactly, which strategy {name!r} needs; "
                             "choose another --solver")
    bar = progress_bar(scenario, name, progress)
    try:
        sim = Simulator(scenario, strategy, backend, preset.options, canonical_ties=canonical_ties,
                        progress=bar, capture=capture).run()
    finally:
        if bar is not None:
            bar.close()
    return evaluate(scenario, sim, name, options or {})


def evaluate(scenario: Scenario, sim: SimResult, name: str, options: dict[str, Any]) -> StrategyRun:
    orders = scenario.orders
    solo = scenario.network.distances()(orders.origin, orders.destination)
    tab = metrics.passenger_table(sim.events, solo, orders.request_s, sim.trajectories)
    occupied = metrics.occupied_distance_m(sim.events, sim.trajectories)
    kpis = metrics.kpis(tab, occupied, scenario.params)
    kpis["wall_s"] = sim.wall_s
    return StrategyRun(name=name, sim=sim, passengers=tab, kpis=kpis, hourly=metrics.hourly(tab), options=options)


def run_comparison(scenario: Scenario, strategies: list[str], preset_name: str, *, out: str | Path | None = None,
                   strategy_options: dict[str, dict[str, Any]] | None = None, progress: bool | None = None,
                   scenario_args: dict[str, Any] | None = None, command: str | None = None,
                   oracle_solver: str | None = None) -> tuple[Path, pd.DataFrame]:
    """Run every strategy (and oracle) on ``scenario`` and write one results folder.

    The oracles are solved with ``oracle_solver`` (a preset name), by default
    the comparison's own preset.
    """
    preset = load_preset(preset_name)
    strategy_options = strategy_options or {}
    runs: list[StrategyRun] = []
    oracle_results = {}
    done: dict[str, StrategyRun] = {}
    for name in strategies:
        if name in ORACLES:
            continue
        options = dict(strategy_options.get(name) or {})
        if name in CALIBRATED:
            options = calibrated_options(scenario, preset, options, done, progress)
        run = done.get(name) if name == "mb" and not options else None
        run = run or simulate_strategy(scenario, name, preset, options=options, progress=progress)
        done[name] = run
        runs.append(run)
    wanted = [n for n in strategies if n in ORACLES]
    if wanted:
        oracle_preset = load_preset(oracle_solver) if oracle_solver else preset
        oracle_results = solve_oracles(scenario, wanted, oracle_preset, strategy_options)
    table = kpi_table(runs, oracle_results, strategies)
    stamp = results.timestamp()
    default = f"{stamp}_{scenario.name}_{preset.name}"
    with results.new_results_folder(out, default) as (folder, final):
        write_folder(folder, scenario, runs, oracle_results, preset, strategies, scenario_args or {}, command)
        write_report(folder, name=final.name)
    return final, table


CALIBRATED = ("fl", "fl-nd")


def calibrated_options(scenario: Scenario, preset: Preset, options: dict[str, Any], done: dict[str, StrategyRun],
                       progress: bool | None) -> dict[str, Any]:
    """Fill FL's ``tau0_s`` (A4) and ``mean_pickup_m`` (l̄) from an MB calibration run on the same scenario.

    ALGORITHMS.md §1-§2: τ_0 = the mean pick-up time and l̄ = the mean pick-up
    distance of an MB run "for the same hour" — per hour when the scenario
    spans several.  The MB run is shared with the comparison's own MB column
    (it is deterministic, so running it once or twice gives the same numbers).
    """
    if "tau0_s" in options and "mean_pickup_m" in options:
        return options
    mb = done.get("mb")
    if mb is None:
        mb = simulate_strategy(scenario, "mb", preset, progress=progress)
        done["mb"] = mb
    hours = max(1, int(np.ceil(scenario.horizon_s / 3600.0)))
    if hours == 1:
        values = {"tau0_s": mb.kpis["avg_pickup_time_s"], "mean_pickup_m": mb.kpis["avg_pickup_distance_m"]}
    else:
        h = mb.hourly.set_index("hour").reindex(range(hours))
        values = {"tau0_s": [round(float(x), 3) for x in h["avg_pickup_time_s"]],
                  "mean_pickup_m": [round(float(x), 3) for x in h["avg_pickup_m"]]}
    return {**{k: v for k, v in values.items() if k not in options}, **options}


ORACLE_FLAGS = ("both_pickup_orders", "pickup_check", "allow_enroute")


def solve_oracles(scenario: Scenario, names: list[str], preset: Preset, strategy_options: dict) -> dict:
    """Oracle-1/Oracle-2 over the scenario's orders, sharing one candidate enumeration when the rules agree."""
    from .oracle import PairRules, find_candidates, solve_oracle
    out = {}
    cache: dict = {}
    for name in names:
        variant, defaults = ORACLE_RUNS[name]
        flags = dict(strategy_options.get(name) or {})
        unknown = set(flags) - set(ORACLE_FLAGS)
        if unknown:
            raise ParameterError(f"{name}: unknown option(s) {', '.join(sorted(unknown))}; known: "
                                 f"{', '.join(ORACLE_FLAGS)}")
        rules = PairRules.from_params(scenario.params, **{**defaults, **{k: bool(v) for k, v in flags.items()}})
        if rules not in cache:
            cache[rules] = find_candidates(scenario.network.distances(), scenario.orders, rules)
        out[name] = solve_oracle(scenario, variant, preset, candidates=cache[rules])
    return out


def oracle_kpis(result) -> dict[str, float]:
    """The numeric KPIs of an oracle result (solver facts go to meta.json)."""
    return {k: float(v) for k, v in result.kpis().items() if isinstance(v, (int, float, np.number))
            and not isinstance(v, bool) and k not in ("variant",)}


def kpi_table(runs: list[StrategyRun], oracle_results: dict, order: list[str]) -> pd.DataFrame:
    """Wide table: KPI rows x run columns (in the requested order), with the competitive ratio."""
    cols = {r.name: r.kpis for r in runs}
    for name, res in oracle_results.items():
        cols[name] = oracle_kpis(res)
    return with_competitive_ratios(pd.DataFrame({name: cols[name] for name in order if name in cols}))


def write_folder(folder: Path, scenario: Scenario, runs: list[StrategyRun], oracle_results: dict, preset: Preset,
                 strategies: list[str], scenario_args: dict[str, Any], command: str | None) -> None:
    orders = scenario.orders
    solo = scenario.network.distances()(orders.origin, orders.destination)
    pd.DataFrame({"order_id": orders.order_id, "request_s": orders.request_s, "origin": orders.origin,
                  "destination": orders.destination, "patience_s": orders.patience_s, "solo_m": solo}
                 ).to_csv(folder / "orders.csv.gz", index=False)
    results.save_network(folder / "network.npz", scenario.network)
    pd.DataFrame({"vehicle": np.arange(len(scenario.fleet)), "initial_node": scenario.fleet.initial_node}
                 ).to_csv(folder / "fleet.csv.gz", index=False)
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
        meta_runs[r.name] = {"kind": "simulation", "options": r.options, "wall_s": r.sim.wall_s,
                             "end_s": r.sim.end_s, "rounds_solved": int(len(r.sim.rounds))}
    for name, res in oracle_results.items():
        d = folder / "runs" / name
        d.mkdir(parents=True)
        res.pairs.to_csv(d / "pairs.csv.gz", index=False)
        tidy += [{"run": name, "kpi": k, "value": v} for k, v in oracle_kpis(res).items()]
        facts = res.kpis()
        meta_runs[name] = {"kind": "oracle", "variant": res.variant, "solver": res.solver,
                           "status": facts["status"], "rules": dataclasses.asdict(res.rules),
                           "objective_m": facts["objective_m"], "bound_m": facts["bound_m"], "gap": facts["gap"],
                           "candidates": res.n_candidates, "evaluated": res.n_evaluated,
                           "timings_s": res.timings}
    pd.DataFrame(tidy).to_csv(folder / "kpis.csv", index=False)
    if rounds:
        pd.concat(rounds, ignore_index=True).to_csv(folder / "rounds.csv.gz", index=False)
    if hourly:
        pd.concat(hourly, ignore_index=True).to_csv(folder / "hourly.csv", index=False)
    meta = {
        "rpbench_results": 1,
        "command": command,
        "scenario": {"name": scenario.name, "label": scenario.label, "synthetic": scenario.synthetic,
                     "args": scenario_args, "seed": scenario.seed, "start_time": scenario.start_time,
                     "horizon_s": scenario.horizon_s, "provenance": scenario.provenance,
                     "summary": {k: v for k, v in scenario.summary().items() if k != "params"},
                     "network_hash": scenario.network.content_hash},
        "params": scenario.params.as_dict(),
        "preset": preset.as_dict(),
        "strategies": strategies,
        "runs": meta_runs,
        **results.environment(),
        "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }
    results.write_json(folder / "meta.json", meta)
