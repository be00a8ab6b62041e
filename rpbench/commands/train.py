"""``rpbench train vf``: learn a value model V(cell, time bin) on training days and write it to a folder.

The training runs are the scenario's generator on ``--dates`` x ``--seeds`` (MB, then with
``--opt iterations=N`` VF's own policy); the folder it writes is what ``--opt vf.model=FOLDER`` loads.
Without ``--out`` the model goes to ``./rpbench-runs/vf-model_...``.  docs/value-function.md.
"""

from __future__ import annotations

import argparse
import time

from rpbench.commands.args import add_scenario_args, check_numbers, progress_of, scenario_request
from rpbench.commands.checks import check_date_list
from rpbench.commands.output import note, print_json
from rpbench.exceptions import ParameterError
from rpbench.harness.training import train
from rpbench.results import store
from rpbench.scenarios.registry import scenario_spec
from rpbench.scenarios.request import ScenarioRequest
from rpbench.strategies.value import ValueFunction, ValueOptions
from rpbench.valuefn.model import save_model
from rpbench.valuefn.training import training_record

#: What the --dates, --seeds and --out arguments give: not options of a training.
_NOT_TRAINING_OPTIONS = {"model": "--out", "train_dates": "--dates", "train_seeds": "--seeds"}
DEFAULT_DATES = ValueOptions().train_dates


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        allow_abbrev=False,  # --date and --seed are not --dates and --seeds: no single draw to train on
        help="learn a value model for the vf strategy from simulated training days",
        description="Learn the tabular value V(cell, time bin) of a vacant vehicle by policy evaluation of MB "
        "(Xu et al., KDD 2018) on training days, and write it as a model folder for --opt vf.model=FOLDER.",
    )
    p.add_argument("what", choices=("vf",), help="what to train (vf: the value-function strategy's model)")
    add_scenario_args(p, one_draw=False)
    p.add_argument("--dates", default=None, help=f"training days, A..B or A,B,... (default {DEFAULT_DATES})")
    p.add_argument(
        "--seeds",
        default=",".join(str(s) for s in ValueOptions().train_seeds),
        help="sample seeds of the training runs, comma-separated (default %(default)s)",
    )
    p.add_argument(
        "--opt",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a training option of vf (cell_m, bin_s, discount, method, learning_rate, epochs, iterations, "
        "order_rule; see `rpbench list`), repeatable",
    )
    # the single-draw options of other commands, refused in one line naming the list to give instead
    p.add_argument("--date", dest="single_date", default=None, help=argparse.SUPPRESS)
    p.add_argument("--seed", dest="single_seed", default=None, help=argparse.SUPPRESS)
    p.add_argument("--out", default=None, metavar="FOLDER", help="the new model folder")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    p.set_defaults(handler=_run)


def _run(args: argparse.Namespace) -> int:
    if args.single_date is not None:
        raise ParameterError("--date: a model is trained on several days, give --dates A..B or A,B,...")
    if args.single_seed is not None:
        raise ParameterError("--seed: a model is trained on a list of sample seeds, give --seeds S1,S2,...")
    check_numbers(args)
    check_date_list("--dates", args.dates)
    options = _options(args.opt, args.seeds)
    store.check_new_folder(args.out)
    request = scenario_request(args)
    scenarios = []
    dates = request.dates(args.dates or DEFAULT_DATES) if _has_dates(request) else [None]
    if args.dates is not None and dates == [None]:
        raise ParameterError(f"--dates: scenario {request.name!r} has no dates to choose from")
    for day in dates:
        for seed in options.train_seeds:
            scenarios.append(request.replace(date=day, seed=seed).build())
    started = time.perf_counter()
    model = train(
        scenarios,
        options.settings(),
        next_policy=ValueFunction(options).next_policy,
        progress=progress_of(args),
    )
    seconds = time.perf_counter() - started
    with store.new_results_folder(args.out, f"vf-model_{store.timestamp()}") as (tmp, final):
        tmp.rmdir()  # save_model creates the folder it writes
        digest = save_model(model, tmp)
    record = training_record(scenarios, options.settings())
    summary = {
        "model": str(final),
        "digest": digest,
        "training_runs": len(scenarios),
        "transitions": int(model.visits.sum()),
        "visited_states": int((model.visits > 0).sum()),
        "states": int(model.visits.size),
        "train_s": round(seconds, 3),
        "training": record,
    }
    if args.json:
        print_json(summary)
    else:
        runs = ", ".join(r["date"] or f"seed {r['seed']}" for r in record["runs"])
        note(f"trained on {len(scenarios)} runs of {record['scenario']} ({runs}) in {seconds:.1f} s")
        print(
            f"value model {digest[:12]}: {summary['transitions']:,} transitions, {summary['visited_states']:,} of "
            f"{summary['states']:,} states visited\nwritten to {final}  (use: --opt vf.model={final})"
        )
    return 0


def _options(items: list[str], seeds: str) -> ValueOptions:
    raw: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip().removeprefix("vf.")
        if not sep:
            raise ParameterError(f"--opt {item!r}: expected NAME=VALUE")
        if name in _NOT_TRAINING_OPTIONS:
            raise ParameterError(f"--opt {name}: give {_NOT_TRAINING_OPTIONS[name]} instead")
        if name in raw:
            raise ParameterError(f"--opt {name} is given twice; give it once")
        raw[name] = value
    raw["train_seeds"] = seeds
    return ValueOptions.parse("vf", raw)


def _has_dates(request: ScenarioRequest) -> bool:
    return scenario_spec(request.name).dates is not None
