"""``rpbench data fetch`` and ``rpbench data verify``: get the Haikou data folder on a fresh machine, check one.

The pinned file list and the download logic are :mod:`rpbench.data.fetch`.
Summaries go to stdout (one JSON object with ``--json``), the progress bar
to stderr; a network error, a checksum mismatch, a body longer than the
registry's size and a full disk are each one line and exit 2.
Commands that need the data fetch it the same way by themselves when no
folder is found (:mod:`rpbench.data.first_run`).
"""

from __future__ import annotations

import argparse
import sys

from rpbench import paths
from rpbench.commands.output import print_json
from rpbench.data.fetch import check_verified, fetch, source_urls, verify_data
from rpbench.exceptions import DataNotFoundError
from rpbench.paths import (
    DATA_ENV,
    DATA_HOME_ENV,
    DATA_MIRROR_ENV,
    fetched_data_dir,
    locate_data_dir,
)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "data",
        help="download (fetch) or check (verify) the Haikou data folder",
        description="Download the Haikou data folder from its public sources at pinned commits "
        "(fetch), or check a data folder against the pinned checksums (verify).",
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
    f.add_argument(
        "--dest",
        metavar="DIR",
        default=None,
        help=f"folder to fill (default: {fetched_data_dir()}, i.e. haikou/ in ${DATA_HOME_ENV} "
        "or the user data directory)",
    )
    f.add_argument(
        "--mirror",
        metavar="URL",
        default=None,
        help="fetch the stored file names from this copy of a data folder instead "
        f"(http(s)://, file:// or a local folder; default: ${DATA_MIRROR_ENV}, else the pinned sources); "
        "content is still checked",
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
    v.add_argument(
        "--data",
        metavar="DIR",
        default=None,
        help="data folder to check (default: the folder rpbench uses, see `rpbench list`)",
    )
    v.add_argument("--json", action="store_true", help="print one JSON object")
    v.set_defaults(handler=_run_verify)


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help(sys.stderr)
    return 2


def _run_fetch(args: argparse.Namespace) -> int:
    if args.dry_run:
        urls = source_urls(args.mirror)
        if args.json:
            print_json({"dest": str(args.dest or fetched_data_dir()), "files": dict(urls)})
        else:
            for name, url in urls:
                print(f"{name}  <-  {url}")
        return 0
    report = fetch(args.dest, args.mirror, progress=not (args.quiet or args.json))
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
    folder, origin = locate_data_dir(args.data)
    if folder is None:  # nothing to verify: no download either
        tried = ", ".join(str(c) for c in paths.default_data_candidates())
        raise DataNotFoundError(
            f"no Haikou data folder found to verify (tried {tried}); fetch it with `rpbench data fetch`, "
            f"pass --data DIR or set ${DATA_ENV}"
        )
    report = verify_data(folder)
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
