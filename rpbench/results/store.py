"""Results folders: written atomically, never overwritten, readable without the data folder.

Layout of one folder::

    meta.json                 versions, git commit, scenario, parameters, seed, preset, machine, runs
    kpis.csv                  tidy KPI table: run, kpi, value
    rounds.csv.gz             per-round solver statistics (model size, build/solve time, status)
    hourly.csv                per-hour KPIs of every run
    orders.csv.gz             the scenario's orders (id, request, origin, destination, patience, solo distance)
    network.npz               the road network (nodes, arcs, lengths) the run drove on
    runs/<run>/events.csv.gz  the event log (request, assign, pickup, dropoff, cancel)
    runs/<run>/trajectories.npz  every vehicle's driven node sequence with times and odometer
    report.md                 the comparison table (rendered by rpbench.report.comparison)

Everything is first written to a hidden sibling folder and renamed into
place at the end, so an interrupted run leaves no half-written folder.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import os
import platform
import re
import shutil
import subprocess
import tempfile
import time
import zipfile
import zlib
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import files
from rpbench.data.road import NetworkTables
from rpbench.exceptions import ResultsError, RpbenchError, one_line, out_named, out_parameter
from rpbench.files.paths import source_root
from rpbench.network import RoadNetwork
from rpbench.version import __version__

VERSIONED_PACKAGES = ("numpy", "scipy", "pandas", "numba", "highspy", "ortools", "pyomo", "cvxpy", "pymatching", "lap")


#: Where results folders go without ``--out`` (below the current folder).
DEFAULT_PARENT = "rpbench-runs"
#: A partial folder whose process is gone is removed only when it is older than this: a PID says nothing
#: about a process on another machine sharing the folder (or a reused PID), and a dead process's leftover
#: costs only disk space meanwhile, so err on the late side.
STALE_PARTIAL_S = 60 * 60
#: ``.NAME.partial-PID``, or ``.NAME.partial-PID-XXXX`` (a staging folder made with tempfile.mkdtemp, such as
#: rpbench publish's).
_PARTIAL = re.compile(r"^\.(?P<name>.+)\.partial-(?P<pid>\d+)(?:-\w+)?$")


def _another_out() -> str:
    name = out_parameter()
    if name.startswith("-"):
        return f"choose another {name}"
    return f"pass another {name}= (or none: a new folder under ./{DEFAULT_PARENT})"


@contextlib.contextmanager
def new_results_folder(out: str | os.PathLike | None, default_name: str) -> Iterator[tuple[Path, Path]]:
    """Yield ``(temporary folder, final path)``; the temporary folder becomes ``out``
    (or ``./rpbench-runs/<default_name>``) on success and is removed on failure.

    Whatever stops the body (an error, Ctrl-C, SIGTERM turned into an exception by the CLI) removes the
    temporary folder and the parent folders this call created, so nothing half-written remains; an
    OSError while writing becomes one :class:`ResultsError` line naming the file.  Stale partial
    folders of dead processes beside the new one are swept away first (:func:`remove_stale_partials`).
    """
    final = _unique(Path.cwd() / DEFAULT_PARENT / default_name) if out is None else Path(out)
    check_new_folder(final)  # again: a long run gives the world time to change
    created = make_parents(final.parent, final)
    remove_stale_partials(final.parent)
    tmp = final.parent / f".{final.name}.partial-{os.getpid()}"
    try:
        if tmp.exists():
            shutil.rmtree(tmp)
        tmp.mkdir()
    except OSError as exc:
        remove_empty(created)
        raise ResultsError(f"cannot create results folder {str(final)!r}: {exc.strerror or exc}") from None
    try:
        yield tmp, final
        _move_into_place(tmp, final)
    except BaseException as exc:
        error = _write_error(exc, tmp, final)
        shutil.rmtree(tmp, ignore_errors=True)
        remove_empty(created)
        if error is not None:
            raise error from None
        raise


def check_new_folder(out: str | os.PathLike | None, *, what: str | None = None) -> None:
    """Raise one :class:`ResultsError` line unless a new results folder can be created at ``out``
    (``None``: the default place, ``./rpbench-runs/``): nothing may exist there (not even a dangling link)
    and its nearest existing parent must be a folder we can create folders in.  Commands call this
    before simulating, so a bad ``--out`` costs nothing.  ``what`` names the parameter in the message
    (default: ``out=`` in Python, ``--out`` under the command line)."""
    target = Path.cwd() / DEFAULT_PARENT / "new" if out is None else Path(out)
    if out is not None and os.path.lexists(target):
        if target.is_symlink() and not target.exists():
            there = "a dangling symbolic link"
        elif target.is_dir():
            there = "a folder"
        else:
            there = "a file"
        if what is None:
            named, another = out_named(target), _another_out()
        else:
            named, another = f"{what} {str(target)!r}", f"choose another {what}"
        raise ResultsError(f"{named} already exists ({there}); rpbench never overwrites results, {another}")
    if out is None:
        label = f"the default results folder ./{DEFAULT_PARENT}"
    else:
        label = out_named(out) if what is None else f"{what} {str(out)!r}"
    _check_can_create_in(_nearest_existing(target.parent), label)


def _nearest_existing(folder: Path) -> Path:
    while not os.path.lexists(folder) and folder.parent != folder:
        folder = folder.parent
    return folder


def _check_can_create_in(folder: Path, label: str) -> None:
    """Try it (a probe folder created and removed): permission bits say nothing about root, read-only
    mounts or /proc."""
    if not folder.is_dir():
        raise ResultsError(f"{label}: {str(folder)!r} is not a folder")
    try:
        probe = tempfile.mkdtemp(prefix=".rpbench-probe-", dir=folder)
    except OSError as exc:
        raise ResultsError(f"{label}: cannot create a folder in {str(folder)!r} ({exc.strerror or exc})") from None
    os.rmdir(probe)


def make_parents(folder: Path, final: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; return the ones created, deepest first (to undo)."""
    missing = []
    while not os.path.lexists(folder) and folder.parent != folder:
        missing.append(folder)
        folder = folder.parent
    created: list[Path] = []
    for f in reversed(missing):
        try:
            f.mkdir()
        except FileExistsError:
            continue  # made meanwhile by a concurrent run: not ours to undo
        except OSError as exc:
            remove_empty(created[::-1])
            raise ResultsError(
                f"cannot create results folder {str(final)!r}: {str(f)!r}: {exc.strerror or exc}"
            ) from None
        created.append(f)
    return created[::-1]


