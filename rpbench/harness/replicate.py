"""``rpbench replicate``'s work: per date and strategy, the authors' engine, the ablation steps, rpbench's engine.

Every run is one row (a dict) with the engine, the strategy, the date, the
KPIs in the authors' definitions (response = served / the run's denominator)
and, beside them, the authors' committed output and the paper's printed value
with its origin.  Engines:

* ``authors``: every switch on (:class:`~rpbench.replication.switches.Switches`);
* ``authors-no-<mechanism>``: that one mechanism off, the others on;
* ``authors-all-off``: every switch off;
* ``rpbench``: rpbench's own simulator (``rpbench/sim``) on the authors'
  input (haikou-paper-input), its response rate over the same denominator;
* ``rpbench-peak``: rpbench's own simulator on its own input (haikou-peak,
  seed 0), i.e. rpbench's published numbers: the end of the chain that
  ``authors-all-off`` approaches.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.backends.presets import Preset
from rpbench.data.paper_orders import PREDICTION_COLUMNS
from rpbench.exceptions import ParameterError
from rpbench.harness.comparison import calibrated, simulate_strategy
from rpbench.replication import reference
from rpbench.replication.engine import STRATEGIES, AuthorsEngine, AuthorsRun
from rpbench.replication.switches import Switches, steps_for
from rpbench.scenarios.base import Scenario
from rpbench.scenarios.paper_input import PaperInput, load_paper_input
from rpbench.scenarios.peak import build_peak
from rpbench.spec import resolve_runs

ROW_KPIS = (
    "response_rate",
    "pairing_ratio",
    "total_saving_km",
    "avg_detour_m",
    "avg_shared_m",
    "avg_response_time_s",
    "avg_pickup_time_s",
)


@dataclass
class Inputs:
    """Both inputs of one date: the authors' and rpbench's haikou-peak (for the authors_input switch)."""

    paper: PaperInput
    peak: PaperInput


@dataclass
class Replication:
    rows: list[dict[str, object]] = field(default_factory=list)
    outcomes: dict[tuple[str, str, str], AuthorsRun] = field(default_factory=dict)  # (date, strategy, engine)


def parse_strategies(text: str) -> list[str]:
    names = [s.strip().lower() for s in text.split(",") if s.strip()]
    unknown = [s for s in names if s not in STRATEGIES]
    if not names or unknown:
        raise ParameterError(f"--strategies {text!r}: expected a comma-separated subset of {', '.join(STRATEGIES)}")
    return list(dict.fromkeys(names))


def load_inputs(data_dir: Path, date: str) -> Inputs:
    paper = load_paper_input(data_dir, date=date)
    peak_scenario = build_peak(data_dir, date=date, sample=0.3, seed=0)
    peak = PaperInput(
        scenario=peak_scenario,
        predictions=_peak_predictions(data_dir, date, peak_scenario),
        response_denominator=len(peak_scenario.orders),
    )
    return Inputs(paper=paper, peak=peak)


def _peak_predictions(data_dir: Path, date: str, scenario: Scenario) -> pd.DataFrame:
    """The order file's per-order predictions aligned with a haikou-peak scenario's orders."""
    from rpbench.data._table import open_csv
    from rpbench.data.orders import peak_order_path

    with open_csv(peak_order_path(data_dir, date), "peak-hour order") as source:
        raw = pd.read_csv(source, compression=None)
    raw = raw.drop_duplicates("dwv_order_make_haikou_1.order_id").set_index("dwv_order_make_haikou_1.order_id")
    cols = [c for c in PREDICTION_COLUMNS if c in raw.columns]
    return raw.loc[scenario.orders.order_id, cols].reset_index(drop=True)


def engine_name(label: str) -> str:
    return label if label == "authors" else f"authors-{label}"


def run_authors(inputs: Inputs, strategy: str, switches: Switches, preset: Preset) -> AuthorsRun:
    chosen = inputs.paper if switches.authors_input else inputs.peak
    return AuthorsEngine(
        chosen.scenario,
        strategy,
        preset,
        switches=switches,
        predictions=chosen.predictions,
        denominator=chosen.response_denominator,
        reposition_origins=chosen.idle_origins,
        release_rank=chosen.sample_rank,
    ).run()


def run_rpbench(chosen: PaperInput, strategy: str, preset: Preset, done: dict[str, Any]) -> dict[str, float]:
    """rpbench's own engine on ``chosen``; response over its denominator (the authors': the whole sample)."""
    scenario = chosen.scenario
    (entry,) = resolve_runs([strategy])
    run = simulate_strategy(scenario, calibrated(entry, scenario, preset, done, False), preset, progress=False)
    done[strategy] = run
    k = dict(run.kpis)
    k["response_denominator"] = chosen.response_denominator
    k["response_rate"] = k["served"] / chosen.response_denominator
    k["vehicles"] = len(scenario.fleet)
    return k


def replicate(
    data_dir: Path,
    dates: list[str],
    strategies: list[str],
    preset: Preset,
    *,
    ablation: str = "single",
    rpbench_engine: bool = True,
    progress: bool = False,
    keep: Callable[[str, str, str, Any, Scenario], None] | None = None,
) -> Replication:
    """Every (date, strategy): the authors' engine and the ablation steps of ``ablation`` (single, cumulative,
    both, none), then rpbench's engine on both inputs unless ``rpbench_engine`` is false.  ``keep(date,
    strategy, engine, run, scenario)`` receives each run of rpbench's engine (its StrategyRun) once made."""
    committed = reference.read_committed(data_dir)
    steps = steps_for(ablation)
    out = Replication()
    for date in dates:
        inputs = load_inputs(data_dir, date)
        done: dict[str, Any] = {}
        done_peak: dict[str, Any] = {}
        for strategy in strategies:
            if strategy in STRATEGIES:
                for label, switches in steps:
                    outcome = run_authors(inputs, strategy, switches, preset)
                    name = engine_name(label)
                    out.outcomes[(date, strategy, name)] = outcome
                    out.rows.append(_row(name, strategy, date, outcome.kpis(), switches.off(), committed))
                    if progress:
                        print(
                            f"rpbench: {date} {strategy:>5} {name:<40} pairing {out.rows[-1]['pairing_ratio']:.3f}"
                            f" saving {out.rows[-1]['total_saving_km']:.1f} km",
                            file=sys.stderr,
                            flush=True,
                        )
            if rpbench_engine:
                for name, chosen, cache in (("rpbench", inputs.paper, done), ("rpbench-peak", inputs.peak, done_peak)):
                    kpis = run_rpbench(chosen, strategy, preset, cache)
                    if keep is not None:
                        keep(date, strategy, name, cache[strategy], chosen.scenario)
                    out.rows.append(_row(name, strategy, date, kpis, ["(rpbench's simulator)"], committed))
                    if progress:
                        print(
                            f"rpbench: {date} {strategy:>5} {name:<40} pairing {kpis['pairing_ratio']:.3f}"
                            f" saving {kpis['total_saving_km']:.1f} km",
                            file=sys.stderr,
                            flush=True,
                        )
    return out


def _row(
    engine: str, strategy: str, date: str, kpis: dict[str, float], off: list[str], committed: pd.DataFrame
) -> dict[str, object]:
    row: dict[str, object] = {"engine": engine, "strategy": strategy, "date": date, "switches_off": ",".join(off)}
    for k in ("orders", "response_denominator", "vehicles", "served", "pooled_passengers"):
        if k in kpis:
            row[k] = int(kpis[k])
    ours = {k: _clean(kpis.get(k, float("nan"))) for k in ROW_KPIS}
    row.update(ours)
    for k in reference.REFERENCE_KPIS:
        c = reference.committed_value(committed, strategy, date, k)
        row[f"committed_{k}"] = _clean(c)
        mine = ours[k]
        row[f"diff_{k}"] = _clean(mine - c) if mine is not None and np.isfinite(c) else None
        printed, origin = reference.printed_value(strategy, date, k)
        row[f"paper_{k}"] = _clean(printed)
        row[f"paper_{k}_origin"] = origin or None
    return row


def _clean(x: float) -> float | None:
    """JSON-friendly: NaN -> None."""
    x = float(x)
    return None if not np.isfinite(x) else x
