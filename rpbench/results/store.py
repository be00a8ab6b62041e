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
    report.md                 the comparison table (rendered by rpbench.results.report)

Everything is first written to a hidden sibling folder and renamed into
place at the end, so an interrupted run leaves no half-written folder.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import os
import platform
import shutil
import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pandas as pd

from rpbench import __version__
from rpbench.data.road import NetworkTables
from rpbench.exceptions import ResultsError
from rpbench.network import RoadNetwork
from rpbench.paths import source_root

VERSIONED_PACKAGES = ("numpy", "scipy", "pandas", "networkx", "highspy", "ortools", "pyomo", "cvxpy", "pymatching",
                      "lap")


@contextlib.contextmanager
def new_results_folder(out: str | os.PathLike | None, default_name: str) -> Iterator[tuple[Path, Path]]:
    """Yield ``(temporary folder, final path)``; the temporary folder becomes ``out``
    (or ``./rpbench-runs/<default_name>``) on success and is removed on failure."""
    if out is None:
        parent = Path.cwd() / "rpbench-runs"
        final = _unique(parent / default_name)
    else:
        final = Path(out)
        if final.exists():
            raise ResultsError(f"results folder {str(final)!r} already exists; rpbench never overwrites results, "
                               "choose another --out")
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = final.parent / f".{final.name}.partial-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir()
    try:
        yield tmp, final
        os.rename(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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
    versions = {"rpbench": __version__, "python": platform.python_version()}
    for pkg in VERSIONED_PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = None
    return {"versions": versions, "git_commit": git_commit(),
            "machine": {"platform": platform.platform(), "processor": platform.machine(), "cpus": os.cpu_count(),
                        "memory_gib": _memory_gib()},
            "created": dt.datetime.now().astimezone().isoformat(timespec="seconds")}


def git_commit() -> str | None:
    root = source_root()
    if not (root / ".git").exists():
        return None
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=5)
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    commit = out.stdout.strip() or None
    return f"{commit}+dirty" if commit and dirty.stdout.strip() else commit


def _memory_gib() -> float | None:
    try:
        return round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 30, 1)
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
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ResultsError(f"{str(path)!r} is not valid JSON: {exc}") from None


# ---------------------------------------------------------- network / orders
def save_network(path: Path, network: RoadNetwork) -> None:
    np.savez_compressed(path, node_id=network.node_id, lon=network.lon, lat=network.lat, arc_tail=network.arc_tail,
                        arc_head=network.arc_head, arc_length_m=network.arc_length_m,
                        arc_link_id=network.arc_link_id, name=np.array(network.name))


def load_network(path: Path) -> RoadNetwork:
    if not path.is_file():
        raise ResultsError(f"results file {str(path)!r} is missing")
    z = np.load(path)
    ids = z["node_id"]
    tables = NetworkTables(name=str(z["name"]), node_id=ids, lon=z["lon"], lat=z["lat"],
                           arc_from=ids[z["arc_tail"]], arc_to=ids[z["arc_head"]], arc_length_m=z["arc_length_m"],
                           arc_link_id=z["arc_link_id"], source=str(path))
    return RoadNetwork.from_tables(tables)


def save_trajectories(path: Path, traj: dict[str, np.ndarray]) -> None:
    np.savez_compressed(path, **traj)


def load_trajectories(path: Path) -> dict[str, np.ndarray]:
    if not path.is_file():
        raise ResultsError(f"results file {str(path)!r} is missing")
    z = np.load(path)
    return {k: z[k] for k in ("vehicle_offsets", "node", "t_s", "odo_m")}


def read_csv(path: Path) -> pd.DataFrame:
    if not path.is_file():
        raise ResultsError(f"results file {str(path)!r} is missing")
    return pd.read_csv(path)


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