def remove_empty(folders: list[Path]) -> None:
    for f in folders:
        try:
            f.rmdir()
        except OSError:
            return  # not empty (someone else's files): keep it and its parents


def _move_into_place(tmp: Path, final: Path) -> None:
    # os.rename would silently replace an empty folder created at ``final`` meanwhile: never overwrite.
    if os.path.lexists(final):
        raise ResultsError(
            f"results folder {str(final)!r} appeared while this run was writing it; rpbench never "
            "overwrites results, nothing was written: choose another --out"
        )
    os.rename(tmp, final)


def _write_error(exc: BaseException, tmp: Path, final: Path) -> ResultsError | None:
    """One line for an OSError met while writing into ``tmp`` (None: not such an error, re-raise it as is)."""
    if not isinstance(exc, OSError) or isinstance(exc, RpbenchError):
        return None
    where = ""
    if exc.filename is not None:
        try:
            inside = Path(os.path.abspath(exc.filename)).relative_to(os.path.abspath(tmp))
        except ValueError:
            return None  # not a file of the folder (an input, say)
        where = f"{inside}: " if str(inside) != "." else ""
    return ResultsError(
        f"cannot write results folder {str(final)!r} ({where}{exc.strerror or exc}); nothing was written"
    )


def remove_stale_partials(parent: Path, *, older_than_s: float = STALE_PARTIAL_S) -> list[Path]:
    """Remove the ``.NAME.partial-PID[-XXXX]`` folders in ``parent`` left by processes that died before cleaning
    up (SIGKILL, power loss): only when no process has that PID any more and the folder is older than
    ``older_than_s``.  Returns the folders removed."""
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return []
    removed = []
    now = time.time()
    for entry in entries:
        match = _PARTIAL.match(entry.name)
        if match is None or not entry.is_dir(follow_symlinks=False):
            continue
        try:
            age = now - entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        if age < older_than_s or _pid_alive(int(match["pid"])):
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        removed.append(Path(entry.path))
    return removed


