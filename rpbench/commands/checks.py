"""Checks a command makes before any work: lists without repeats, dates, a Dask address, and output
paths that can be written (and written whole).
"""

from __future__ import annotations

import argparse
import datetime as dt
import importlib.util
import os
import secrets
import tempfile
import urllib.parse
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.scenarios.request import parse_date


def check_unique(what: str, names: Iterable[str]) -> None:
    """One error line when ``names`` (dates, run names, sweep points) repeat one: the folders named after
    them would collide only when the results are written, after every simulation."""
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise ParameterError(f"{what} gives {name!r} twice; give each once")
        seen.add(name)


def check_date_list(option: str, text: str | None) -> None:
    """``--dates A,B,...``: each date well-formed and given once, checked before the data folder is needed
    (a range ``A..B`` cannot repeat a day)."""
    if text is None or ".." in text:
        return
    dates: list[dt.date] = [parse_date(d.strip()) for d in text.split(",") if d.strip()]
    check_unique(f"{option} {text!r}", (d.isoformat() for d in dates))


# ---------------------------------------------------------------- scheduler
#: Address schemes a Dask client connects to (``host:port`` alone means tcp).
DASK_SCHEMES = ("tcp", "tls", "ucx", "ws", "wss", "inproc")


def check_scheduler(address: str | None) -> None:
    """``--scheduler``: a Dask address (``tcp://host:8786``, ``host:8786``) with Dask installed, checked
    before any work (the client would otherwise fail with a traceback, or only after the set-up)."""
    if address is None:
        return
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    wrong = f"--scheduler {address!r} is not a Dask scheduler address (e.g. tcp://host:8786 or host:8786)"
    if scheme not in DASK_SCHEMES or not rest or any(c.isspace() for c in text):
        raise ParameterError(wrong)
    if scheme != "inproc":
        try:
            parts = urllib.parse.urlsplit(f"//{rest}")
            port = parts.port
        except ValueError:
            raise ParameterError(f"{wrong}: its port must be a number in [1, 65535]") from None
        if not parts.hostname or parts.path not in ("", "/") or parts.query or parts.fragment or port == 0:
            raise ParameterError(wrong)
    if importlib.util.find_spec("distributed") is None:
        raise ParameterError("--scheduler needs Dask, which is not installed: pip install 'rpbench[dask]'")


def check_parallel(args: argparse.Namespace) -> None:
    """``--workers`` and ``--scheduler``: their values, and not both (a cluster has its own workers)."""
    if getattr(args, "workers", None) is not None and getattr(args, "scheduler", None) is not None:
        raise ParameterError("--workers and --scheduler exclude each other: a Dask cluster has its own workers")
    check_scheduler(getattr(args, "scheduler", None))


# ---------------------------------------------------------------- out paths
#: What a results folder's staging name adds to its final name (``.NAME.partial-PID``, a PID of up to 7
#: digits: Linux's largest pid_max).
_STAGING_BYTES = len(".") + len(".partial-") + 7


#: Room for the deepest path rpbench writes below a results folder (``<day or point>/runs/<run>/<file>``):
#: day and file names are short, a run name is at most NAME_MAX bytes.
_INNER_BYTES = 64


def _limits(path: Path) -> tuple[int, int]:
    """NAME_MAX and PATH_MAX (bytes) of the file system holding ``path``'s nearest existing parent."""
    folder = path
    while not os.path.lexists(folder) and folder.parent != folder:
        folder = folder.parent
    try:
        return os.pathconf(folder, "PC_NAME_MAX"), os.pathconf(folder, "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):
        return 255, 4096


def check_out_name(out: str | None, option: str = "--out", *, inner: Sequence[str] = ()) -> None:
    """One error line when folder ``out`` or a file rpbench writes below it would have a name longer than
    the file system allows (NAME_MAX bytes a name, PATH_MAX a path): the write would fail only at the end,
    after every simulation.  ``inner`` are the names rpbench puts below ``out`` (days, points, runs)."""
    if out is None:
        return
    path = Path(os.path.abspath(out))
    name_max, path_max = _limits(path)
    for part in path.parts[1:]:
        if len(os.fsencode(part)) > name_max:
            raise ParameterError(
                f"{option}: the name {part[:40]!r}... is {len(os.fsencode(part))} bytes; the file system "
                f"allows {name_max}"
            )
    if len(os.fsencode(path.name)) + _STAGING_BYTES > name_max:
        raise ParameterError(
            f"{option}: the folder name {path.name[:40]!r}... is {len(os.fsencode(path.name))} bytes; at most "
            f"{name_max - _STAGING_BYTES} fit (the file system allows {name_max}, and rpbench writes the folder "
            "under a longer temporary name first)"
        )
    for name in inner:
        if len(os.fsencode(name)) > name_max:
            raise ParameterError(
                f"{option}: rpbench would write {name[:40]!r}... inside it, {len(os.fsencode(name))} bytes; the "
                f"file system allows {name_max}"
            )
    deepest = len(os.fsencode(str(path))) + _STAGING_BYTES + sum(len(os.fsencode(n)) + 1 for n in inner)
    if deepest + _INNER_BYTES > path_max:
        raise ParameterError(
            f"{option}: the path {str(path)[:40]!r}... is {len(os.fsencode(str(path)))} bytes; with the files "
            f"written inside it the paths would exceed the file system's {path_max}"
        )


# ------------------------------------------------------------- output files
def check_out_file(path: str, option: str) -> Path:
    """Fail in one line, before any work, unless file ``path`` can be written: its folder exists and takes
    new files, and ``path`` is not a folder.  An existing file is replaced (atomically, see
    :func:`write_out_file`)."""
    out = Path(path)
    folder = out.parent
    if out.is_dir():
        raise ParameterError(f"{option} {path!r} is a folder; give a file name")
    if not folder.is_dir():
        state = "is not a folder" if os.path.lexists(folder) else "does not exist"
        raise ParameterError(f"{option} {path!r}: folder {str(folder)!r} {state}; create it or choose another path")
    try:  # try it: permission bits say nothing about root, read-only mounts or /proc
        fd, probe = tempfile.mkstemp(prefix=".rpbench-probe-", dir=folder)
    except OSError as exc:
        raise ParameterError(
            f"{option} {path!r}: cannot create files in {str(folder)!r} ({exc.strerror or exc})"
        ) from None
    os.close(fd)
    os.unlink(probe)
    return out


def write_out_file(path: Path, option: str, write: Callable[[Path], object]) -> None:
    """``write(tmp)`` a sibling temporary file, then rename it to ``path``: an interrupted or failed write
    leaves no half-written ``path`` (nor the temporary file); an OSError is one line naming ``path``."""
    # the random part makes the name unguessable (nothing to plant a link at); the original name last keeps
    # the suffix pandas picks compression by
    tmp = path.with_name(f".partial-{secrets.token_hex(6)}-{path.name}")
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError) and not isinstance(exc, RpbenchError):
            raise ParameterError(f"{option} {str(path)!r}: cannot write the file ({exc.strerror or exc})") from None
        raise
