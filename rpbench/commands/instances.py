"""``rpbench instances``: the citable instance library — list its sets, build, verify, export, prove optima.

``build SET`` regenerates a set from the data into a new folder and compares it with the set's packaged
manifest; ``verify SET [--dir DIR]`` checks a folder of a set's files against it (the committed S tier:
``instances/library/S``); ``export PATH... --format mps|lp|asn|edges`` writes instances for command-line
solvers; ``solu SET --dir DIR`` proves each instance's optimum with two exact presets of different
algorithms and writes the known-values lines.  instances/README.md.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from rpbench.backends import load_preset
from rpbench.bench.runner import IsolatedWorker
from rpbench.commands.args import TIME_LIMIT, add_data_arg, add_number_arg, check_numbers
from rpbench.commands.checks import check_out_file, check_unique, write_out_file
from rpbench.commands.output import note, print_json
from rpbench.exceptions import ParameterError
from rpbench.files.digests import arrays_sha256
from rpbench.library.build import build_set
from rpbench.library.export import FORMATS, export_formats, write_model
from rpbench.library.manifest import (
    MANIFEST,
    packaged_manifest,
    read_manifest,
    same_files,
    verify_folder,
    write_manifest,
)
from rpbench.library.prove import prove, with_time_limit
from rpbench.library.sets import SETS, instance_set
from rpbench.model import Model
from rpbench.model.instances import find_instances, load_instances
from rpbench.results import store
from rpbench.results.solu import write_solu
from rpbench.version import __version__

#: Where a set's files are looked for without --dir: the committed tier in a checkout, else the default
#: place `build` writes to.
COMMITTED = Path("instances") / "library"
DEFAULT_INSTANCES_FOLDER = Path("rpbench-instances")
#: Exact presets of different algorithms (HiGHS; Jonker-Volgenant and sparse blossom; OR-Tools; Blossom V).
PROVERS = ("highs", "matching", "blossom-v", "ortools")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "instances",
        help="the instance library: list, build, verify, export, prove optima",
        description="The library of frozen dispatch models in size tiers (instances/README.md).",
    )
    verbs = p.add_subparsers(dest="verb", metavar="VERB", required=True)
    lst = verbs.add_parser("list", help="the sets, their tiers and sizes")
    lst.add_argument("--json", action="store_true", help="print one JSON object")
    lst.set_defaults(handler=_run_list)

    build = verbs.add_parser("build", help="regenerate a set from the data and compare it with its manifest")
    build.add_argument("set", metavar="SET", help=f"one of {', '.join(SETS)}")
    build.add_argument(
        "--out", default=None, metavar="DIR", help=f"new folder (default ./{DEFAULT_INSTANCES_FOLDER}/SET)"
    )
    add_data_arg(build)
    build.add_argument(
        "--write-manifest",
        metavar="FILE",
        default=None,
        help="also write the built manifest to FILE (to record a new reference manifest)",
    )
    build.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    build.set_defaults(handler=_run_build)

    verify = verbs.add_parser("verify", help="check a folder of a set's files against the set's manifest")
    verify.add_argument("set", metavar="SET", help=f"one of {', '.join(SETS)}")
    verify.add_argument(
        "--dir",
        default=None,
        metavar="DIR",
        help="the folder (default: instances/library/SET, else ./rpbench-instances/SET)",
    )
    verify.set_defaults(handler=_run_verify)

    export = verbs.add_parser("export", help="write instances as MPS, LP, DIMACS assignment or an edge list")
    export.add_argument("paths", nargs="+", metavar="PATH", help="instance files or folders")
    export.add_argument(
        "--format",
        default="mps",
        help=f"comma-separated, of {', '.join(FORMATS)} (default mps); each instance in those its structure has",
    )
    export.add_argument("--out", required=True, metavar="DIR", help="new folder for the files")
    export.set_defaults(handler=_run_export)

    solu = verbs.add_parser("solu", help="prove each instance's optimum with several exact presets: .solu lines")
    solu.add_argument("paths", nargs="+", metavar="PATH", help="instance files or folders")
    solu.add_argument(
        "--presets",
        default=",".join(PROVERS),
        help="exact presets to solve with, in order, until two different algorithms agree; the installed ones "
        "are used (default %(default)s)",
    )
    add_number_arg(solu, "--time-limit", TIME_LIMIT, default=600.0, metavar="S", help="per solve (default 600)")
    solu.add_argument("--out", required=True, metavar="FILE", help="the .solu file to write (new)")
    solu.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")
    solu.set_defaults(handler=_run_solu)


def _run_export(args: argparse.Namespace) -> int:
    formats = [f.strip().lower() for f in args.format.split(",") if f.strip()]
    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise ParameterError(f"--format {args.format!r}: expected one or more of {', '.join(FORMATS)}")
    check_unique(f"--format {args.format!r}", formats)
    store.check_new_folder(args.out)
    models, _ = load_instances(args.paths)
    written = 0
    with store.new_results_folder(args.out, "export") as (tmp, final):
        for model in models:
            for fmt in formats:
                if fmt in export_formats(model):
                    write_model(model, tmp / f"{model.name.replace('/', '_')}.{fmt}", fmt)
                    written += 1
    print(f"{written} file(s) of {len(models)} instance(s) written to {final}")
    return 0


def _run_solu(args: argparse.Namespace) -> int:
    check_numbers(args)
    out = check_out_file(args.out, "--out")
    if out.exists():
        raise ParameterError(f"--out {args.out!r} already exists; rpbench never overwrites it")
    names = [n.strip() for n in args.presets.split(",") if n.strip()]
    check_unique(f"--presets {args.presets!r}", names)
    presets = [load_preset(n) for n in names]
    installed = [p for p in presets if p.is_installed()]
    models = _distinct_by_name(list(args.paths))
    entries, lines = {}, []
    counts: dict[str, int] = {}
    # each preset solves in its own process, killed at twice its time limit plus 30 s (as rpbench bench)
    hard = 2 * args.time_limit + 30
    workers = {p.name: IsolatedWorker(with_time_limit(p, args.time_limit), hard) for p in installed}
    try:
        for k, model in enumerate(models):
            if not args.no_progress:
                note(f"{k + 1}/{len(models)} {model.name} ({model.n_cols:,} columns)")
            proof = prove(model, installed, args.time_limit, workers=workers)
            entries[model.name] = proof.known
            counts[proof.known.kind] = counts.get(proof.known.kind, 0) + 1
            lines.append(f"{model.name}: {', '.join(proof.algorithms) or 'no proof'} ({'; '.join(proof.answers)})")
    finally:
        for worker in workers.values():
            worker.close()
    header = [
        f"rpbench {__version__} known values of {len(models)} instances (objective in model units, maximised)",
        "=opt=: proven by at least two different algorithms (presets tried in order: "
        f"{', '.join(p.name for p in installed)})",
        "=best=: proven by one algorithm only, or the best value found within the time limit",
        *lines,
    ]
    write_out_file(out, "--out", lambda path: write_solu(path, entries, header))
    summary = ", ".join(f"{counts[k]} ={k}=" for k in sorted(counts))
    print(f"{len(models)} instances: {summary}; written to {out}")
    return 0


#: The member of an instance file that records where it comes from, not what the model is.
MODEL_META = ("meta_json",)


def _distinct_by_name(paths: list[str | Path]) -> list[Model]:
    """The models of the instance files under ``paths``, named by their file stems as a ``.solu`` file names
    them: files of one name in two folders (a tier's instances shared with another) must hold the same
    model (their metadata name their own tier), and are proved once."""
    files = list(dict.fromkeys(find_instances(paths)))
    models, _ = load_instances(paths)  # in the order of ``files``
    seen: dict[str, Path] = {}
    out = []
    for f, model in zip(files, models, strict=True):
        if f.stem in seen:
            if arrays_sha256(f, skip=MODEL_META) != arrays_sha256(seen[f.stem], skip=MODEL_META):
                raise ParameterError(
                    f"two different instances are named {f.stem!r}: {str(seen[f.stem])!r} and {str(f)!r}; "
                    "a .solu file needs one value per name"
                )
            continue
        seen[f.stem] = f
        out.append(model.renamed(f.stem))
    return out


def _reference(name: str) -> dict:
    reference = packaged_manifest(name)
    if reference is None:
        raise ParameterError(
            f"instance set {name!r} has no reference manifest yet: build it and record one with --write-manifest"
        )
    return reference


def _run_list(args: argparse.Namespace) -> int:
    rows = []
    for name, spec in SETS.items():
        ref = packaged_manifest(name)
        rows.append(
            {
                "set": name,
                "tier": spec.tier,
                "instances": len(ref["instances"]) if ref else None,
                "largest_cols": max((e["cols"] for e in ref["instances"]), default=0) if ref else None,
                "committed": spec.committed,
                "needs_data": spec.needs_data,
                "description": spec.description,
            }
        )
    if args.json:
        print_json({"sets": rows})
        return 0
    print(f"{'set':<10} {'tier':<4} {'instances':>9} {'largest':>10}  where")
    for r in rows:
        where = f"committed: instances/library/{r['set']}" if r["committed"] else f"rpbench instances build {r['set']}"
        n = "?" if r["instances"] is None else f"{r['instances']}"
        cols = "?" if r["largest_cols"] is None else f"{r['largest_cols']:,}"
        print(f"{r['set']:<10} {r['tier']:<4} {n:>9} {cols:>10}  {where}")
        print(f"{'':<16}{r['description']}")
    return 0


def _run_build(args: argparse.Namespace) -> int:
    spec = instance_set(args.set)
    reference = packaged_manifest(spec.name)
    out = args.out if args.out is not None else str(DEFAULT_INSTANCES_FOLDER / spec.name)
    store.check_new_folder(out)
    if args.write_manifest is not None and Path(args.write_manifest).exists():
        raise ParameterError(f"--write-manifest {args.write_manifest!r} already exists; rpbench never overwrites it")
    started = time.perf_counter()
    progress = None if args.no_progress else note
    with store.new_results_folder(out, spec.name) as (tmp, final):
        manifest = build_set(spec, tmp, data_dir=args.data, progress=progress)
        write_manifest(tmp / MANIFEST, manifest)
    seconds = time.perf_counter() - started
    if args.write_manifest is not None:
        write_manifest(Path(args.write_manifest), manifest)
    print(f"{len(manifest['instances'])} instances of set {spec.name} written to {final} in {seconds:.1f} s")
    if reference is None:
        print(f"set {spec.name} has no reference manifest to compare with")
        return 0
    return _report(final, reference)


def _run_verify(args: argparse.Namespace) -> int:
    spec = instance_set(args.set)
    reference = _reference(spec.name)
    folder = Path(args.dir) if args.dir is not None else _default_dir(spec.name)
    if not folder.is_dir():
        raise ParameterError(
            f"instance folder {str(folder)!r} does not exist (build it: rpbench instances build {spec.name})"
        )
    return _report(folder, reference)


def _default_dir(name: str) -> Path:
    committed = COMMITTED / name
    return committed if committed.is_dir() else DEFAULT_INSTANCES_FOLDER / name


def _report(folder: Path, reference: dict) -> int:
    problems = verify_folder(folder, reference)
    same, total = same_files(folder, reference)
    if (folder / MANIFEST).is_file():
        theirs = read_manifest(folder)
        if (
            json.dumps(theirs.get("instances"), sort_keys=True)
            != json.dumps(reference.get("instances"), sort_keys=True)
            and not problems
        ):
            problems.append(f"{MANIFEST}: differs from the reference manifest (sizes, tags or provenance)")
    if problems:
        for line in problems:
            print(f"FAILED {line}")
        print(f"{folder}: {len(problems)} difference(s) from the manifest of set {reference['set']}")
        return 1
    print(
        f"{folder}: OK, the {total} instances of set {reference['set']} hold the manifest's arrays "
        f"({same} of {total} files identical byte for byte)"
    )
    return 0
