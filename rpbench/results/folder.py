"""Writing a comparison's results folder, and the ``meta.json`` of parent folders (multi-day runs, sweeps).

:func:`write_folder` writes every file of :mod:`.layout` but the report
(:func:`rpbench.report.comparison.write_report` renders it from these files):
the inputs, one folder per run, the KPI, round and hourly tables and
``meta.json``.  ``meta.json`` records, per run, what the checker holds it to
(kind, options, rules, status: digested in ``inputs_digest``) and what a
report needs to show it without importing its class (label, colour, source),
so that a folder re-renders from its files alone, plug-ins included.  A run given a decision budget
records it as ``decision_budget_s`` (absent otherwise): the checker and the reports read it there.
kpis.csv also holds the rows derived from the other runs (:mod:`rpbench.results.ratios`: each simulated
run's competitive ratios and saving / Oracle-1, the bound's LB and U / LB) and meta.json names the run
that gave LB (``best_known``).
"""

from __future__ import annotations

import dataclasses
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.backends import Preset
from rpbench.options import RunOptions
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.oracle.solve import OracleResult
from rpbench.results import layout
from rpbench.results.digest import inputs_digest
from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.ratios import BEST_KNOWN_FIELD, best_known, derived_rows
from rpbench.results.store import environment, save_network, save_trajectories, write_json
from rpbench.scenarios.base import Scenario
from rpbench.sim.simulator import SimResult
from rpbench.spec import RunSpec

#: Format version of ``meta.json`` (``rpbench_results``).
RESULTS_FORMAT = 1
#: The inputs meta.json digests are gzip files written without a time in their header, so that one scenario
#: written twice gives the same bytes and the same digests (folders of one instance then combine even as
#: published light copies, which keep only the digests).
REPRODUCIBLE_GZIP = {"method": "gzip", "mtime": 0}
#: The runs' logs (events, rounds, pairs) at zlib's default level: gzip's own default, 9, took twice the time
#: to write them for files about 7 % smaller.  Digests and the checker read the uncompressed content.
LOG_GZIP = {"method": "gzip", "compresslevel": 6}


@dataclass
class StrategyRun:
    """One simulated run with its KPIs: what its folder and its rows of the tables hold."""

    name: str
    sim: SimResult
    passengers: pd.DataFrame
    kpis: dict[str, float]
    hourly: pd.DataFrame
    options: RunOptions
    source: str  # the strategy it ran (a built-in name, an entry point or module:Class)
    label: str
    color: str | None


def oracle_kpis(result: OracleResult) -> dict[str, float]:
    """The numeric KPIs of an offline run (its solver facts go to meta.json); the upper bound's matching
    statistics under their own names (:data:`~rpbench.results.metrics.BOUND_MATCHING_KPIS`): they bound nothing."""
    rename = BOUND_MATCHING_KPIS if result.is_upper_bound else {}
    return {
        rename.get(k, k): float(v)
        for k, v in result.kpis().items()
        if isinstance(v, (int, float, np.number)) and not isinstance(v, bool) and k != "variant"
    }


def bound_by_hour(pairs: pd.DataFrame) -> pd.DataFrame:
    """The upper bound's matching split by the hour of each pair's earlier request (``hourly.csv`` rows of run
    ``bound``; only the saving column: per hour this is a description of the matching, not itself a bound)."""
    hour = (np.minimum(pairs["first_request_s"], pairs["second_request_s"]) // 3600).astype(int)
    saving = pairs["saving_m"].groupby(hour).sum() / 1000.0
    return pd.DataFrame({"hour": saving.index, "total_saving_km": saving.to_numpy(), "run": "bound"})


def derived_kpi_rows(runs: Sequence[StrategyRun], offline: dict[str, OracleResult]) -> list[dict[str, Any]]:
    """kpis.csv's rows derived from the other runs (:mod:`rpbench.results.ratios`): each simulated run's
    competitive ratios and saving / Oracle-1, and with a bound LB and U / LB as rows of the bound."""
    savings = {r.name: r.kpis["total_saving_km"] for r in runs}
    offline_savings = {name: oracle_kpis(res)["total_saving_km"] for name, res in offline.items()}
    rows = derived_rows(savings, offline_savings)
    return [{"run": run, "kpi": k, "value": v} for run, row in rows.items() for k, v in row.items()]


def copy_artefacts(artefacts: dict[str, tuple[str, Path]], run_dir: Path) -> dict[str, str]:
    """Copy each artefact folder into ``run_dir/NAME/`` and return ``{name: digest}`` for meta.json."""
    for name, (_, source) in artefacts.items():
        shutil.copytree(source, run_dir / name)
    return {name: digest for name, (digest, _) in artefacts.items()}


def write_folder(
    folder: Path,
    spec: RunSpec,
    scenario: Scenario,
    runs: Sequence[StrategyRun],
    offline: dict[str, OracleResult],
    preset: Preset,
) -> dict[str, Any]:
    """Write the comparison ``spec`` ran on ``scenario`` (its ``runs`` and ``offline`` runs, the simulations
    solved by ``preset``) into ``folder``; returns the ``meta.json`` record it wrote."""
    write_inputs(folder, scenario)
    records = {r.name: write_simulated_run(folder, r) for r in runs}
    records.update({name: write_offline_run(folder, name, res) for name, res in offline.items()})
    write_tables(folder, runs, offline)
    meta = meta_record(folder, spec, scenario, preset, records, runs)
    write_json(folder / layout.META, meta)
    return meta


def write_inputs(folder: Path, scenario: Scenario) -> None:
    """The scenario's orders, road network and fleet: what every run of the folder was given."""
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
    ).to_csv(folder / layout.ORDERS, index=False, compression=REPRODUCIBLE_GZIP)
    save_network(folder / layout.NETWORK, scenario.network)
    pd.DataFrame({"vehicle": np.arange(len(scenario.fleet)), "initial_node": scenario.fleet.initial_node}).to_csv(
        folder / layout.FLEET, index=False, compression=REPRODUCIBLE_GZIP
    )


