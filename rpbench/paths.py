"""Where rpbench finds its data folder, its cache and its checkout.

Data folder precedence (DESIGN.md "Data"): ``--data DIR``, else the
``RPBENCH_DATA`` environment variable, else ``../shared/data/haikou`` next to
the checkout (tried beside the current directory first, then beside the
source tree when rpbench runs from a checkout), else the folder
``rpbench data fetch`` downloads into (``haikou`` in the user data directory,
or in ``RPBENCH_DATA_HOME``), so a fresh machine without ``../shared`` runs
the real data after one fetch.  Nothing here assumes which days exist in the
folder.  When no folder is found,
:func:`rpbench.data.first_run.ensure_data_dir` fetches the pinned registry into
that last folder first, from ``$RPBENCH_DATA_MIRROR`` when set; this module
only finds folders.

The cache (all-pairs distances, predictions) lives in the user cache
directory, never in the repository; ``RPBENCH_CACHE`` overrides it.  A
cache folder that cannot be used is one clear error (:func:`cache_dir`).
Entries are written under hidden temporary names that carry the writer's
pid (:func:`temporary_file`, :func:`temporary_folder`) and renamed into
place; the first use of a cache folder in a process sweeps the temporaries
of writers that died (:func:`sweep_stale_temporaries`).
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from platformdirs import user_cache_dir, user_data_dir

from rpbench.exceptions import CacheError, DataNotFoundError, one_line

DATA_ENV = "RPBENCH_DATA"
CACHE_ENV = "RPBENCH_CACHE"
DATA_HOME_ENV = "RPBENCH_DATA_HOME"
DATA_MIRROR_ENV = "RPBENCH_DATA_MIRROR"
_RELATIVE_DEFAULT = Path("..") / "shared" / "data" / "haikou"
# The fetched folder gets the same name as the shared one, so the data home can
# later hold other cities beside it.
_FETCHED_NAME = "haikou"
#: A dead writer's temporary is swept once untouched this long: a pid says nothing about a writer on
#: another machine or in another pid namespace sharing the folder (which keeps writing while it builds),
#: and a leftover costs only disk space meanwhile, so err on the late side.
STALE_AFTER_S = 3600.0
#: Temporaries without a pid (written by older rpbench versions): swept once untouched this long.
LEGACY_STALE_AFTER_S = 86400.0
_LEGACY_PREFIX = ".predict-structure-"
_SWEPT: set[Path] = set()  # cache folders this process has swept


def source_root() -> Path:
    """The folder holding the ``rpbench`` package (the checkout, when run from one)."""
    return Path(__file__).resolve().parent.parent


def data_home() -> Path:
    """Where downloaded data lives: ``$RPBENCH_DATA_HOME``, else the user data directory."""
    root = os.environ.get(DATA_HOME_ENV) or user_data_dir("rpbench", appauthor=False)
    return Path(root).expanduser()


def fetched_data_dir() -> Path:
    """The folder ``rpbench data fetch`` fills by default (it may not exist yet)."""
    return data_home() / _FETCHED_NAME


def default_data_candidates() -> list[Path]:
    """Folders tried, in order, when neither ``--data`` nor the env var is set."""
    candidates = [Path.cwd() / _RELATIVE_DEFAULT, source_root() / _RELATIVE_DEFAULT, fetched_data_dir()]
    unique: list[Path] = []
    for c in candidates:
        c = c.resolve()
        if c not in unique:
            unique.append(c)
    return unique


def describe_candidate(path: Path) -> str:
    """Say which default a candidate folder is (for ``rpbench list``)."""
    path = path.resolve()
    if path == fetched_data_dir().resolve():
        return f"downloaded by `rpbench data fetch` (${DATA_HOME_ENV} or the user data directory)"
    if path == (Path.cwd() / _RELATIVE_DEFAULT).resolve():
        return "../shared/data/haikou beside the current directory"
    if path == (source_root() / _RELATIVE_DEFAULT).resolve():
        return "../shared/data/haikou beside the checkout"
    return "a default candidate folder"


def locate_data_dir(explicit: str | os.PathLike | None = None) -> tuple[Path | None, str]:
    """The data folder to use and where it came from (``--data``, the env var, which default).

    An explicit folder (argument or env var) that does not exist is an
    error, not a silent fall-back: the user asked for it by name.
    """
    if explicit is not None:
        path = Path(explicit).expanduser()
        if not path.is_dir():
            raise DataNotFoundError(
                f"data folder {str(path)!r} (from --data) does not exist; point --data at the Haikou data folder"
            )
        return path.resolve(), "--data"
    env = os.environ.get(DATA_ENV)
    if env:
        path = Path(env).expanduser()
        if not path.is_dir():
            raise DataNotFoundError(
                f"data folder {env!r} (from ${DATA_ENV}) does not exist; "
                f"unset {DATA_ENV} or point it at the Haikou data folder"
            )
        return path.resolve(), f"${DATA_ENV}"
    # Looked up through the module so tests can replace the candidate list.
    for candidate in default_data_candidates():
        if candidate.is_dir():
            return candidate, describe_candidate(candidate)
    return None, "none found"


def find_data_dir(explicit: str | os.PathLike | None = None) -> Path | None:
    """Return the data folder to use, or ``None`` when no folder exists (see :func:`locate_data_dir`)."""
    return locate_data_dir(explicit)[0]


def cache_dir() -> Path:
    """The user cache directory for derived data (created on demand).

    A cache folder that is a file, cannot be created or is not writable is a
    :class:`CacheError` naming it (and ``$RPBENCH_CACHE``), never a traceback
    and never a silent fall-back to computing without a cache: the all-pairs
    table of the Haikou network takes a while to build, and rebuilding it on
    every run without saying so would hide a misconfiguration.
    """
    env = os.environ.get(CACHE_ENV)
    path = Path(env or user_cache_dir("rpbench", appauthor=False)).expanduser()
    origin = f"from ${CACHE_ENV}" if env else f"the user cache directory; set ${CACHE_ENV} to move it"
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # FileExistsError (a file sits there), NotADirectoryError, PermissionError, ...
        raise CacheError(
            f"cache folder {str(path)!r} ({origin}) cannot be created: {one_line(exc)}; "
            f"point ${CACHE_ENV} at a writable folder"
        ) from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise CacheError(
            f"cache folder {str(path)!r} ({origin}) is not writable; point ${CACHE_ENV} at a writable folder"
        )
    if path not in _SWEPT:
        _SWEPT.add(path)
        sweep_stale_temporaries(path)
    return path


def temporary_file(final: Path) -> Path:
    """The hidden name ``final`` is written under before its rename: ``.<name>.<pid>.tmp``."""
    return final.with_name(f".{final.name}.{os.getpid()}.tmp")


def temporary_folder(final: Path) -> Path:
    """A new hidden folder beside ``final`` to build it in: ``.<name>.<random>.<pid>.tmp``."""
    return Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=f".{os.getpid()}.tmp", dir=final.parent))


def temporary_writer(name: str) -> int | None:
    """The pid a temporary's name carries (None: not a temporary, or one without a pid)."""
    if not (name.startswith(".") and name.endswith(".tmp")):
        return None
    pid = name.removesuffix(".tmp").rpartition(".")[2]
    return int(pid) if pid.isdigit() else None


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a process of another user counts as running)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # PermissionError: it exists, and is not ours; else cannot tell
        return True
    return True


