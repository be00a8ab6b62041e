"""``rpbench bench``: time every solver preset on the same models, and summarise as the field reports.

The models are snapshot instance files (``rpbench bench instances/examples``,
files or folders searched recursively) and/or seeded synthetic models
(``--synthetic``).  One row per (model, preset): status, objective, build /
solve / extract times (the fastest of ``--repeat`` runs, and their spread),
and a verdict (:func:`rpbench.bench.runner.verdict`): ``optimal``, ``wrong``
(against the known values of ``--solu FILE``, a folder's ``rpbench.solu``,
or another preset's proven optimum; exit status 1), ``time_limit``,
``memory_limit`` (``--memory-limit``), ``error`` or ``killed`` (the hard
timeout).  Then one line per (tier, preset) (:mod:`rpbench.report.bench`):
instances solved, the shifted geometric mean of the time with unsolved
instances at the time limit, its ratio to the best preset.  ``--out FOLDER``
writes all of it with the performance profile, the machine and the library
versions, and a report.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.backends.presets import load_preset, preset_names
from rpbench.bench.runner import BenchSpec, format_table, run_benchmark
from rpbench.bench.synthetic import SUITES, suite
from rpbench.commands.args import SEED, TIME_LIMIT, add_number_arg, check_numbers, progress_of
from rpbench.commands.checks import check_out_file, check_unique, write_out_file
from rpbench.commands.output import command_line, note, print_json
from rpbench.exceptions import ParameterError
from rpbench.library.manifest import library_names
from rpbench.model import OBJECTIVES, Structure
from rpbench.model.instances import find_instances, load_instances
from rpbench.options import Range
from rpbench.report.bench import NO_TIER, SHIFT_S, SHIFTS, format_summary, solver_environment, summarise, write_outputs
from rpbench.report.html.bench import write_bench_html
from rpbench.report.plots import bench_figure
from rpbench.results.solu import Known, check_names, read_solu, write_solu
from rpbench.results.store import check_new_folder, new_results_folder, write_json

#: About the default hard timeout (2 x limit + 30 s) of the longest time limit a preset may set.
HARD_TIMEOUT = Range(0.0, 2 * TIME_LIMIT.high, "s", low_open=True)
#: The fastest of more than 100 runs of one solve tells nothing the fastest of 100 does not.
REPEAT = Range(1, 100, integer=True)
#: A worker's address space, in GB of 2**30 bytes.
MEMORY_LIMIT = Range(0.0, 65536.0, "GB", low_open=True)
#: The shift of the shifted geometric mean (0: the plain geometric mean).
SHIFT = Range(0.0, 3600.0, "s")
#: The known-values file a folder of instances may hold at its top, used unless --solu names one.
SOLU_NAME = "rpbench.solu"
_SHIFTS_TEXT = ", ".join(f"{k} {v:g} s" for k, v in SHIFTS.items() if k != NO_TIER) + f", others {SHIFT_S:g} s"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="time every solver preset on the same models",
        description="Time every installed solver preset on the same decision models, build and "
        "solve apart; check every answer against the other presets and the known values (--solu), and "
        "summarise per preset: instances solved, shifted geometric mean of the time, performance profile.",
    )
    add_model_args(p)
    add_solve_args(p)
    add_judging_args(p)
    add_output_args(p)
    p.set_defaults(handler=_run)


def add_model_args(p: argparse.ArgumentParser) -> None:
    """What is benchmarked: instance files or folders, or seeded synthetic models."""
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


def add_solve_args(p: argparse.ArgumentParser) -> None:
    """How each model is solved: the presets, their time limits, repeats, and the worker that runs them."""
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
    add_number_arg(
        p,
        "--memory-limit",
        MEMORY_LIMIT,
        metavar="GB",
        help="cap each isolated worker's address space at GB (2**30 bytes; RLIMIT_AS, which counts reserved "
        "as well as used memory: leave headroom); a solve over it reports memory_limit (default: none)",
    )
    add_number_arg(
        p,
        "--repeat",
        REPEAT,
        default=3,
        help="runs per solve; the fastest is kept, with the min / median / max of all (default 3)",
    )
    p.add_argument(
        "--no-isolate",
        dest="isolate",
        action="store_false",
        help="solve in this process (no hard timeout, no memory limit)",
    )


def add_judging_args(p: argparse.ArgumentParser) -> None:
    """What the answers and times are judged by: the known values and the shifted geometric mean's shift."""
    p.add_argument(
        "--solu",
        metavar="FILE",
        default=None,
        help="known values (.solu: =opt=, =best=, =bound= NAME VALUE, =inf=, =unkn= NAME) to check every answer "
        f"against (default: the {SOLU_NAME} at the top of a folder named, if any)",
    )
    add_number_arg(
        p,
        "--shift",
        SHIFT,
        metavar="S",
        help=f"shift of the shifted geometric mean, for every tier (default per tier: {_SHIFTS_TEXT})",
    )


