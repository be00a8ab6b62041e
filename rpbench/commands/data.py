"""``rpbench data fetch`` and ``rpbench data verify``: get a city's data folder on a fresh machine, check one.

``--city NAME`` picks the city (default Haikou; the cities with a registry,
:data:`rpbench.data.fetch.REGISTRY_FILES`); an unknown one is one line and
exit 2, before anything is read or written.  The pinned file lists and the
download logic are :mod:`rpbench.data.fetch`.
Summaries go to stdout (one JSON object with ``--json``), the progress bar
to stderr; a network error, a checksum mismatch, a body longer than the
registry's size and a full disk are each one line and exit 2.
Commands that need the data fetch it the same way by themselves when no
folder is found (:mod:`rpbench.data.first_run`).
"""

from __future__ import annotations

import argparse
import sys

from rpbench.commands.output import print_json
from rpbench.data.fetch import (
    MIRROR_CITY,
    REGISTRY_FILES,
    check_verified,
    fetch,
    registry_file,
    source_urls,
    verify_data,
)
from rpbench.exceptions import DataNotFoundError
from rpbench.files import paths
from rpbench.files.paths import (
    DATA_ENV,
    DATA_HOME_ENV,
    DATA_MIRROR_ENV,
    DEFAULT_CITY,
    city_label,
    data_home,
    fetch_command,
    fetched_data_dir,
    locate_data_dir,
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "data",
        help="download (fetch) or check (verify) a city's data folder (Haikou unless --city)",
        description="Download a city's data folder from its public sources at pinned commits "
        "(fetch), or check a data folder against the pinned checksums (verify).  "
        f"Cities: {', '.join(REGISTRY_FILES)} (--city NAME; default {DEFAULT_CITY}).",
    )
    p.set_defaults(handler=lambda args: _usage(p))
    actions = p.add_subparsers(dest="data_action", metavar="ACTION")

    f = actions.add_parser(
        "fetch",
        help="download every pinned data file, verify and store it",
        description="Download every data file rpbench needs from its public source at a "
        "pinned commit, check its SHA-256 and store it (gzipped where the data "
        "folder keeps it gzipped).  Files already present with the right content "
        "are skipped, so a second run downloads nothing and an interrupted one "
        "resumes.  Without --dest, rpbench then finds the folder by itself "
        "(see `rpbench list`).",
    )
    _add_city_arg(f, "whose data folder to fetch")
    f.add_argument(
        "--dest",
        metavar="DIR",
        default=None,
        help=f"folder to fill (default: the city's folder in the data home, {data_home()}/CITY, "
        f"e.g. {fetched_data_dir()}; ${DATA_HOME_ENV} moves the data home)",
    )
    f.add_argument(
        "--mirror",
        metavar="URL",
        default=None,
        help="fetch the stored file names from this copy of the city's data folder instead "
        f"(http(s)://, file:// or a local folder; default: ${DATA_MIRROR_ENV}, else the pinned sources); "
        f"{MIRROR_CITY} in it stands for the city's name, so one value serves every city "
        f"(e.g. https://host/data/{MIRROR_CITY}); content is still checked",
    )
    f.add_argument("--dry-run", action="store_true", help="print each file and the URL it comes from; download nothing")
    f.add_argument("--quiet", action="store_true", help="no progress bar")
    f.add_argument("--json", action="store_true", help="print one JSON object")
    f.set_defaults(handler=_run_fetch)

    v = actions.add_parser(
        "verify",
        help="check a data folder against the pinned checksums",
        description="Check every pinned file present in the data folder against its SHA-256 "
        "(exit 2 naming the bad files), report the missing ones and list files "
        "the registry does not pin (e.g. other days' orders) without failing.",
    )
    _add_city_arg(v, "whose data folder to check")
    v.add_argument(
        "--data",
        metavar="DIR",
        default=None,
        help="the city's data folder to check (default: the folder rpbench uses, see `rpbench list`)",
    )
    v.add_argument("--json", action="store_true", help="print one JSON object")
    v.set_defaults(handler=_run_verify)


def _add_city_arg(parser: argparse.ArgumentParser, what: str) -> None:
    # Checked by the handler, not by argparse's choices: an unknown name is then one line, not a usage block.
    parser.add_argument(
        "--city",
        metavar="NAME",
        default=DEFAULT_CITY,
        help=f"the city {what}: {', '.join(REGISTRY_FILES)} (default: {DEFAULT_CITY})",
    )


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help(sys.stderr)
    return 2


def _city(args: argparse.Namespace) -> str:
    """``--city``, checked: a city without a registry is one line naming those with one."""
    registry_file(args.city)
    return args.city


def _run_fetch(args: argparse.Namespace) -> int:
    city = _city(args)
    if args.dry_run:
        urls = source_urls(args.mirror, city=city)
        if args.json:
            print_json({"dest": str(args.dest or fetched_data_dir(city)), "files": dict(urls)})
        else:
            for name, url in urls:
                print(f"{name}  <-  {url}")
        return 0
    report = fetch(args.dest, args.mirror, city=city, progress=not (args.quiet or args.json))
    if args.json:
        print_json(report.as_dict())
        return 0
    source = "pinned upstream sources" if report.source == "registry" else report.source
    if report.downloaded:
        print(
            f"fetched {len(report.downloaded)} file(s) ({report.content_bytes / 1e6:.1f} MB of content) "
            f"from {source} into {report.dest}"
        )
    if report.replaced:
        print(f"  replaced (their content was wrong): {', '.join(report.replaced)}")
    if report.already_present:
        print(
            f"{'  ' if report.downloaded else ''}{len(report.already_present)} file(s) already present "
            f"and verified in {report.dest}"
        )
    return 0


def _run_verify(args: argparse.Namespace) -> int:
    city = _city(args)
    folder, origin = locate_data_dir(args.data, city)
    if folder is None:  # nothing to verify: no download either
        tried = ", ".join(str(c) for c in paths.candidate_data_dirs(city))
        named = f"pass --data DIR or set ${DATA_ENV}" if city == DEFAULT_CITY else "or pass --data DIR"
        raise DataNotFoundError(
            f"no {city_label(city)} data folder found to verify (tried {tried}); "
            f"fetch it with `{fetch_command(city)}`, {named}"
        )
    report = verify_data(folder, city=city)
    if args.json:
        print_json({**report.as_dict(), "source": origin})
    else:
        total = len(report.ok) + len(report.bad) + len(report.missing)
        print(f"data folder: {report.folder} (from {origin})")
        print(f"  verified: {len(report.ok)} of {total} pinned file(s)")
        for name, problem in report.bad.items():
            print(f"  BAD      {name}: {problem}")
        if report.missing:
            print(f"  missing ({len(report.missing)}): {', '.join(report.missing)}")
        for name, kind in report.extra.items():
            print(f"  extra    {name}: {kind}")
    check_verified(report)
    return 0
