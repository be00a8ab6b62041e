"""``rpbench bench``: time every solver preset on the same models.

The models are snapshot instance files (``rpbench bench instances/examples``,
files or folders searched recursively) and/or seeded synthetic models
(``--synthetic``).  One row per (model, preset): status, objective, build /
solve / extract times, and whether the objective equals the proven optimum
of the other presets and of the run the instance was frozen from (exit
status 1 on any disagreement).  A preset that hits its
time limit reports ``time_limit``; one that overruns the hard timeout is
killed and reports ``killed``.
"""

from __future__ import annotations

import argparse
import shlex
import sys

from rpbench.backends.presets import load_preset, preset_names
from rpbench.bench.runner import format_table, run_benchmark
from rpbench.bench.synthetic import SUITES, suite
from rpbench.commands._common import (
    SEED,
    TIME_LIMIT,
    add_number_arg,
    check_numbers,
    check_out_file,
    check_unique,
    command_line,
    note,
    print_json,
    write_out_file,
)
from rpbench.exceptions import ParameterError
from rpbench.instances import load_instances
from rpbench.model import OBJECTIVES, Structure
from rpbench.results.html.bench import write_bench_html
from rpbench.results.plots import bench_figure
from rpbench.strategies.options import Range

#: About the default hard timeout (2 x limit + 30 s) of the longest time limit a preset may set.
HARD_TIMEOUT = Range(0.0, 2 * TIME_LIMIT.high, "s", low_open=True)
#: The fastest of more than 100 runs of one solve tells nothing the fastest of 100 does not.
REPEAT = Range(1, 100, integer=True)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="time every solver preset on the same models",
        description="Time every installed solver preset on the same decision models, build and "
        "solve apart, and cross-check their objectives.",
    )
    p.add_argument(
        "paths",
        nargs="*",
        metavar="PATH",
        help="instance files (.npz) or folders holding them, e.g. instances/examples",
    )
    p.add_argument(
        "--synthetic", action="store_true", help="benchmark seeded synthetic models shaped like rpbench's (see --sizes)"
    )
    p.add_argument(
        "--sizes",
        default="default",
        choices=sorted(SUITES),
        help="synthetic model set (default: default = assignment 20x100 .. 2000x5000, "
        "pairing 2,000 and 50,000 orders, two trip packings)",
    )
    p.add_argument(
        "--objectives",
        default="weight",
        help="pairing objectives, comma-separated: weight (Oracle-1), cardinality_then_weight "
        "(Oracle-2) (default: weight)",
    )
    p.add_argument(
        "--structures",
        default=None,
        metavar="LIST",
        help="only models of these structures, comma-separated: assignment, trip_packing, pairing",
    )
    add_number_arg(p, "--seed", SEED, default=0, help="seed of the synthetic models (default 0)")
    p.add_argument(
        "--solver",
        action="append",
        default=None,
        metavar="NAME",
        help="preset to run (repeatable; default: every installed preset)",
    )
    add_number_arg(
        p,
        "--time-limit",
        TIME_LIMIT,
        metavar="S",
        help="per-solve time limit for every preset (default: each preset's own)",
    )
    p.add_argument(
        "--preset-time-limit",
        action="append",
        default=[],
        metavar="NAME=S",
        help="per-solve time limit of one preset, e.g. pyomo-highs=30 (repeatable)",
    )
    add_number_arg(
        p,
        "--hard-timeout",
        HARD_TIMEOUT,
        metavar="S",
        help="kill a solve after S seconds (default: 2 x its time limit + 30)",
    )
    add_number_arg(p, "--repeat", REPEAT, default=3, help="runs per solve; the fastest is kept (default 3)")
    p.add_argument("--no-isolate", dest="isolate", action="store_false", help="solve in this process (no hard timeout)")
    p.add_argument("--csv", metavar="FILE", default=None, help="also write the table as CSV")
    p.add_argument("--plot", metavar="PNG", default=None, help="also plot solver time against model size")
    p.add_argument(
        "--html",
        metavar="PAGE",
        default=None,
        help="also write one self-contained interactive page: per-preset shifted geometric means, the "
        "performance profile, times against model size, every solve",
    )
    p.add_argument("--json", action="store_true", help="print the table as JSON records")
    p.set_defaults(handler=run)