def add_output_args(p: argparse.ArgumentParser) -> None:
    """Where the results go besides the terminal table: a folder, CSV, a plot, a page, JSON."""
    p.add_argument(
        "--no-progress", action="store_true", help="no progress bar (there is none when stderr is not a terminal)"
    )
    p.add_argument(
        "--out",
        metavar="FOLDER",
        default=None,
        help="also write a new folder: results.csv, summary.csv, profile.csv, profile.png/.svg, environment.json, "
        "report.md",
    )
    p.add_argument(
        "--csv",
        metavar="FILE",
        default=None,
        help="also write the table as CSV (and the machine and versions beside it, FILE's stem + .environment.json)",
    )
    p.add_argument("--plot", metavar="PNG", default=None, help="also plot solver time against model size")
    p.add_argument(
        "--html",
        metavar="PAGE",
        default=None,
        help="also write one self-contained interactive page: per-preset shifted geometric means, the "
        "performance profile, times against model size, every solve",
    )
    p.add_argument("--json", action="store_true", help="print the table as JSON records")


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


def _run(args: argparse.Namespace) -> int:
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
    if args.memory_limit is not None and not args.isolate:
        raise ParameterError("--memory-limit caps an isolated worker; --no-isolate solves in this process, without one")
    # output files checked before benchmarking: a bad path must not cost the run
    csv_out = check_out_file(args.csv, "--csv") if args.csv else None
    sidecar = check_out_file(str(_sidecar(csv_out)), "--csv") if csv_out is not None else None
    plot_out = check_out_file(args.plot, "--plot") if args.plot else None
    html_out = check_out_file(args.html, "--html") if args.html else None
    if args.out is not None:
        check_new_folder(args.out)
    check_unique("--solver", args.solver or [])
    presets = None if args.solver is None else [load_preset(name) for name in args.solver]  # fail before building
    limits = _limits(args.preset_time_limit, preset_names() if presets is None else [p.name for p in presets])
    wanted = None
    if args.structures is not None:  # checked before the (slow) synthetic suite is built
        wanted = {x.strip() for x in args.structures.split(",") if x.strip()}
        known_structures = {st.value for st in Structure}
        if not wanted or wanted - known_structures:
            raise ParameterError(
                f"--structures {args.structures!r}: expected a comma-separated subset of "
                f"{', '.join(sorted(known_structures))}"
            )
    models, recorded = load_instances(args.paths) if args.paths else ([], {})
    tiers = _tiers(args.paths, [m.name for m in models]) if args.paths else {}
    solu_files = [Path(args.solu)] if args.solu is not None else _folder_solus(args.paths)
    solus = _read_solus(solu_files, explicit=args.solu is not None)  # a bad line fails before any build
    if args.synthetic:
        note(f"building the {args.sizes!r} synthetic models (seed {args.seed}) ...")
        models += suite(args.sizes, seed=args.seed, objectives=objectives)
    known = _known(solus, [m.name for m in models])
    if wanted is not None:
        models = [m for m in models if m.structure.value in wanted]
        if not models:
            raise ParameterError(f"no model of structure {args.structures!r} to benchmark")
    spec = BenchSpec(
        presets,
        time_limit_s=args.time_limit,
        time_limits=limits,
        repeat=args.repeat,
        isolate=args.isolate,
        hard_timeout_s=args.hard_timeout,
        memory_limit_gb=args.memory_limit,
        recorded=recorded,
        known=known,
        tiers=tiers,
    )
    table = run_benchmark(models, spec, progress=progress_of(args))
    what = f"{len(models)} models x {table['preset'].nunique()} presets"
    settings = _settings(args, table, solu_files)
    env = solver_environment() if csv_out is not None or html_out is not None or args.out is not None else None
    if csv_out is not None and sidecar is not None:
        write_out_file(csv_out, "--csv", lambda tmp: table.to_csv(tmp, index=False))
        write_out_file(sidecar, "--csv", lambda tmp: write_json(tmp, {**(env or {}), "bench": settings}))
    if plot_out is not None:
        title = f"rpbench bench: {what} (time of proven optima)"
        write_out_file(plot_out, "--plot", lambda tmp: bench_figure(table, tmp, title))
    if html_out is not None:
        write_out_file(
            html_out,
            "--html",
            lambda tmp: write_bench_html(table, tmp, what, command_line(), shift=args.shift, env=env),
        )
    if args.out is not None:
        from rpbench.check.bench import KNOWN_FILE  # the checker's package: only for a --out folder

        with new_results_folder(args.out, "bench") as (tmp, final):
            used = {name: known[name] for name in sorted(known)}
            if used:  # the folder carries the values it was judged against: rpbench check re-judges with them
                write_solu(tmp / KNOWN_FILE, used, header=["the known values this benchmark was judged against"])
            known_file = KNOWN_FILE if used else None
            write_outputs(tmp, table, title=what, settings=settings, shift=args.shift, env=env, known_values=known_file)
        note(
            f"rpbench: wrote {final} (results.csv, summary.csv, profile.csv, profile.png, environment.json, report.md)"
        )
    if args.json:
        print_json(table.astype(object).where(table.notna(), None).to_dict(orient="records"))
    else:
        print(format_table(table))
        print()
        print(format_summary(summarise(table, args.shift)))
    wrong = int((table["verdict"] == "wrong").sum())
    if wrong:
        print(
            f"rpbench: {wrong} {'answer is' if wrong == 1 else 'answers are'} wrong (verdict wrong: against the "
            "known values or another preset's proven optimum)",
            file=sys.stderr,
        )
        return 1
    return 0