def _pid_alive(pid: int) -> bool:
    """False only when no process has this PID; another user's process (PermissionError) is alive."""
    if pid <= 0 or pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):
        return True  # cannot tell: never remove what may be in use
    return True


def _unique(path: Path) -> Path:
    if not path.exists():
        return path
    k = 2
    while path.with_name(f"{path.name}-{k}").exists():
        k += 1
    return path.with_name(f"{path.name}-{k}")


def timestamp() -> str:
    return dt.datetime.now().strftime("%Y%m%d-%H%M%S")


# ------------------------------------------------------------------ metadata
def environment() -> dict[str, Any]:
    """Versions, git commit and machine facts for meta.json."""
    versions: dict[str, str | None] = {"rpbench": __version__, "python": platform.python_version()}
    for pkg in VERSIONED_PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    return {
        "versions": versions,
        "git_commit": git_commit(),
        "machine": {
            "platform": platform.platform(),
            "processor": platform.machine(),
            "cpus": os.cpu_count(),
            "memory_gib": _memory_gib(),
        },
        "created": dt.datetime.now().astimezone().isoformat(timespec="seconds"),
    }


def git_commit() -> str | None:
    root = source_root()
    if not (root / ".git").exists():
        return None
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5)
        dirty = subprocess.run(
            ["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=5,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    commit = out.stdout.strip() or None
    return f"{commit}+dirty" if commit and dirty.stdout.strip() else commit


def _memory_gib() -> float | None:
    try:
        return round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1)
    except (ValueError, OSError, AttributeError):
        return None


def to_jsonable(obj: Any) -> Any:
    """Plain-JSON version of nested dicts/lists holding numpy scalars (NaN/inf -> null)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


def write_json(path: Path, obj: Any) -> None:
    path.write_text(json.dumps(to_jsonable(obj), indent=2) + "\n")


def read_meta(folder: Path) -> dict[str, Any]:
    path = folder / "meta.json"
    if not path.is_file():
        raise ResultsError(f"{str(folder)!r} is not an rpbench results folder (no meta.json)")
    try:
        meta = files.parse_json(path.read_text(), repr(str(path)), ResultsError)  # deep nesting: one line too
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ResultsError(f"{str(path)!r} is not valid JSON: {one_line(exc)}") from None
    if not isinstance(meta, dict):
        raise ResultsError(f"{str(path)!r} does not hold a JSON object (it holds a {type(meta).__name__})")
    return meta


# ---------------------------------------------------------- network / orders
def save_network(path: Path, network: RoadNetwork) -> None:
    np.savez_compressed(
        path,
        node_id=network.node_id,
        lon=network.lon,
        lat=network.lat,
        arc_tail=network.arc_tail,
        arc_head=network.arc_head,
        arc_length_m=network.arc_length_m,
        arc_link_id=network.arc_link_id,
        name=np.array(network.name),
    )


NETWORK_KEYS = ("node_id", "lon", "lat", "arc_tail", "arc_head", "arc_length_m", "arc_link_id", "name")


def load_network(path: Path) -> RoadNetwork:
    """The road network of a results folder; a missing, corrupt or inconsistent file is one ResultsError line."""
    z = _load_npz(path, NETWORK_KEYS)
    ids, tail, head, length = z["node_id"], z["arc_tail"], z["arc_head"], z["arc_length_m"]
    n = len(ids) if ids.ndim == 1 else 0
    if not n or not all(a.ndim == 1 for a in (tail, head, length, z["arc_link_id"], z["lon"], z["lat"])):
        raise ResultsError(f"results file {str(path)!r} holds no nodes or arrays of the wrong shape")
    if not (len(tail) == len(head) == len(length) == len(z["arc_link_id"])) or len(z["lon"]) != n or len(z["lat"]) != n:
        raise ResultsError(f"results file {str(path)!r}: arc (or node) arrays differ in length")
    if not (
        np.issubdtype(tail.dtype, np.integer)
        and np.issubdtype(head.dtype, np.integer)
        and np.issubdtype(ids.dtype, np.integer)
        and np.issubdtype(length.dtype, np.number)
    ):
        raise ResultsError(f"results file {str(path)!r}: node ids, arc ends or arc lengths are not numbers")
    if len(tail) and (min(tail.min(), head.min()) < 0 or max(tail.max(), head.max()) >= n):
        raise ResultsError(f"results file {str(path)!r}: an arc ends at a node index outside 0..{n - 1}")
    if not np.isfinite(length).all() or (length < 0).any():
        raise ResultsError(f"results file {str(path)!r}: an arc length is negative, NaN or infinite")
    tables = NetworkTables(
        name=str(z["name"]),
        node_id=ids,
        lon=z["lon"],
        lat=z["lat"],
        arc_from=ids[tail],
        arc_to=ids[head],
        arc_length_m=length,
        arc_link_id=z["arc_link_id"],
        source=str(path),
    )
    return RoadNetwork.from_tables(tables)


def _load_npz(path: Path, keys: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The arrays ``keys`` of an ``.npz`` results file, read in full (numpy reads lazily: a truncated or
    corrupt archive fails on access, with zipfile, zlib or numpy errors, all turned into one line here)."""
    if not path.is_file():
        raise ResultsError(f"results file {str(path)!r} is missing")
    try:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in keys if k not in z.files]
            if missing:
                raise ResultsError(f"results file {str(path)!r} lacks the array(s) {', '.join(missing)}")
            return {k: z[k] for k in keys}
    except ResultsError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise ResultsError(f"results file {str(path)!r} is corrupt or not an npz archive: {one_line(exc)}") from None