def write_simulated_run(folder: Path, r: StrategyRun) -> dict[str, Any]:
    """``runs/<name>/``: a simulation's event log, trajectories and artefacts; returns its meta.json record."""
    d = folder / layout.RUNS / r.name
    d.mkdir(parents=True)
    r.sim.events.to_csv(d / layout.EVENTS, index=False, compression=LOG_GZIP)
    save_trajectories(d / layout.TRAJECTORIES, r.sim.trajectories)
    return {
        "kind": "simulation",
        "options": r.options.as_dict(),
        "wall_s": r.sim.wall_s,
        "prepare_s": r.sim.prepare_s,
        **({"artefacts": copy_artefacts(r.sim.artefacts, d)} if r.sim.artefacts else {}),
        "end_s": r.sim.end_s,
        "rounds_solved": len(r.sim.rounds),
        "clairvoyant": r.sim.clairvoyant,
        "source": r.source,
        "label": r.label,
        "color": r.color,
    }


def write_offline_run(folder: Path, name: str, res: OracleResult) -> dict[str, Any]:
    """``runs/<name>/``: an offline run's pairs; returns its meta.json record (its solver's facts)."""
    d = folder / layout.RUNS / name
    d.mkdir(parents=True)
    res.pairs.to_csv(d / layout.PAIRS, index=False, compression=LOG_GZIP)
    facts = res.kpis()
    return {
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
        "source": name,
        "label": ORACLE_RUNS[name].label,
        "color": ORACLE_RUNS[name].color,
    }


def rounds_table(runs: Sequence[StrategyRun]) -> pd.DataFrame | None:
    """``rounds.csv.gz``: every simulated run's rounds, with its name (None: no simulated run)."""
    return pd.concat([r.sim.rounds.assign(run=r.name) for r in runs], ignore_index=True) if runs else None


def write_tables(folder: Path, runs: Sequence[StrategyRun], offline: dict[str, OracleResult]) -> None:
    """``kpis.csv`` (every run's KPIs and the rows derived from them), ``rounds.csv.gz`` and ``hourly.csv``."""
    tidy = [{"run": r.name, "kpi": k, "value": v} for r in runs for k, v in r.kpis.items()]
    tidy += [{"run": name, "kpi": k, "value": v} for name, res in offline.items() for k, v in oracle_kpis(res).items()]
    tidy += derived_kpi_rows(runs, offline)
    pd.DataFrame(tidy).to_csv(folder / layout.KPIS, index=False)
    rounds = rounds_table(runs)
    if rounds is not None:
        rounds.to_csv(folder / layout.ROUNDS, index=False, compression=LOG_GZIP)
    hourly = [r.hourly.assign(run=r.name) for r in runs]
    if hourly and "bound" in offline:
        hourly.append(bound_by_hour(offline["bound"].pairs))
    if hourly:
        pd.concat(hourly, ignore_index=True).to_csv(folder / layout.HOURLY, index=False)


def meta_record(
    folder: Path,
    spec: RunSpec,
    scenario: Scenario,
    preset: Preset,
    records: dict[str, dict[str, Any]],
    runs: Sequence[StrategyRun],
) -> dict[str, Any]:
    """``meta.json`` of a comparison whose inputs and runs are written in ``folder`` (``records``: each run's)."""
    lb = best_known({r.name: r.kpis["total_saving_km"] for r in runs})
    return {
        "rpbench_results": RESULTS_FORMAT,
        "command": spec.command,
        "scenario": {
            "name": scenario.name,
            "label": scenario.label,
            "synthetic": scenario.synthetic,
            "args": spec.request.meta(),
            "seed": scenario.seed,
            "start_time": scenario.start_time,
            "horizon_s": scenario.horizon_s,
            "provenance": scenario.provenance,
            "summary": {k: v for k, v in scenario.summary().items() if k != "params"},
            "network_hash": scenario.network.content_hash,
        },
        "params": scenario.params.as_dict(),
        # only with a budget: without one, meta.json holds what it held before budgets existed
        **({"decision_budget_s": spec.decision_budget_s} if spec.decision_budget_s is not None else {}),
        "preset": preset.as_dict(),
        "strategies": spec.names,
        "runs": records,
        # the run that gave LB, the best known schedule (docs/simulator.md; rpbench check recomputes it)
        BEST_KNOWN_FIELD: lb.record() if lb is not None else None,
        # What `rpbench check` holds the folder to (docs/guarantees.md): every run folder written, and the
        # SHA-256 of the inputs, parameters and run options, so that a deleted run or an edit is caught.
        "manifest": {"runs": list(records)},
        "inputs_digest": inputs_digest(folder, scenario.params.as_dict(), records),
        **environment(),
        "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }


def write_parent_meta(folder: Path, kind: str, children: Sequence[str], fields: dict[str, Any]) -> None:
    """``meta.json`` of a multi-day or sweep folder: its kind, its child folders (the checker's manifest),
    the kind's own ``fields`` and the environment."""
    write_json(
        folder / layout.META,
        {"rpbench_results": RESULTS_FORMAT, "kind": kind, **fields, "children": list(children), **environment()},
    )
