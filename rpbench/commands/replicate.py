"""``rpbench replicate``: the authors' simulator semantics, the ablation and rpbench's engine, beside the
authors' committed outputs and the paper's printed values (docs/replication.md)."""

from __future__ import annotations

import argparse
import sys

import pandas as pd

from rpbench.backends.presets import load_preset
from rpbench.commands.args import add_data_arg, add_offline_arg
from rpbench.commands.checks import check_date_list, check_out_name, check_unique
from rpbench.commands.output import command_line, print_json
from rpbench.data import available_peak_dates
from rpbench.data.first_run import ensure_data_dir
from rpbench.exceptions import ParameterError
from rpbench.results import layout
from rpbench.results import store as results
from rpbench.results.layout import engine_folder
from rpbench.results.store import check_new_folder
from rpbench.scenarios.request import parse_dates

REPLICATED_STRATEGIES = "np,mb,rtv,fl-nd,fl"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replicate",
        help="the authors' simulator semantics, an ablation, beside their outputs",
        description="Run the authors' simulator semantics (rpbench.replication, every mechanism a "
        "switch), the ablation (one mechanism off at a time, fixed order) and rpbench's "
        "own engine on the authors' exact input, and print them beside the authors' "
        "committed outputs and the paper's printed Table 2.",
    )
    add_data_arg(p)
    add_offline_arg(p)
    p.add_argument("--date", default=None, help="one date (default 2017-05-01)")
    p.add_argument("--dates", default=None, metavar="A..B|A,B,...", help="several dates, e.g. 2017-05-01..2017-05-14")
    p.add_argument(
        "--strategies",
        default=REPLICATED_STRATEGIES,
        help=f"comma-separated subset of {REPLICATED_STRATEGIES} (default all)",
    )
    p.add_argument("--solver", default="highs", help="solver preset for every round (default highs)")
    p.add_argument(
        "--ablation",
        default="single",
        metavar="MODE",
        help="single (default): one mechanism off at a time; cumulative: mechanisms 1..k off, k = 1..8 "
        "(the steps add up to the whole difference); both; none",
    )
    p.add_argument("--no-ablation", action="store_true", help="same as --ablation none")
    p.add_argument("--no-rpbench", action="store_true", help="skip rpbench's own engine")
    p.add_argument("--out", default=None, help="results folder to create (default ./rpbench-runs/<stamp>_replicate)")
    p.add_argument(
        "--json",
        action="store_true",
        help='print {"runs": [{"engine", "strategy", "date", "pairing_ratio", "total_saving_km", '
        '"response_rate", ...}], "criterion": {...}}',
    )
    p.add_argument("--progress", action="store_true", help="one line on stderr per run")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    # the authors' engine and the replication's report: only when replicating
    from rpbench.harness.replicate import parse_strategies, replicate
    from rpbench.replication.folder import file_manifest, write_engine_folder
    from rpbench.replication.reference import has_committed
    from rpbench.replication.report import criterion, markdown
    from rpbench.replication.switches import steps_for
    from rpbench.report.html import write_html

    strategies = parse_strategies(args.strategies)
    check_unique(
        f"--strategies {args.strategies!r}", [s.strip().lower() for s in args.strategies.split(",") if s.strip()]
    )
    if args.date and args.dates:
        raise ParameterError("give --date or --dates, not both")
    check_date_list("--dates", args.dates)
    mode = "none" if args.no_ablation else args.ablation
    steps_for(mode)  # a bad --ablation is one line before anything runs
    preset = load_preset(args.solver)
    check_out_name(args.out, inner=["records", "2017-05-01_fl-nd_rpbench", "runs", "fl-nd", "trajectories.npz"])
    check_new_folder(args.out)  # before the data folder is fetched
    data_dir = ensure_data_dir(args.data, what="rpbench replicate", offline=args.offline)
    have = available_peak_dates(data_dir)
    dates = parse_dates(args.dates or args.date or "2017-05-01", have)
    check_unique(f"--dates {args.dates!r}", dates)
    own: list = []  # rpbench's own engine's runs, kept as results folders that rpbench check verifies
    result = replicate(
        data_dir,
        dates,
        strategies,
        preset,
        ablation=mode,
        rpbench_engine=not args.no_rpbench,
        progress=args.progress,
        keep=lambda *run: own.append(run),
    )
    frame = pd.DataFrame(result.rows)
    meta = {
        "kind": "replication",
        "command": command_line(),
        "dates": dates,
        "dates_text": f"{dates[0]} .. {dates[-1]}" if len(dates) > 1 else dates[0],
        "strategies": strategies,
        "preset": preset.name,
        "ablation": mode,
        "version": None,
        **results.environment(),
    }
    meta["version"] = meta["versions"]["rpbench"]
    # A fetched data folder has no committed outputs: the criterion is then not evaluated, not failed.
    reference = has_committed(data_dir)
    meta["reference_outputs"] = reference  # the checker re-renders report.md as it was rendered
    text = markdown(frame, meta, reference=reference)
    default = f"{results.timestamp()}_replicate"
    with results.new_results_folder(args.out, default) as (folder, final):
        results.write_json(folder / "meta.json", meta)
        frame.to_csv(folder / "runs.csv", index=False)
        (folder / "report.md").write_text(text)
        write_html(folder, name=final.name)
        (folder / layout.RECORDS_DIR).mkdir()
        for (date, strategy, engine), outcome in result.outcomes.items():
            if engine != "authors":
                continue  # records of the authors' full semantics only (size)
            rec = outcome.passengers()
            orders = outcome.scenario_orders
            rec.insert(0, "order_id", orders.order_id[rec["order"].to_numpy()])
            rec["request_s"] = orders.request_s[rec["order"].to_numpy()]
            rec["patience_s"] = outcome.patience_s[rec["order"].to_numpy()]
            rec["solo_m"] = outcome.solo_m[rec["order"].to_numpy()]
            partner = rec["partner"].to_numpy()
            rec["partner"] = [int(orders.order_id[p]) if p >= 0 else -1 for p in partner]
            rec.drop(columns=["order"]).to_csv(layout.records_file(folder, date, strategy, engine), index=False)
        for date, strategy, engine, strategy_run, scenario in own:
            dest = engine_folder(folder, date, strategy, engine)
            write_engine_folder(dest, scenario, strategy_run, preset, meta["command"])
        # Last: the SHA-256 of every file written, so that an edited, deleted or added file fails rpbench check.
        results.write_json(folder / "meta.json", {**meta, "manifest": {"files": file_manifest(folder)}})
    if args.json:
        print_json({"runs": result.rows, "criterion": criterion(frame, reference=reference), "folder": str(final)})
    else:
        print(text)
        print(f"rpbench: wrote {final}", file=sys.stderr)
    return 0