def sweep_stale_temporaries(folder: Path, *, now: float | None = None) -> list[Path]:
    """Delete the temporaries in ``folder`` whose writer died, with one note on stderr each.

    A temporary is stale when the pid in its name runs no process and nothing
    in it changed for :data:`STALE_AFTER_S` (or, for a pid-less structure
    folder of an older rpbench, for :data:`LEGACY_STALE_AFTER_S`).  A live
    writer's temporary is never touched.  The entry is first renamed to a
    name carrying this process's pid, so two sweepers never both report it
    and a sweep cut short is swept again later.  Returns what was removed.
    """
    now = time.time() if now is None else now
    removed: list[Path] = []
    try:
        names = [e.name for e in os.scandir(folder) if e.name.startswith(".")]
    except OSError:
        return removed
    for name in names:
        entry = folder / name
        pid = temporary_writer(name)
        if pid is not None:
            if pid == os.getpid() or pid_alive(pid) or now - _last_change(entry) < STALE_AFTER_S:
                continue
        elif not (name.startswith(_LEGACY_PREFIX) and entry.is_dir()):
            continue  # not ours to judge
        elif now - _last_change(entry) < LEGACY_STALE_AFTER_S:
            continue
        size = _size(entry)
        claimed = entry.with_name(f".swept.{time.monotonic_ns()}.{os.getpid()}.tmp")
        try:
            os.rename(entry, claimed)
        except OSError:
            continue  # gone already (another process swept it) or not ours to move
        if claimed.is_dir():
            shutil.rmtree(claimed, ignore_errors=True)
        else:
            claimed.unlink(missing_ok=True)
        writer = f"process {pid}, which no longer runs" if pid is not None else "an older rpbench"
        print(
            f"rpbench: note: removed the stale temporary cache entry {name} ({_megabytes(size)}) "
            f"left by {writer}, from {folder}",
            file=sys.stderr,
        )
        removed.append(entry)
    return removed


def _last_change(entry: Path) -> float:
    """The latest mtime of ``entry`` and, for a folder, of the files in it (a build writes into them)."""
    try:
        latest = entry.lstat().st_mtime
        if entry.is_dir() and not entry.is_symlink():
            for f in os.scandir(entry):
                latest = max(latest, f.stat(follow_symlinks=False).st_mtime)
    except OSError:
        return time.time()  # vanished or unreadable meanwhile: treat as fresh, look again next time
    return latest


def _size(entry: Path) -> int:
    try:
        if entry.is_dir() and not entry.is_symlink():
            return sum(f.stat(follow_symlinks=False).st_size for f in os.scandir(entry))
        return entry.lstat().st_size
    except OSError:
        return 0


def _megabytes(size: int) -> str:
    return f"{size / 1e9:.1f} GB" if size >= 1e8 else f"{size / 1e6:.1f} MB"


def cache_write_error(path: Path, exc: OSError) -> CacheError:
    """The one-line error for a cache file that cannot be written (disk full, permissions...)."""
    return CacheError(
        f"cannot write the cache file {str(path)!r}: {one_line(exc)}; free some space or "
        f"point ${CACHE_ENV} at another writable folder"
    )
