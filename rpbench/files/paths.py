"""Where rpbench finds its data folders, its cache and its checkout.

rpbench knows the data folders of a few cities (:data:`CITY_LABELS`; Haikou is
the default, :data:`DEFAULT_CITY`).  A city's folder is, in order of precedence
(DESIGN.md "Data"): ``--data DIR`` (the folder of the city the command is
about), else, for Haikou only, the ``RPBENCH_DATA`` environment variable, else
``../shared/data/<city>`` next to the checkout (tried beside the current
directory first, then beside the source tree when rpbench runs from a
checkout), else the folder ``rpbench data fetch --city CITY`` downloads into
(``<city>`` in the user data directory, or in ``RPBENCH_DATA_HOME``), so a
fresh machine without ``../shared`` runs the real data after one fetch.
Nothing here assumes which days exist in a folder.  When no folder is found,
:func:`rpbench.data.first_run.ensure_data_dir` fetches the city's pinned
registry into that last folder first, from ``$RPBENCH_DATA_MIRROR`` when set;
this module only finds folders.

The cache (all-pairs distances, predictions) lives in the user cache
directory, never in the repository; ``RPBENCH_CACHE`` overrides it.  A
cache folder that cannot be used is one clear error (:func:`cache_dir`).
Entries are written under hidden temporary names that carry the writer's
pid (:func:`temporary_file`, :func:`temporary_folder`) and renamed into
place; the first use of a cache folder in a process sweeps the temporaries
of writers that died (:func:`sweep_stale_temporaries`).  Builders of one entry take turns under a lock
(:func:`builder_lock`), so a second process waits for the first's entry instead of reading it half-renamed.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from platformdirs import user_cache_dir, user_data_dir

from rpbench.exceptions import CacheError, DataNotFoundError, ParameterError, one_line

DATA_ENV = "RPBENCH_DATA"
CACHE_ENV = "RPBENCH_CACHE"
DATA_HOME_ENV = "RPBENCH_DATA_HOME"
DATA_MIRROR_ENV = "RPBENCH_DATA_MIRROR"
#: The cities whose data folders rpbench finds and fetches (``--city NAME``), with the name messages give them.
CITY_LABELS = {"haikou": "Haikou", "manhattan": "Manhattan"}
#: The city of a command that names none: every scenario of the paper is Haikou's.
DEFAULT_CITY = "haikou"
# ``../shared/data/<city>``: the shared folders sit beside the checkout.
_SHARED_DATA = Path("..") / "shared" / "data"
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
    return Path(__file__).resolve().parents[2]  # rpbench/files/paths.py -> the checkout


def data_home() -> Path:
    """Where downloaded data lives: ``$RPBENCH_DATA_HOME``, else the user data directory."""
    root = os.environ.get(DATA_HOME_ENV) or user_data_dir("rpbench", appauthor=False)
    return Path(root).expanduser()


def city_label(city: str) -> str:
    """The name messages give ``city`` (``"Haikou"``); an unknown city is a :class:`ParameterError`
    naming the known ones (a city's name becomes a folder name: nothing else may pass)."""
    try:
        return CITY_LABELS[city]
    except (KeyError, TypeError):
        raise ParameterError(
            f"unknown city {city!r}: rpbench knows the data folders of {', '.join(CITY_LABELS)}; name one of them"
        ) from None


def fetch_command(city: str = DEFAULT_CITY) -> str:
    """The command that fills :func:`fetched_data_dir` of ``city`` (``--city`` only when it is not the default)."""
    city_label(city)
    return "rpbench data fetch" if city == DEFAULT_CITY else f"rpbench data fetch --city {city}"


def fetched_data_dir(city: str = DEFAULT_CITY) -> Path:
    """The folder ``rpbench data fetch --city CITY`` fills by default: ``<data home>/<city>`` (it may not
    exist yet).  It has the name of the shared folder, so one data home holds every city side by side."""
    city_label(city)
    return data_home() / city


def shared_data_candidates(city: str = DEFAULT_CITY) -> list[Path]:
    """``../shared/data/<city>`` beside the current directory, then beside the checkout (they may not exist)."""
    city_label(city)
    return [Path.cwd() / _SHARED_DATA / city, source_root() / _SHARED_DATA / city]


def default_data_candidates(city: str = DEFAULT_CITY) -> list[Path]:
    """Folders tried for ``city``, in order, when no folder is named (no ``--data``; for Haikou, no env var):
    :func:`shared_data_candidates`, then :func:`fetched_data_dir`, resolved, each once."""
    return _defaults(city)


def candidate_data_dirs(city: str = DEFAULT_CITY) -> list[Path]:
    """The folders :func:`locate_data_dir` tries for ``city``, in order (messages list them as tried).

    They are :func:`default_data_candidates`.  Haikou's list is looked up through this module and asked
    for without an argument, as before rpbench knew other cities, so that a test standing for another
    machine can replace that function by one of no argument; that replacement leaves the other cities'
    lists as they are.
    """
    if city == DEFAULT_CITY:
        return default_data_candidates()
    return _defaults(city)


def _defaults(city: str) -> list[Path]:
    unique: list[Path] = []
    for c in [*shared_data_candidates(city), fetched_data_dir(city)]:
        c = c.resolve()
        if c not in unique:
            unique.append(c)
    return unique


def describe_candidate(path: Path, city: str = DEFAULT_CITY) -> str:
    """Say which default of ``city`` a candidate folder is (for ``rpbench list``)."""
    path = path.resolve()
    if path == fetched_data_dir(city).resolve():
        return f"downloaded by `{fetch_command(city)}` (${DATA_HOME_ENV} or the user data directory)"
    here, checkout = (c.resolve() for c in shared_data_candidates(city))
    if path == here:
        return f"../shared/data/{city} beside the current directory"
    if path == checkout:
        return f"../shared/data/{city} beside the checkout"
    return "a default candidate folder"


def locate_data_dir(explicit: str | os.PathLike | None = None, city: str = DEFAULT_CITY) -> tuple[Path | None, str]:
    """``city``'s data folder and where it came from (``--data``, the env var, which default).

    ``explicit`` (``--data DIR``) is the folder of ``city``, the city the
    command is about; ``$RPBENCH_DATA`` names Haikou's folder only.  A folder
    named so (argument or env var) that does not exist is an error, not a
    silent fall-back: the user asked for it by name.  ``(None, "none found")``
    when no default exists; an unknown city is a :class:`ParameterError`.
    """
    label = city_label(city)
    if explicit is not None:
        path = Path(explicit).expanduser()
        if not path.is_dir():
            raise DataNotFoundError(
                f"data folder {str(path)!r} (from --data) does not exist; point --data at the {label} data folder"
            )
        return path.resolve(), "--data"
    env = os.environ.get(DATA_ENV) if city == DEFAULT_CITY else None
    if env:
        path = Path(env).expanduser()
        if not path.is_dir():
            raise DataNotFoundError(
                f"data folder {env!r} (from ${DATA_ENV}) does not exist; "
                f"unset {DATA_ENV} or point it at the {label} data folder"
            )
        return path.resolve(), f"${DATA_ENV}"
    for candidate in candidate_data_dirs(city):
        if candidate.is_dir():
            return candidate, describe_candidate(candidate, city)
    return None, "none found"


def find_data_dir(explicit: str | os.PathLike | None = None, city: str = DEFAULT_CITY) -> Path | None:
    """Return ``city``'s data folder, or ``None`` when no folder exists (see :func:`locate_data_dir`)."""
    return locate_data_dir(explicit, city)[0]


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


@contextmanager
def builder_lock(path: Path, waiting: str | None = None) -> Iterator[None]:
    """Hold the exclusive lock of one cache entry's builders (``flock`` on ``path``, released by the kernel
    if the process dies); print ``waiting`` on stderr first, if given, when another process holds it.

    The caller checks the entry again once it holds the lock: the process it waited for may have written it.
    """
    try:
        fh = open(path, "a+")  # noqa: SIM115 (held for the lock's lifetime, closed below)
    except OSError as exc:
        raise cache_write_error(path, exc) from None
    with fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if waiting is not None:
                print(waiting, file=sys.stderr)
            fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)
