"""The file names of a results folder, shared by the writer, the checker, the reports and ``publish``.

A comparison folder (one scenario, several runs)::

    meta.json                      versions, git commit, scenario, parameters, seed, preset, machine, runs
    kpis.csv                       tidy KPI table: run, kpi, value
    rounds.csv.gz                  per-round solver statistics (model size, build/solve time, status)
    hourly.csv                     per-hour KPIs of every run
    orders.csv.gz                  the scenario's orders (id, request, origin, destination, patience, solo distance)
    fleet.csv.gz                   every vehicle's initial node
    network.npz                    the road network (nodes, arcs, lengths) the runs drove on
    runs/<run>/events.csv.gz       a simulation's event log (request, assign, pickup, dropoff, cancel)
    runs/<run>/trajectories.npz    a simulation's vehicle paths with times and odometers
    runs/<run>/pairs.csv.gz        an offline run's pairs (bound, Oracle-1, Oracle-2)
    report.md                      the report, rendered from the files above, with its figures:
    kpis.png, timeline.png         the headline KPIs per run; waiting, served and pooled passengers over time
    hourly.png                     the KPIs per hour (scenarios of more than two hours)
    *.svg, *.pdf                   every figure again as vector graphics (only with --figures png,svg,pdf)
    table.tex, table.csv           the comparison table as LaTeX (booktabs) and with raw values
    report.html                    the report as one self-contained interactive page, with a map

A parent folder (multi-day run, sweep) holds one comparison folder per day
or point, its own ``meta.json`` and ``report.md``, and ``by_day.csv`` and
``summary.csv`` (multi-day) or ``sweep.csv`` (sweep).  An evaluation (``rpbench evaluate``) holds one
comparison folder per (day, seed), ``units.csv`` (their KPIs), ``leaderboard.csv`` and ``paired.csv``.
A published light copy (``rpbench publish``) keeps no ``runs/`` nor inputs (:data:`HEAVY`) and
adds ``check.txt``, the checker's verdict on the full folder.
"""

from __future__ import annotations

from pathlib import Path

META = "meta.json"
KPIS = "kpis.csv"
ROUNDS = "rounds.csv.gz"
HOURLY = "hourly.csv"
ORDERS = "orders.csv.gz"
FLEET = "fleet.csv.gz"
NETWORK = "network.npz"
REPORT = "report.md"
REPORT_HTML = "report.html"
RUNS = "runs"
EVENTS = "events.csv.gz"
TRAJECTORIES = "trajectories.npz"
PAIRS = "pairs.csv.gz"
BY_DAY = "by_day.csv"
SUMMARY = "summary.csv"
SWEEP = "sweep.csv"
UNITS = "units.csv"
LEADERBOARD = "leaderboard.csv"
PAIRED = "paired.csv"
CHECK = "check.txt"
KPIS_PNG = "kpis.png"
TIMELINE_PNG = "timeline.png"
HOURLY_PNG = "hourly.png"
TABLE_TEX = "table.tex"
TABLE_CSV = "table.csv"
#: The vector copies of a figure, written beside its PNG on request (``--figures``; for papers).
VECTOR_SUFFIXES = (".svg", ".pdf")

#: The kinds of folder that hold other results folders (their children), not runs of their own.
PARENT_KINDS = ("multi-day", "sweep", "evaluate")

#: Inputs and logs a published light copy leaves out (the checker's raw material; the recorded command
#: regenerates them).
HEAVY = (RUNS, ORDERS, NETWORK, FLEET)

# A replication folder (``rpbench replicate``): the authors' and rpbench's passenger records of each run, and
# each run of rpbench's own engine as a comparison folder.
RECORDS_DIR = "records"
ENGINES_DIR = "engines"


def engine_folder(folder: Path, date: str, strategy: str, engine: str) -> Path:
    """Where a replication folder keeps one run of rpbench's own engine (a results folder)."""
    return folder / ENGINES_DIR / f"{date}_{strategy}_{engine}"


def records_file(folder: Path, date: str, strategy: str, engine: str) -> Path:
    """Where a replication folder keeps one run's passenger records."""
    return folder / RECORDS_DIR / f"{date}_{strategy}_{engine}.csv.gz"
