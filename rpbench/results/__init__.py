"""Results: the folder a run writes, its KPIs, the independent checker, reports and plots.

The package face is the folder API of :mod:`.store` (``from rpbench import
results; results.read_meta(folder)``); :mod:`.metrics` defines the KPIs,
:mod:`.check` re-verifies a folder from its files alone, :mod:`.report` and
:mod:`.plots` render what a folder holds.
"""

from rpbench.results.store import (
    environment,
    git_commit,
    load_network,
    load_trajectories,
    new_results_folder,
    read_csv,
    read_meta,
    run_folders,
    run_names,
    save_network,
    save_trajectories,
    timestamp,
    to_jsonable,
    write_json,
)

__all__ = [
    "environment",
    "git_commit",
    "load_network",
    "load_trajectories",
    "new_results_folder",
    "read_csv",
    "read_meta",
    "run_folders",
    "run_names",
    "save_network",
    "save_trajectories",
    "timestamp",
    "to_jsonable",
    "write_json",
]