def _sidecar(csv: Path) -> Path:
    """The machine-and-versions file beside a ``--csv`` table: ``bench.csv`` -> ``bench.environment.json``."""
    return csv.with_name(f"{csv.stem}.environment.json")


def _tiers(paths: list[str], names: list[str]) -> dict[str, str]:
    """Each instance's tier (its metadata's ``tier``; :data:`~rpbench.bench.runner.NO_TIER` if none), by the
    names :func:`load_instances` gave (its models come in the order of the files it found)."""
    files = list(dict.fromkeys(find_instances([*paths])))
    if len(files) != len(names):  # load_instances reads each file once, in this order
        raise AssertionError("instance files and models do not line up")
    out = {}
    for f, name in zip(files, names, strict=True):
        with np.load(f, allow_pickle=False) as data:  # only the metadata member is read
            meta = json.loads(str(data["meta_json"])) if "meta_json" in data.files else {}
        tier = meta.get("tier") if isinstance(meta, dict) else None
        out[name] = tier if isinstance(tier, str) and tier.strip() else NO_TIER
    return out


def _folder_solus(paths: list[str]) -> list[Path]:
    """The known-values files at the top of the folders named (said on stderr)."""
    found = []
    for p in map(Path, dict.fromkeys(paths)):
        solu = p / SOLU_NAME
        if p.is_dir() and solu.is_file():
            note(f"rpbench: known values from {solu} (--solu FILE to use another)")
            found.append(solu)
    return found


def _read_solus(files: list[Path], *, explicit: bool) -> list[tuple[Path, dict[str, Known]]]:
    out = []
    for f in files:
        if explicit and not f.is_file():
            state = "is a folder" if f.is_dir() else "does not exist"
            raise ParameterError(f"--solu {str(f)!r} {state}; give a known-values (.solu) file")
        out.append((f, read_solu(f)))
    return out


def _known(solus: list[tuple[Path, dict[str, Known]]], names: list[str]) -> dict[str, Known]:
    """The known values of every file by instance name; each name must name an instance of ``names`` or of
    the library (a library-wide file judges any subset: the other lines are skipped, said on stderr), and
    one given in two files is an error."""
    known: dict[str, Known] = {}
    source: dict[str, Path] = {}
    library = library_names()
    for f, entries in solus:
        elsewhere = set(check_names(entries, names, f"known values {str(f)!r}", library))
        if elsewhere:
            skipped = f"{len(elsewhere)} of the {len(entries)} known values of {str(f)!r}"
            note(f"rpbench: {skipped} name library instances not benchmarked here")
        for name, k in entries.items():
            if name in elsewhere:
                continue
            if name in known:
                raise ParameterError(
                    f"instance {name!r} has known values in {str(source[name])!r} and {str(f)!r}; keep one"
                )
            known[name], source[name] = k, f
    return known


def _settings(args: argparse.Namespace, table: pd.DataFrame, solu_files: list[Path]) -> dict[str, Any]:
    """What the benchmark ran with, for environment.json and report.md."""
    limits = table.groupby("preset", sort=True)["time_limit_s"].first()
    return {
        "command": command_line(),
        "presets": sorted(set(table["preset"])),
        "time_limit_s": {str(k): (None if v != v else float(v)) for k, v in limits.items()},
        "hard_timeout_s": (args.hard_timeout or "2 x the time limit + 30") if args.isolate else None,
        "memory_limit_gb": args.memory_limit,
        "repeat": args.repeat,
        "isolate": args.isolate,
        "known_values": [str(f) for f in solu_files],
        "shift_s": args.shift if args.shift is not None else f"per tier: {_SHIFTS_TEXT}",
    }
