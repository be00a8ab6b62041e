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
"""

from __future__ import annotations

import os
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
    return path


def cache_write_error(path: Path, exc: OSError) -> CacheError:
    """The one-line error for a cache file that cannot be written (disk full, permissions...)."""
    return CacheError(
        f"cannot write the cache file {str(path)!r}: {one_line(exc)}; free some space or "
        f"point ${CACHE_ENV} at another writable folder"
    )
