"""``rpbench predict``: solve the seeker/taker prediction model and write the per-OD table.

``--rates month`` is the 21-day table (the paper's choice), ``--rates day``
one date's peak-hour orders (count per OD / 3600 s), ``--rates day-table``
the 2017-05-01 per-day OD table the authors predicted for, or a path to any
OD table in the ``month_5_OD`` format.  ``--validate-fcfs`` also simulates a
first-come-first-served dispatcher on Poisson demand from the same rates and
reports MAPE/RMSE; ``--compare-authors`` compares with the authors' published
2017-05-01 predictions.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from rpbench.commands.args import (
    SEED,
    add_data_arg,
    add_number_arg,
    add_offline_arg,
    check_numbers,
    parse_param_overrides,
)
from rpbench.commands.checks import check_out_file, write_out_file
from rpbench.commands.output import note, print_json
from rpbench.data.first_run import ensure_data_dir
from rpbench.data.paper import PAPER_DATE
from rpbench.exceptions import ParameterError
from rpbench.options import Range
from rpbench.predict import PredictConfig, build_prediction_model, predict, solve_prediction_model
from rpbench.predict.compare import compare
from rpbench.predict.config import ACCELERATIONS, PRIORITIES
from rpbench.predict.fcfs import simulate, validate
from rpbench.predict.rates import RATE_KINDS, load_rates
from rpbench.scenarios.base import Params
from rpbench.scenarios.common import haikou_network

#: τ_0 is a sojourn (a mean pick-up time): a day bounds it, as it bounds FL's tau0_s.
TAU0 = Range(0.0, 86400.0, "s")
#: The FCFS simulation holds every simulated order in memory: 1000 h (ten times the default) of the month
#: table's demand is a few GB, already more than a validation needs.
HOURS = Range(0.0, 1000.0, "h", low_open=True)
MIN_SAMPLES = Range(1, 10**6, integer=True)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "predict",
        help="predict pairing probabilities and expected savings per OD",
        description="Solve the seeker/taker fixed point (TR-B 2021 model as used by the FL "
        "strategy) for an OD rate table and write one CSV row per OD.",
    )
    p.add_argument(
        "--rates",
        default="month",
        metavar="KIND",
        help="month (21-day table, default), day (a date's peak orders), day-table "
        "(the 2017-05-01 per-day OD table), or a path to an OD table CSV",
    )
    p.add_argument("--date", default=None, help=f"date for --rates day (default {PAPER_DATE})")
    add_data_arg(p)
    add_offline_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--out",
        metavar="FILE.csv",
        default=None,
        help="per-OD CSV (default: prediction-<rates>[-<date>].csv in the current folder)",
    )
    add_number_arg(
        p,
        "--tau0",
        TAU0,
        metavar="S",
        help="sojourn of the origin taker state, e.g. a calibrated mean pick-up time (default 120)",
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter (max_pickup_m, max_detour_m, speed_mps, ...)",
    )
    p.add_argument("--priority", choices=PRIORITIES, default=None, help="seeker priority order (default net_saving)")
    p.add_argument(
        "--accel",
        choices=ACCELERATIONS,
        default=None,
        help="fixed-point acceleration (default none: the spec's damped iteration, A9, 32 sweeps on the "
        "month table; anderson: FL's default, the same fixed point in about half the sweeps)",
    )
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="recompute the prediction and its seeker/taker structure even when cached "
        "(the structure is then built in a private temporary folder)",
    )
    p.add_argument(
        "--validate-fcfs",
        action="store_true",
        help="also simulate an FCFS dispatcher on Poisson demand and report MAPE/RMSE",
    )
    add_number_arg(p, "--hours", HOURS, help="simulated hours for --validate-fcfs (default 100)")
    add_number_arg(
        p, "--min-samples", MIN_SAMPLES, help="compare ODs with at least this many simulated orders (default 20)"
    )
    add_number_arg(p, "--seed", SEED, help="random seed of the FCFS simulation (default 0)")
    p.add_argument(
        "--compare-authors", action="store_true", help="compare with the authors' published 2017-05-01 predictions"
    )
    p.set_defaults(handler=_run)


def default_csv(kind: str, date: str | None) -> Path:
    label = kind if kind in RATE_KINDS else Path(kind).name.split(".")[0]
    if kind == "day":
        label += f"-{date or PAPER_DATE}"
    return Path(f"prediction-{label}.csv")


def _run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    check_numbers(args)  # before the data folder is fetched or anything is built
    given = {"--hours": args.hours, "--min-samples": args.min_samples, "--seed": args.seed}
    if not args.validate_fcfs:
        for flag, value in given.items():
            if value is not None:
                raise ParameterError(f"{flag} applies to --validate-fcfs only; add --validate-fcfs or drop it")
    hours = 100.0 if args.hours is None else args.hours
    min_samples = 20 if args.min_samples is None else args.min_samples
    seed = 0 if args.seed is None else args.seed
    params = Params().replace(**parse_param_overrides(args.param))
    # checked before the (minutes-long) solve: a bad --out must not cost it
    csv_path = check_out_file(args.out or str(default_csv(args.rates, args.date)), "--out")
    data_dir = ensure_data_dir(args.data, what="rpbench predict", offline=args.offline)
    changes = {
        k: v for k, v in (("tau0_s", args.tau0), ("priority", args.priority), ("accel", args.accel)) if v is not None
    }
    config = PredictConfig().replace(**changes)
    network = haikou_network(data_dir)
    rates = load_rates(args.rates, network, data_dir, args.date)
    if not args.json:
        note(f"rpbench predict: {len(rates)} ODs from {rates.source}; building the model ...")
    out: dict = {}
    if args.validate_fcfs:
        model = build_prediction_model(network, rates, params, config)
        prediction = solve_prediction_model(model)
        simulated = simulate(model, hours=hours, seed=seed)
        del model
        out["fcfs"], _ = validate(prediction, simulated, min_samples=min_samples)
        if not out["fcfs"]["ods_compared"]:  # nothing to report: refused before the CSV is written
            raise ParameterError(
                f"--validate-fcfs: no OD has {min_samples} simulated orders in {hours:g} h; raise --hours or "
                "lower --min-samples"
            )
    else:
        prediction = predict(network, rates, params, config, use_cache=not args.no_cache)
    table = prediction.per_od_table()
    write_out_file(csv_path, "--out", lambda tmp: table.to_csv(tmp, index=False))
    if args.compare_authors:
        out["authors"], _ = compare(prediction, data_dir)
    summary = {k: v for k, v in prediction.summary().items() if k not in ("config", "params")}
    result = {
        **summary,
        "csv": str(csv_path),
        "wall_s": round(time.perf_counter() - t0, 3),
        **out,
        "params": prediction.summary().get("params"),
        "config": prediction.summary().get("config"),
    }
    if args.json:
        print_json(result)
        return 0
    _print_human(result)
    return 0


def _print_human(r: dict) -> None:
    print(
        f"{r['ods']} ODs ({r['rates_source']}), {r['states']} taker states, "
        f"{r['candidate_pairs']:,} candidate seeker-taker pairs"
    )
    state = "converged" if r["converged"] else "NOT converged"
    took = "from cache" if r["from_cache"] else "{:.1f} s".format(r.get("time_s", r["wall_s"]))
    print(
        f"fixed point: {state} in {r['iterations']} iterations, residual {r['residual']:.2e}, "
        f"{r['clip_count']} clipped; {took}"
    )
    print(
        f"mean pairing probability {r['mean_pairing_prob']:.3f} (seeker {r['mean_p_seeker']:.3f}); "
        f"per-OD table: {r['csv']}"
    )
    if "fcfs" in r:
        f = r["fcfs"]
        print(
            f"FCFS validation ({f['hours']:g} h, {f['simulated_orders']:,} orders, {f['ods_compared']} ODs "
            f"with >= {f['min_samples']} orders):"
        )
        for name in ("pairing_prob", "ride_m", "shared_m"):
            m = f[name]
            print(
                f"  {name:<13} MAPE {_num(m['mape_pct'], '.2f')} %  RMSE {_num(m['rmse'], '.4g')}  "
                f"(mean predicted {_num(m['mean_pred'], '.4g')}, simulated {_num(m['mean_sim'], '.4g')})"
            )
    if "authors" in r:
        a = r["authors"]
        print(f"vs the authors' predictions ({a['ods_joined']} ODs joined):")
        for c in a["columns"]:
            print(
                f"  {c['column']:<28} ours {c['mean_ours']:10.4g}  authors {c['mean_authors']:10.4g}  "
                f"pearson {c['pearson'] if c['pearson'] is None else round(c['pearson'], 3)}"
            )


def _num(value: float | None, spec: str) -> str:
    """A metric, or "n/a" where it is undefined (no simulated OD with a positive value)."""
    return "n/a" if value is None else format(value, spec)