def save_trajectories(path: Path, traj: dict[str, np.ndarray]) -> None:
    # numeric arrays only; the explicit flag also keeps a key from being read as numpy's own argument
    np.savez_compressed(path, allow_pickle=False, **traj)


TRAJECTORY_KEYS = ("vehicle_offsets", "node", "t_s", "odo_m")


def load_trajectories(path: Path) -> dict[str, np.ndarray]:
    """A run's trajectories (CSR by vehicle); a missing, corrupt or ill-shaped file is one ResultsError line."""
    traj = _load_npz(path, TRAJECTORY_KEYS)
    if any(a.ndim != 1 for a in traj.values()) or not len(traj["node"]) == len(traj["t_s"]) == len(traj["odo_m"]):
        raise ResultsError(f"results file {str(path)!r}: the node, t_s and odo_m arrays differ in length or shape")
    if not (
        np.issubdtype(traj["vehicle_offsets"].dtype, np.integer)
        and np.issubdtype(traj["node"].dtype, np.integer)
        and np.issubdtype(traj["t_s"].dtype, np.number)
        and np.issubdtype(traj["odo_m"].dtype, np.number)
    ):
        raise ResultsError(f"results file {str(path)!r}: offsets and nodes must be integers, t_s and odo_m numbers")
    return traj


def read_csv(path: Path) -> pd.DataFrame:
    """A results table (``.csv`` or ``.csv.gz``); a missing, empty, truncated or corrupt file is one ResultsError
    line."""
    if not path.is_file():
        raise ResultsError(f"results file {str(path)!r} is missing")
    try:
        return pd.read_csv(path)
    except pd.errors.EmptyDataError:
        raise ResultsError(f"results file {str(path)!r} is empty (not even a header line)") from None
    except (pd.errors.ParserError, UnicodeDecodeError, EOFError, OSError, zlib.error, ValueError) as exc:
        raise ResultsError(f"results file {str(path)!r} is corrupt or not a CSV table: {one_line(exc)}") from None


def run_names(folder: Path) -> list[str]:
    runs = folder / "runs"
    return sorted(p.name for p in runs.iterdir() if p.is_dir()) if runs.is_dir() else []


def run_folders(folder: str | os.PathLike) -> list[Path]:
    """``folder`` itself if it holds runs, else the results folders below it (multi-day, sweep parents)."""
    folder = Path(folder)
    if not folder.is_dir() or run_names(folder):
        return [folder]
    found = sorted(p.parent for p in folder.rglob("runs") if p.is_dir() and (p.parent / "meta.json").is_file())
    return found or [folder]