def _limits(items: list[str], run: list[str]) -> dict[str, float]:
    """``--preset-time-limit NAME=S`` items: each a preset that runs (``run``), given once, S in range."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ParameterError(f"--preset-time-limit {item!r}: expected NAME=SECONDS, e.g. pyomo-highs=30")
        if name not in run:
            raise ParameterError(
                f"--preset-time-limit {item!r}: preset {name!r} is not benchmarked (presets: {', '.join(run)})"
            )
        if name in out:
            raise ParameterError(f"--preset-time-limit gives preset {name!r} twice; give it once")
        out[name] = TIME_LIMIT.check("--preset-time-limit", value.strip(), shlex.quote(item))
    return out


def run(args: argparse.Namespace) -> int:
    check_numbers(args)  # before any model is built or loaded
    if not args.synthetic and not args.paths:
        raise ParameterError(
            "nothing to benchmark: name instance files or folders (e.g. instances/examples) and/or pass --synthetic"
        )
    objectives = tuple(o.strip() for o in args.objectives.split(",") if o.strip())
    bad = [o for o in objectives if o not in OBJECTIVES]
    if bad or not objectives:
        raise ParameterError(
            f"--objectives {args.objectives!r}: expected a comma-separated subset of {', '.join(OBJECTIVES)}"
        )
    if args.hard_timeout is not None and not args.isolate:
        raise ParameterError("--hard-timeout kills an isolated solve; --no-isolate solves in this process, without one")
    # output files checked before benchmarking: a bad path must not cost the run
    csv_out = check_out_file(args.csv, "--csv") if args.csv else None
    plot_out = check_out_file(args.plot, "--plot") if args.plot else None
    html_out = check_out_file(args.html, "--html") if args.html else None
    check_unique("--solver", args.solver or [])
    presets = None if args.solver is None else [load_preset(name) for name in args.solver]  # fail before building
    limits = _limits(args.preset_time_limit, preset_names() if presets is None else [p.name for p in presets])
    wanted = None
    if args.structures is not None:  # checked before the (slow) synthetic suite is built
        wanted = {x.strip() for x in args.structures.split(",") if x.strip()}
        known = {st.value for st in Structure}
        if not wanted or wanted - known:
            raise ParameterError(
                f"--structures {args.structures!r}: expected a comma-separated subset of {', '.join(sorted(known))}"
            )
    models, recorded = load_instances(args.paths) if args.paths else ([], {})
    if args.synthetic:
        note(f"building the {args.sizes!r} synthetic models (seed {args.seed}) ...")
        models += suite(args.sizes, seed=args.seed, objectives=objectives)
    if wanted is not None:
        models = [m for m in models if m.structure.value in wanted]
        if not models:
            raise ParameterError(f"no model of structure {args.structures!r} to benchmark")
    table = run_benchmark(
        models,
        presets,
        time_limit_s=args.time_limit,
        time_limits=limits,
        repeat=args.repeat,
        isolate=args.isolate,
        hard_timeout_s=args.hard_timeout,
        progress=None if args.json else note,
        recorded=recorded,
    )
    if csv_out is not None:
        write_out_file(csv_out, "--csv", lambda tmp: table.to_csv(tmp, index=False))
    if plot_out is not None:
        title = f"rpbench bench: {len(models)} models x {table['preset'].nunique()} presets (time of proven optima)"
        write_out_file(plot_out, "--plot", lambda tmp: bench_figure(table, tmp, title))
    if html_out is not None:
        what = f"{len(models)} models x {table['preset'].nunique()} presets"
        write_out_file(html_out, "--html", lambda tmp: write_bench_html(table, tmp, what, command_line()))
    if args.json:
        print_json(table.astype(object).where(table.notna(), None).to_dict(orient="records"))
    else:
        print(format_table(table))
    if (table["agrees"] == False).any():  # noqa: E712  (pandas boolean with missing values)
        print("rpbench: presets disagree on a proven optimum (see the rows marked NO)", file=sys.stderr)
        return 1
    return 0
