"""Independent verification of a results folder from its own files alone.

The checker re-reads what the folder stores — orders, network, fleet, every
event log, trajectory and oracle pair list, the reported tables — never the
data folder, the simulator's state or the KPI code a run used
(:mod:`rpbench.results.metrics`), and recomputes every number a reader is
shown.  ``docs/guarantees.md`` says what it proves and what it trusts.

Folder checks (reported as the run ``(folder)``):

* ``manifest`` — the runs meta.json lists are exactly the ``runs/`` folders
  (a multi-day or sweep parent: every listed day or point folder is there);
* ``inputs-digest`` — the SHA-256 of orders.csv.gz, fleet.csv.gz,
  network.npz, of the parameters and of each run's options and rules equal
  the digest recorded at run time (skipped, and said so, for older folders);
* ``orders`` — orders in request order, stored solo distances = shortest
  paths of the folder's network;
* ``hourly`` — hourly.csv recomputed from the event logs and odometers;
* ``report`` — the KPI tables of report.md are the rendering of kpis.csv;
* ``parent-tables`` — a multi-day or sweep parent's tables are its children's KPIs.

Simulation runs:

* ``event-log`` — every event has a known kind, a finite time, an existing
  order, vehicle and node; one request per order at its request time and
  origin; pick-ups and cancellations at the origin, drop-offs at the
  destination; each partner named consistently;
* ``assigned-once`` — each order is assigned at most once, never after it
  was cancelled, and cancelled only when unassigned at request + K_p;
* ``within-patience`` — assignment happens between the request and request + K_p;
* ``service`` — every assigned passenger is picked up after assignment and
  dropped off after pick-up, by the assigned vehicle, and the vehicle passes
  the passenger's origin / destination node at exactly those times;
* ``max-pickup`` — pick-up distance <= R̄ (driven from the assignment, or
  from the partner's pick-up when the partner was collected first, A14);
* ``max-detour`` — ride distance - solo distance <= D̄ for every passenger;
* ``capacity`` — at most two passengers assigned-or-on-board at once, at
  most two on board, partners on the same vehicle;
* ``movement`` — finite trajectories that start at the vehicle's initial
  node, follow arcs of the network, with odometer steps equal to arc lengths
  and time steps of at least length / speed, times non-decreasing;
* ``kpi`` — every KPI of kpis.csv equals its recomputation by this module's
  own code from the event log and the odometers; none missing, unknown or text;
* ``bound-certificate`` — every pair the run formed is an edge of the upper
  bound's graph (docs/bound.md) whose weight covers its realised saving (read
  off the odometers, + :data:`CERT_TOL_M`); with a ``bound`` run in the
  folder, the run's saving is at most the bound.

Oracle runs (``pairs.csv.gz``): ``oracle-rules`` (the recorded pair rules are
the folder's parameters), ``oracle-pairs`` (a matching of pairs inside the
rules' time windows — en-route pairs included — whose saving, route length,
detours, shared and pick-up distances are recomputed from the orders and the
network, feasible and in the rule's service and pick-up order; the bound's
pairs are bound edges of the largest weight), ``max-detour`` and ``kpi``
(recomputed from the recomputed pairs; the solver's objective re-summed).

A folder that cannot be read — a file missing, truncated or unparseable, a
column missing or not numeric, meta.json without its parameters — is
*unreadable*: :class:`ResultsError` (``rpbench check`` exit status 2).  A
readable folder whose content breaks a rule fails that check by name (exit
status 1).  Everything is vectorised: loops run per vehicle or per path
position, never per event.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.results.parents import by_day_table, sweep_table
from rpbench.results.replication_audit import audit_folder
from rpbench.results.report import report_markdown
from rpbench.scenarios.base import Params

TOL_M = 1e-6
TOL_S = 1e-6
#: POOL's inclusive detour tolerance (rpbench.geometry.TOLERANCE_M): a detour of exactly D̄ is allowed.
DETOUR_TOL_M = 1e-9
#: A recomputed KPI may differ from the reported one by this much (relative, plus :data:`KPI_ATOL`): this
#: module sums the same odometer readings in another order; a report prints 3 to 6 significant digits.
KPI_RTOL = 1e-8
KPI_ATOL = 1e-6
#: Tolerance of the bound certificate: a realised saving may exceed its edge weight by float rounding only.
CERT_TOL_M = 1e-3
#: The name under which a folder's own checks are reported.
FOLDER = "(folder)"
#: ``rpbench check`` exit statuses.
EXIT_OK, EXIT_FAILED, EXIT_UNREADABLE = 0, 1, 2
PARENT_KINDS = ("multi-day", "sweep")
#: Input files whose bytes meta.json's ``inputs_digest`` pins.
DIGEST_FILES = ("orders.csv.gz", "fleet.csv.gz", "network.npz")
#: The fields of a run's meta.json record that decide what the checker checks (digested per run).
RUN_SPEC_FIELDS = ("kind", "options", "variant", "rules", "status", "unit_m")
EVENT_KINDS = ("request", "assign", "pickup", "dropoff", "cancel", "reposition")
#: Reported figures the files cannot reproduce (timings, sizes of the oracle's enumeration and model, the
#: solver's gap): listed in docs/guarantees.md; any other KPI in kpis.csv must be one the checker recomputes.
UNVERIFIED_KPIS = {
    "simulation": {"wall_s"},
    "oracle": {"candidates", "edges", "gap", "candidates_s", "model_s", "build_s", "solve_s", "extract_s", "total_s"},
}
SIMULATION_KPIS = (
    "orders",
    "served",
    "cancelled",
    "pooled_passengers",
    "pairs",
    "response_rate",
    "pairing_ratio",
    "pairing_ratio_of_orders",
    "platform_profit_cny",
    "platform_profit_alt_cny",
    "avg_response_time_s",
    "avg_pickup_time_s",
    "avg_pickup_distance_m",
    "avg_detour_m",
    "avg_shared_m",
    "total_occupied_km",
    "total_solo_served_km",
    "total_saving_km",
)
ORACLE_KPIS = (
    "orders",
    "pairs",
    "pooled_passengers",
    "pairing_ratio",
    "avg_detour_m",
    "avg_shared_m",
    "total_saving_km",
    "objective_m",
    "bound_m",
    "pairs_bound",
)
#: Saving ratios: against the folder's bound (in kpis.csv) and against Oracle-1 (rendered from kpis.csv).
RATIO_KPIS = ("competitive_ratio_bound", "competitive_ratio")
KNOWN_KPIS = {*SIMULATION_KPIS, *ORACLE_KPIS, *RATIO_KPIS, *UNVERIFIED_KPIS["simulation"], *UNVERIFIED_KPIS["oracle"]}
HOURLY_COLUMNS = (
    "orders",
    "response_rate",
    "pairing_ratio",
    "avg_detour_m",
    "avg_shared_m",
    "total_saving_km",
    "avg_pickup_m",
    "avg_pickup_time_s",
)

# Column schemas: a file lacking a column, or holding text or a missing value in a numeric one, is unreadable.
ORDER_COLUMNS = {
    "order_id": "int",
    "request_s": "float",
    "origin": "int",
    "destination": "int",
    "patience_s": "float",
    "solo_m": "float",
}
FLEET_COLUMNS = {"vehicle": "int", "initial_node": "int"}
EVENT_COLUMNS = {"t_s": "float", "event": "str", "order": "int", "vehicle": "int", "node": "int", "partner": "int"}
PAIR_COLUMNS = {
    "first_id": "int",
    "second_id": "int",
    "first_request_s": "float",
    "second_request_s": "float",
    "service_order": "str",
    "enroute": "bool",
    "saving_m": "float",
    "length_m": "float",
    "detour_first_m": "float",
    "detour_second_m": "float",
    "shared_m": "float",
    "pickup_m": "float",
}
KPI_COLUMNS = {"run": "str", "kpi": "str", "value": "raw"}
RULE_NUMBERS = ("planner_patience_s", "max_detour_m", "max_pickup_m", "speed_mps")
RULE_FLAGS = ("both_pickup_orders", "pickup_check", "allow_enroute")


@dataclass
class RunCheck:
    """The verdict on one run (or, named :data:`FOLDER`, on the folder's own files)."""

    run: str
    violations: dict[str, list[str]] = field(default_factory=dict)
    checked: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)  # check -> why it could not be made

    def fail(self, check: str, message: str) -> None:
        self.violations.setdefault(check, []).append(message)

    def skip(self, check: str, reason: str) -> None:
        self.skipped[check] = f"{self.skipped[check]}; {reason}" if check in self.skipped else reason

    @property
    def ok(self) -> bool:
        return not self.violations

    @property
    def status(self) -> str:
        return "ok" if self.ok else "failed"


@dataclass
class FolderResult:
    """The verdict on one results folder: its own checks, its runs', or why it could not be read."""

    folder: str
    runs: list[RunCheck] = field(default_factory=list)
    folder_check: RunCheck | None = None
    error: str | None = None  # one line: the folder is unreadable

    @property
    def checks(self) -> list[RunCheck]:
        return ([self.folder_check] if self.folder_check is not None else []) + self.runs

    @property
    def status(self) -> str:
        if self.error is not None:
            return "unreadable"
        return "ok" if all(c.ok for c in self.checks) else "failed"


def exit_status(found: list[FolderResult]) -> int:
    """2 when some folder is unreadable, else 1 when some check failed, else 0."""
    if any(r.error is not None for r in found):
        return EXIT_UNREADABLE
    return EXIT_FAILED if any(r.status == "failed" for r in found) else EXIT_OK


# ------------------------------------------------------------------ entry points
def check_tree(path: str | Path) -> list[FolderResult]:
    """Check a results folder, or a multi-day / sweep parent (its own files, then every child folder);
    an unreadable folder is a :class:`FolderResult` with ``error`` set, never an exception."""
    path = Path(path)
    if not path.is_dir():
        return [FolderResult(str(path), error=f"results folder {str(path)!r} does not exist")]
    meta = None
    if (path / "meta.json").exists():
        try:
            meta = results.read_meta(path)
        except RpbenchError as exc:
            return [FolderResult(str(path), error=one_line(exc))]
    if meta is not None and meta.get("kind") == "replication":
        return [_check_replication(path)]
    if meta is not None and meta.get("kind") in PARENT_KINDS:
        parent, children = _check_parent(path, meta)
        return [parent] + [check_results(child) for child in children]
    return [check_results(folder) for folder in results.run_folders(path)]


def _check_replication(folder: Path) -> FolderResult:
    """A ``rpbench replicate`` folder: the checks that apply to the authors' engine, the rest skipped by
    name with the reason (:mod:`rpbench.results.replication_audit`)."""
    out = FolderResult(str(folder))
    try:
        for name, violations, checked, skipped in audit_folder(folder):
            out.runs.append(RunCheck(name, violations=violations, checked=checked, skipped=skipped))
    except RpbenchError as exc:
        out.error = one_line(exc)
    return out


def check_results(folder: str | Path) -> FolderResult:
    """Check one results folder (a comparison: ``runs/<name>/``); never raises on a malformed folder."""
    out = FolderResult(str(folder))
    try:
        with np.errstate(all="ignore"):  # absurd values (1e300 s) must not print numpy warnings
            out.folder_check, out.runs = _check_comparison(Path(folder))
    except RpbenchError as exc:
        out.error = one_line(exc)
    return out


def check_folder(folder: str | Path) -> list[RunCheck]:
    """Check every run of a results folder; one :class:`RunCheck` per run, preceded by the folder's own
    checks (run :data:`FOLDER`) when one of them failed.  Raises :class:`ResultsError` when the folder is
    unreadable."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ResultsError(f"results folder {str(folder)!r} does not exist")
    found = check_results(folder)
    if found.error is not None:
        raise ResultsError(found.error)
    return ([found.folder_check] if not found.folder_check.ok else []) + found.runs


def _check_comparison(folder: Path) -> tuple[RunCheck, list[RunCheck]]:
    f = _read_folder(folder)
    fc = RunCheck(FOLDER)
    names = _check_manifest(fc, f)
    _check_digest(fc, f)
    _check_orders(fc, f)
    bound_km = _bound_km(f)
    runs, hourly = [], {}
    for name in names:
        rc, table = _check_run(f, name, bound_km)
        runs.append(rc)
        if table is not None:
            hourly[name] = table
    if not any(f.meta["runs"][name]["kind"] == "simulation" for name in names):
        hourly = {}  # hourly.csv is written for the strategy runs (and then the bound's split)
    per_hour = {
        name
        for name in names
        if f.meta["runs"][name]["kind"] == "simulation"
        or f.meta["runs"][name].get("rules", {}).get("window") == "bound"
    }
    _check_hourly(fc, f, runs, hourly, per_hour)
    _check_report(fc, f)
    return fc, runs


def _check_run(f: _Folder, name: str, bound_km: float | None) -> tuple[RunCheck, pd.DataFrame | None]:
    """One run's checks, and its expected rows of hourly.csv (None: an oracle without any).  A malformation
    this module did not foresee makes the run unreadable (exit status 2), never a traceback."""
    run_dir = f.path / "runs" / name
    try:
        if f.meta["runs"][name]["kind"] == "oracle":
            return _check_oracle(f, name, run_dir)
        return _check_simulation(f, name, run_dir, bound_km)
    except RpbenchError:
        raise
    except (ValueError, TypeError, KeyError, IndexError, OverflowError, AttributeError) as exc:
        raise ResultsError(f"{str(run_dir)!r} cannot be checked: {type(exc).__name__}: {one_line(exc)}") from None


# ----------------------------------------------------------------------- digest
def inputs_digest(folder: str | Path, params: dict, runs: dict) -> dict:
    """What meta.json records at run time so that later edits are caught (``inputs-digest``): the SHA-256
    of the input files' bytes, of the parameters and of each run's options and rules (canonical JSON)."""
    return {
        "algorithm": "sha256",
        "files": {name: file_sha256(Path(folder) / name) for name in DIGEST_FILES},
        "params": json_sha256(params),
        "runs": {name: json_sha256(run_spec(record)) for name, record in runs.items()},
    }


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def json_sha256(obj) -> str:
    """SHA-256 of ``obj`` as canonical JSON (sorted keys; what meta.json holds reads back to the same text)."""
    text = json.dumps(results.to_jsonable(obj), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def run_spec(record: dict) -> dict:
    """The fields of a run's meta.json record that decide what is checked (options, rules, status)."""
    return {k: record[k] for k in RUN_SPEC_FIELDS if k in record}


# ---------------------------------------------------------------------- reading
@dataclass
class _Folder:
    """A comparison folder's inputs, read and validated once."""

    path: Path
    meta: dict
    params: Params
    orders: pd.DataFrame
    fleet: pd.DataFrame
    network: object
    distances: object
    solo: np.ndarray
    kpis: pd.DataFrame

    @property
    def n(self) -> int:
        return len(self.orders)

    def col(self, name: str) -> np.ndarray:
        return self.orders[name].to_numpy()

    def reported(self, run: str) -> pd.DataFrame:
        return self.kpis[self.kpis["run"] == run]


def _read_folder(folder: Path) -> _Folder:
    meta = results.read_meta(folder)
    if not (folder / "runs").is_dir() and (folder / "check.txt").is_file():
        raise ResultsError(
            f"{str(folder)!r} is a published light copy without event logs or inputs: check.txt holds "
            "the verdict on the full folder; rerun the command in its meta.json to check it again"
        )
    params = _read_params(folder, meta)
    _read_run_records(folder, meta)
    network = results.load_network(folder / "network.npz")
    orders = _read_table(folder / "orders.csv.gz", ORDER_COLUMNS)
    _require(
        folder / "orders.csv.gz",
        orders,
        network.n_nodes,
        nodes=("origin", "destination"),
        finite=("request_s", "patience_s", "solo_m"),
    )
    if orders["order_id"].duplicated().any():
        raise ResultsError(
            f"results file {str(folder / 'orders.csv.gz')!r}: order ids repeat "
            f"(e.g. {int(orders['order_id'][orders['order_id'].duplicated()].iloc[0])})"
        )
    fleet = _read_table(folder / "fleet.csv.gz", FLEET_COLUMNS)
    _require(folder / "fleet.csv.gz", fleet, network.n_nodes, nodes=("initial_node",), finite=())
    if not np.array_equal(fleet["vehicle"].to_numpy(), np.arange(len(fleet))):
        raise ResultsError(
            f"results file {str(folder / 'fleet.csv.gz')!r}: vehicles are not numbered 0..{len(fleet) - 1}"
        )
    kpis = _read_table(folder / "kpis.csv", KPI_COLUMNS)
    distances = network.distances()
    solo = distances.dist[orders["origin"].to_numpy(), orders["destination"].to_numpy()]
    return _Folder(folder, meta, params, orders, fleet, network, distances, solo, kpis)


def _read_params(folder: Path, meta: dict) -> Params:
    """The run's parameters, all of them: a missing one is not replaced by its default (it may be the
    threshold a violation hides behind), an unknown one is not ignored."""
    where = str(folder / "meta.json")
    raw = meta.get("params")
    if not isinstance(raw, dict):
        raise ResultsError(f"{where!r} has no params: the parameters the runs used cannot be known")
    known = [f.name for f in fields(Params)]
    missing = [k for k in known if k not in raw]
    unknown = sorted(set(raw) - set(known))
    if missing:
        raise ResultsError(f"{where!r}: params lack {', '.join(missing)} (the checker assumes no default)")
    if unknown:
        raise ResultsError(
            f"{where!r}: params hold unknown parameter(s) {', '.join(unknown)} (written by another rpbench version?)"
        )
    if any(isinstance(v, bool) for v in raw.values()):
        raise ResultsError(f"{where!r}: params must be numbers, not true/false")
    try:
        return Params(**raw)
    except (RpbenchError, TypeError) as exc:
        raise ResultsError(f"{where!r}: params: {one_line(exc)}") from None


def _read_run_records(folder: Path, meta: dict) -> None:
    """Each run's record in meta.json: its kind, and an oracle's pair rules (the checker tests pairs by them)."""
    where = str(folder / "meta.json")
    runs = meta.get("runs")
    if not isinstance(runs, dict) or not all(isinstance(r, dict) for r in runs.values()):
        raise ResultsError(f"{where!r} has no runs record (a mapping of run name to facts)")
    for name, rec in runs.items():
        if rec.get("kind") not in ("simulation", "oracle"):
            raise ResultsError(f"{where!r}: run {name!r} has kind {rec.get('kind')!r}, not simulation or oracle")
        if rec["kind"] != "oracle":
            continue
        rules = rec.get("rules")
        ok = (
            isinstance(rules, dict)
            and all(isinstance(rules.get(k), (int, float)) and not isinstance(rules.get(k), bool) for k in RULE_NUMBERS)
            and all(isinstance(rules.get(k), bool) for k in RULE_FLAGS)
        )
        if not ok:
            raise ResultsError(
                f"{where!r}: oracle run {name!r} lacks its pair rules ({', '.join(RULE_NUMBERS)} "
                f"as numbers, {', '.join(RULE_FLAGS)} as true/false)"
            )
        if not isinstance(rec.get("unit_m", 0.01), (int, float)) or not rec.get("unit_m", 0.01) > 0:
            raise ResultsError(f"{where!r}: oracle run {name!r}: unit_m must be a positive number")


def _read_table(path: Path, columns: dict[str, str]) -> pd.DataFrame:
    """A CSV results file with ``columns`` coerced to their kinds (``int``, ``float``, ``bool``, ``str``,
    ``raw``: as read); anything else is one :class:`ResultsError` line."""
    table = results.read_csv(path)
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ResultsError(f"results file {str(path)!r} lacks the column(s) {', '.join(missing)}")
    for name, kind in columns.items():
        table[name] = _coerce(path, name, table[name], kind)
    return table


def _coerce(path: Path, name: str, col: pd.Series, kind: str) -> pd.Series:
    if kind == "raw":
        return col
    if kind == "str":
        return col.fillna("").astype(str)  # an empty cell is the empty text, never NaN
    if kind == "bool":
        if col.dtype == bool:
            return col
        mapped = col.map({True: True, False: False, "True": True, "False": False, "true": True, "false": False})
        if mapped.isna().any():
            raise ResultsError(
                f"results file {str(path)!r}: column {name!r} holds {col[mapped.isna()].iloc[0]!r}, not True/False"
            )
        return mapped.astype(bool)
    if kind == "int" and pd.api.types.is_integer_dtype(col.dtype):
        return col.astype(np.int64)
    if kind == "float" and pd.api.types.is_float_dtype(col.dtype):
        return col
    number = pd.to_numeric(col, errors="coerce")
    text = number.isna() & col.notna()
    if text.any():
        raise ResultsError(
            f"results file {str(path)!r}: column {name!r} holds {col[text].iloc[0]!r}, not a number "
            f"(row {int(np.flatnonzero(text)[0]) + 2})"
        )
    if kind == "float":
        return number.astype(np.float64)
    values = number.to_numpy(dtype=np.float64)
    if not np.isfinite(values).all() or (values != np.round(values)).any():
        raise ResultsError(f"results file {str(path)!r}: column {name!r} holds missing or non-integer values")
    return number.astype(np.int64)


def _require(path: Path, table: pd.DataFrame, n_nodes: int, *, nodes: tuple, finite: tuple) -> None:
    """Inputs every check reads: node indices of the network, finite numbers."""
    for name in nodes:
        values = table[name].to_numpy()
        if len(values) and (values.min() < 0 or values.max() >= n_nodes):
            raise ResultsError(
                f"results file {str(path)!r}: column {name!r} names a node outside the network's 0..{n_nodes - 1}"
            )
    for name in finite:
        if not np.isfinite(table[name].to_numpy()).all():
            raise ResultsError(f"results file {str(path)!r}: column {name!r} holds NaN or infinite values")


def _as_number(value) -> float | None:
    """A reported value as a float (NaN for an empty cell), None when it is text."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number


def _show(value) -> str:
    """A value for a message: a number as a plain float (not ``np.float64(...)``), text quoted."""
    number = _as_number(value)
    return repr(number) if number is not None else repr(str(value))


def _same(reported: float, value: float, rtol: float = KPI_RTOL, atol: float = KPI_ATOL) -> bool:
    """Equal up to the tolerance; two NaN (an undefined KPI, reported empty) are equal."""
    if np.isnan(reported) or np.isnan(value):
        return bool(np.isnan(reported) and np.isnan(value))
    return bool(np.isclose(reported, value, rtol=rtol, atol=atol))


# ----------------------------------------------------------------- folder checks
def _listed_runs(meta: dict) -> list[str] | None:
    """The run manifest: ``manifest.runs`` (recorded since rpbench writes one), else the keys of ``runs``,
    written at run time by every version; None when the manifest is malformed."""
    manifest = meta.get("manifest")
    if manifest is None:
        return list(meta["runs"])
    if not (isinstance(manifest, dict) and isinstance(manifest.get("runs"), list)):
        return None
    return [str(r) for r in manifest["runs"]]


def _check_manifest(fc: RunCheck, f: _Folder) -> list[str]:
    """A deleted or added run folder fails here; returns the runs to check (listed, present, recorded)."""
    listed = _listed_runs(f.meta)
    present = results.run_names(f.path)
    if listed is None:
        fc.fail("manifest", 'meta.json\'s manifest is malformed (expected {"runs": [run names]})')
        listed = list(f.meta["runs"])
    if not listed and not present:
        raise ResultsError(f"results folder {str(f.path)!r} holds no runs (no runs/<name>/ folders)")
    for name in listed:
        if name not in present:
            fc.fail("manifest", f"run {name!r} listed in meta.json has no folder runs/{name}/ (deleted?)")
        if name not in f.meta["runs"]:
            fc.fail("manifest", f"run {name!r} is listed in the manifest but has no record in meta.json's runs")
    for name in present:
        if name not in listed:
            fc.fail("manifest", f"runs/{name}/ is not a run meta.json lists")
    strategies = f.meta.get("strategies")
    if isinstance(strategies, list) and sorted(map(str, strategies)) != sorted(listed):
        fc.fail(
            "manifest",
            f"meta.json's strategies ({', '.join(map(str, strategies))}) are not its runs ({', '.join(listed)})",
        )
    stray = sorted(set(f.kpis["run"]) - set(listed))
    if stray:
        fc.fail("manifest", f"kpis.csv reports run(s) {', '.join(map(repr, stray))} that meta.json does not list")
    fc.checked["runs"] = len(listed)
    return [name for name in listed if name in present and name in f.meta["runs"]]


def _check_digest(fc: RunCheck, f: _Folder) -> None:
    """The inputs, parameters and run options are those of the run: an edited file or a relaxed parameter
    (say max_detour_m raised to hide a violation) changes its SHA-256."""
    recorded = f.meta.get("inputs_digest")
    if recorded is None and "manifest" in f.meta:
        fc.fail(
            "inputs-digest",
            "meta.json has a manifest but no inputs_digest: rpbench writes both, so the digest was removed",
        )
        return
    if recorded is None:
        fc.skip(
            "inputs-digest",
            "meta.json records no inputs digest (a folder written before rpbench recorded "
            "one): edited inputs or parameters are caught only where another check breaks",
        )
        return
    if not (
        isinstance(recorded, dict)
        and isinstance(recorded.get("files"), dict)
        and isinstance(recorded.get("runs"), dict)
        and recorded.get("algorithm") == "sha256"
    ):
        fc.fail("inputs-digest", "meta.json's inputs_digest is malformed (files, params, runs of sha256 digests)")
        return
    actual = inputs_digest(f.path, f.meta["params"], f.meta["runs"])
    for name, digest in actual["files"].items():
        if recorded["files"].get(name) != digest:
            fc.fail("inputs-digest", f"{name} is not the file the run wrote (its SHA-256 differs from meta.json's)")
    if recorded.get("params") != actual["params"]:
        fc.fail("inputs-digest", "meta.json's params are not those of the run (their SHA-256 differs)")
    for name in sorted(set(actual["runs"]) | set(recorded["runs"])):
        if recorded["runs"].get(name) != actual["runs"].get(name):
            fc.fail(
                "inputs-digest",
                f"run {name!r}: its options/rules in meta.json are not those of the run "
                "(SHA-256 differs, or the run is not in the digest)",
            )
    fc.checked["digests"] = len(actual["files"]) + 1 + len(actual["runs"])


def _check_orders(fc: RunCheck, f: _Folder) -> None:
    request = f.col("request_s")
    if (np.diff(request) < 0).any():
        fc.fail("orders", "orders.csv.gz is not in request-time order")
    bad = np.flatnonzero(np.abs(f.col("solo_m") - f.solo) > TOL_M)
    if len(bad):
        fc.fail(
            "orders",
            f"{len(bad)} orders' stored solo distances differ from the shortest paths of the folder's "
            f"network, e.g. order {bad[0]}: {f.col('solo_m')[bad[0]]:.3f} m, network "
            f"{f.solo[bad[0]]:.3f} m",
        )
    if (f.col("patience_s") <= 0).any():
        fc.fail("orders", "an order has a patience <= 0")
    fc.checked["orders"] = f.n


def _bound_km(f: _Folder) -> float | None:
    """The reported upper bound (km) when the folder has a bound run (its own check verifies it)."""
    for name, run in f.meta["runs"].items():
        if run.get("kind") == "oracle" and run.get("rules", {}).get("window") == "bound":
            value = f.reported(name)
            value = value[value["kpi"] == "total_saving_km"]["value"]
            number = _as_number(value.iloc[0]) if len(value) else None
            return float("nan") if number is None else number
    return None


# ------------------------------------------------------------- simulation runs
def _check_simulation(
    f: _Folder, name: str, run_dir: Path, bound_km: float | None
) -> tuple[RunCheck, pd.DataFrame | None]:
    rc = RunCheck(name)
    events = _read_table(run_dir / "events.csv.gz", EVENT_COLUMNS)
    traj = results.load_trajectories(run_dir / "trajectories.npz")
    if not _check_movement(rc, traj, f.network, f.fleet["initial_node"].to_numpy(), f.params):
        for check in ("service", "max-pickup", "max-detour", "kpi", "bound-certificate", "hourly"):
            rc.skip(check, "the trajectories cannot be read per vehicle (see [movement])")
        return rc, None
    events = _check_event_log(rc, events, f, len(f.fleet))
    tab = _check_events(rc, events, f, traj)
    kpis = _simulation_kpis(tab, f.solo, f.params, bound_km)
    _compare_kpis(rc, "simulation", kpis, f.reported(name))
    _check_certificate(rc, tab, f, kpis["total_saving_km"], bound_km)
    rc.checked["orders"] = f.n
    rc.checked["served"] = int(tab["served"].sum())
    return rc, _hourly_expected(tab, f.solo)


# --------------------------------------------------------------------- movement
def _check_movement(rc: RunCheck, traj, network, initial: np.ndarray, params: Params) -> bool:
    """Vehicles drive network arcs at no more than the set speed; False when the trajectories cannot even
    be split per vehicle (then nothing else of the run can be checked)."""
    off = traj["vehicle_offsets"].astype(np.int64)
    nodes, t, odo = traj["node"].astype(np.int64), traj["t_s"].astype(np.float64), traj["odo_m"].astype(np.float64)
    if len(off) - 1 != len(initial):
        rc.fail("movement", f"{len(off) - 1} trajectories for {len(initial)} vehicles")
        return False
    if off[0] != 0 or off[-1] != len(nodes) or (np.diff(off) < 1).any():
        rc.fail("movement", "the trajectory offsets do not split the entries into one non-empty trajectory per vehicle")
        return False
    bad = ~np.isfinite(t) | ~np.isfinite(odo)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        rc.fail(
            "movement",
            f"{int(bad.sum())} trajectory entries have a non-finite time or odometer (NaN or inf), "
            f"e.g. entry {k}: t = {_show(t[k])}, odo = {_show(odo[k])}",
        )
    outside = (nodes < 0) | (nodes >= network.n_nodes)
    if outside.any():
        rc.fail(
            "movement",
            f"{int(outside.sum())} trajectory entries name a node outside the network, e.g. "
            f"{nodes[np.flatnonzero(outside)[0]]}",
        )
    starts = off[:-1]
    bad_start = np.flatnonzero((nodes[starts] != initial) | ~(np.abs(t[starts]) <= TOL_S))
    for v in bad_start[:5]:
        rc.fail("movement", f"vehicle {v} does not start at its initial node {initial[v]} at t=0")
    step = np.ones(len(nodes), dtype=bool)
    step[off[1:] - 1] = False  # no step across vehicles (nor past the last entry)
    i = np.flatnonzero(step)
    u, w = nodes[i], nodes[i + 1]
    dt, dodo = t[i + 1] - t[i], odo[i + 1] - odo[i]
    if (dt < -TOL_S).any():
        k = i[np.flatnonzero(dt < -TOL_S)[0]]
        rc.fail("movement", f"time runs backwards in trajectory entry {k}")
    stay = u == w
    if (np.abs(dodo[stay]) > TOL_M).any():
        rc.fail("movement", f"{int((np.abs(dodo[stay]) > TOL_M).sum())} standing steps change the odometer")
    move = ~stay
    arc = network.arc_index(u[move], w[move])
    if (arc < 0).any():
        k = np.flatnonzero(arc < 0)[0]
        rc.fail("movement", f"{int((arc < 0).sum())} steps are not network arcs, e.g. {u[move][k]} -> {w[move][k]}")
    else:
        length = network.arc_length_m[arc]
        wrong = np.abs(dodo[move] - length) > TOL_M
        if wrong.any():
            k = np.flatnonzero(wrong)[0]
            rc.fail(
                "movement",
                f"{int(wrong.sum())} steps' odometer differs from the arc length, e.g. entry "
                f"{i[move][k]}: {dodo[move][k]:.3f} m on an arc of {length[k]:.3f} m",
            )
        too_fast = dt[move] < length / params.speed_mps - TOL_S
        if too_fast.any():
            rc.fail("movement", f"{int(too_fast.sum())} arcs driven faster than {params.speed_mps:.4f} m/s")
    rc.checked["trajectory_steps"] = len(i)
    return True


def _by_vehicle(vehicle: np.ndarray):
    """(vehicle, positions) groups of the queries with ``vehicle >= 0``: one vectorised step per vehicle."""
    q = np.flatnonzero(vehicle >= 0)
    q = q[np.argsort(vehicle[q], kind="stable")]
    cut = np.flatnonzero(np.diff(vehicle[q])) + 1
    for group in np.split(q, cut) if len(q) else []:
        yield int(vehicle[group[0]]), group


def _locate(traj, vehicle: np.ndarray, t: np.ndarray, node: np.ndarray) -> np.ndarray:
    """Odometer at the trajectory entry where ``vehicle`` is at ``node`` within TOL_S of time ``t`` (NaN if none)."""
    off, ts, nodes, odo = traj["vehicle_offsets"], traj["t_s"], traj["node"], traj["odo_m"]
    vehicle = np.where(np.isfinite(t), vehicle, -1)
    lo = np.zeros(len(vehicle), dtype=np.int64)
    hi = np.zeros(len(vehicle), dtype=np.int64)
    for v, group in _by_vehicle(vehicle):
        a, b = off[v], off[v + 1]
        lo[group] = a + np.searchsorted(ts[a:b], t[group] - TOL_S, side="left")
        hi[group] = a + np.searchsorted(ts[a:b], t[group] + TOL_S, side="right")
    out = np.full(len(vehicle), np.nan)
    active = np.flatnonzero(lo < hi)
    while len(active):  # entries within TOL_S of t: a handful per query
        k = lo[active]
        hit = nodes[k] == node[active]
        out[active[hit]] = odo[k[hit]]
        lo[active] += 1
        active = active[~hit & (lo[active] < hi[active])]
    return out


def _odometer_at(traj, vehicle: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Odometer of ``vehicle`` at time ``t``, linear between trajectory entries (NaN where vehicle < 0)."""
    off = traj["vehicle_offsets"]
    out = np.full(len(vehicle), np.nan)
    for v, group in _by_vehicle(np.where(np.isnan(t), -1, vehicle)):
        a, b = off[v], off[v + 1]
        out[group] = np.interp(t[group], traj["t_s"][a:b], traj["odo_m"][a:b])
    return out


# -------------------------------------------------------------------- event log
def _check_event_log(rc: RunCheck, events: pd.DataFrame, f: _Folder, n_vehicles: int) -> pd.DataFrame:
    """Every event names things that exist; returns the events that do (the others fail ``event-log``)."""
    kind = events["event"].to_numpy()
    order, vehicle = events["order"].to_numpy(), events["vehicle"].to_numpy()
    node, partner, t = events["node"].to_numpy(), events["partner"].to_numpy(), events["t_s"].to_numpy()
    n = f.n
    known = np.isin(kind, EVENT_KINDS)
    of_order = known & (kind != "reposition")
    unvehicled = np.isin(kind, ("request", "cancel"))
    problems = {
        "an unknown event kind": ~known,
        "a time that is not finite": known & ~np.isfinite(t),
        f"an order outside 0..{n - 1}": of_order & ((order < 0) | (order >= n)),
        "an order (a reposition names none)": (kind == "reposition") & (order != -1),
        f"a vehicle outside 0..{n_vehicles - 1}": known & ~unvehicled & ((vehicle < 0) | (vehicle >= n_vehicles)),
        "a vehicle (a request or cancellation names none)": unvehicled & (vehicle != -1),
        "a node outside the network": known & (kind != "assign") & ((node < 0) | (node >= f.network.n_nodes)),
        "a partner that is not another order": (partner != -1)
        & ((kind != "assign") | (partner < 0) | (partner >= n) | (partner == order)),
    }
    valid = np.ones(len(events), dtype=bool)
    for what, bad in problems.items():
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            rc.fail(
                "event-log",
                f"{int(bad.sum())} events name {what}, e.g. row {k + 2}: {kind[k]} of order "
                f"{order[k]}, vehicle {vehicle[k]}, node {node[k]}, partner {partner[k]} "
                f"at t={_show(t[k])}",
            )
            valid &= ~bad
    ev = events[valid]
    _check_event_places(rc, ev, f)
    return ev


def _check_event_places(rc: RunCheck, ev: pd.DataFrame, f: _Folder) -> None:
    """One request per order, at its request time; requests, pick-ups and cancellations at the origin,
    drop-offs at the destination (the node column of the log is what a reader of it sees)."""
    origin, dest, request = f.col("origin"), f.col("destination"), f.col("request_s")
    req = ev[ev["event"] == "request"]
    counts = np.bincount(req["order"].to_numpy(), minlength=f.n)
    wrong = np.flatnonzero(counts != 1)
    if len(wrong):
        rc.fail(
            "event-log",
            f"{len(wrong)} orders do not have exactly one request event, e.g. order {wrong[0]}: {counts[wrong[0]]}",
        )
    o, t = req["order"].to_numpy(), req["t_s"].to_numpy()
    late = np.flatnonzero(np.abs(t - request[o]) > TOL_S)
    if len(late):
        k = late[0]
        rc.fail(
            "event-log",
            f"{len(late)} request events are not at the order's request time, e.g. order {o[k]}: "
            f"{t[k]:.3f} s in the log, {request[o[k]]:.3f} s in orders.csv.gz",
        )
    for kind, where, label in (
        ("request", origin, "origin"),
        ("pickup", origin, "origin"),
        ("cancel", origin, "origin"),
        ("dropoff", dest, "destination"),
    ):
        sel = ev[ev["event"] == kind]
        o, node = sel["order"].to_numpy(), sel["node"].to_numpy()
        bad = np.flatnonzero(node != where[o])
        if len(bad):
            k = bad[0]
            rc.fail(
                "event-log",
                f"{len(bad)} {kind} events are not at the order's {label}, e.g. order {o[k]} at "
                f"node {node[k]}, its {label} is {where[o[k]]}",
            )


# ----------------------------------------------------------------------- events
def _check_events(rc: RunCheck, events: pd.DataFrame, f: _Folder, traj) -> pd.DataFrame:
    """The service rules, and the per-order table (times, vehicle, partner, odometers) the KPIs are read off."""
    n, params = f.n, f.params
    request, patience = f.col("request_s"), f.col("patience_s")
    origin, dest = f.col("origin"), f.col("destination")

    def times(kind: str) -> tuple[np.ndarray, np.ndarray]:
        sel = events[events["event"] == kind]
        o = sel["order"].to_numpy()
        counts = np.bincount(o, minlength=n)
        col = np.full(n, np.nan)
        col[o] = sel["t_s"].to_numpy()
        veh = np.full(n, -1, dtype=np.int64)
        veh[o] = sel["vehicle"].to_numpy()
        for k in np.flatnonzero(counts > 1)[:5]:
            rc.fail("assigned-once" if kind == "assign" else "service", f"order {k} has {counts[k]} {kind} events")
        return col, veh

    t_assign, v_assign = times("assign")
    t_pick, v_pick = times("pickup")
    t_drop, v_drop = times("dropoff")
    t_cancel, _ = times("cancel")
    assigned = ~np.isnan(t_assign)
    cancelled = ~np.isnan(t_cancel)
    for o in np.flatnonzero(assigned & cancelled)[:5]:
        rc.fail("assigned-once", f"order {o} is both assigned and cancelled")
    bad = cancelled & (np.abs(t_cancel - (request + patience)) > TOL_S)
    for o in np.flatnonzero(bad)[:5]:
        rc.fail("assigned-once", f"order {o} cancelled at {t_cancel[o]:.3f} s, not at request + patience")
    late = assigned & ((t_assign < request - TOL_S) | (t_assign - request > patience + TOL_S))
    for o in np.flatnonzero(late)[:5]:
        rc.fail(
            "within-patience",
            f"order {o} assigned {t_assign[o] - request[o]:.2f} s after its request (patience {patience[o]:.2f} s)",
        )
    unresolved = ~assigned & ~cancelled
    if unresolved.any():
        rc.fail(
            "service",
            f"{int(unresolved.sum())} orders are neither assigned nor cancelled, e.g. order "
            f"{np.flatnonzero(unresolved)[0]}",
        )
    orphan = ~assigned & (~np.isnan(t_pick) | ~np.isnan(t_drop))
    for o in np.flatnonzero(orphan)[:5]:
        rc.fail("service", f"order {o} is picked up or dropped off but never assigned")
    # service by the assigned vehicle, in order, at the right nodes
    not_served = assigned & (np.isnan(t_pick) | np.isnan(t_drop))
    for o in np.flatnonzero(not_served)[:5]:
        rc.fail("service", f"order {o} assigned but never picked up and dropped off")
    wrong = assigned & ~not_served & ((v_pick != v_assign) | (v_drop != v_assign))
    for o in np.flatnonzero(wrong)[:5]:
        rc.fail("service", f"order {o} served by another vehicle than the one assigned")
    order_bad = assigned & ~not_served & ((t_pick < t_assign - TOL_S) | (t_drop < t_pick - TOL_S))
    for o in np.flatnonzero(order_bad)[:5]:
        rc.fail("service", f"order {o}: pick-up before assignment or drop-off before pick-up")
    served = assigned & ~not_served
    odo_pick = _locate(traj, np.where(served, v_assign, -1), t_pick, origin)
    odo_drop = _locate(traj, np.where(served, v_assign, -1), t_drop, dest)
    missing = served & (np.isnan(odo_pick) | np.isnan(odo_drop))
    for o in np.flatnonzero(missing)[:5]:
        rc.fail(
            "service",
            f"order {o}: vehicle {v_assign[o]} is not at the origin/destination node at the pick-up/drop-off time",
        )
    ok = served & ~missing
    detour = odo_drop - odo_pick - f.solo
    over = ok & (detour > params.max_detour_m + TOL_M)
    for o in np.flatnonzero(over)[:5]:
        rc.fail("max-detour", f"order {o}: detour {detour[o]:.1f} m > D̄ = {params.max_detour_m:g} m")
    partner = _partners(rc, events, n, assigned)
    p = np.maximum(partner, 0)
    pair_bad = (partner >= 0) & (v_assign != v_assign[p])
    for o in np.flatnonzero(pair_bad)[:5]:
        rc.fail("capacity", f"order {o} is paired with order {partner[o]} of another vehicle")
    # pick-up distance (A14 rule: from the partner's pick-up when the partner came first)
    partner_first = (partner >= 0) & (t_pick[p] <= t_pick + TOL_S) & ok & ok[p]
    start_t = np.where(partner_first, np.maximum(t_assign, t_pick[p]), t_assign)
    odo_start = _odometer_at(traj, np.where(ok, v_assign, -1), start_t)
    pickup = odo_pick - odo_start
    far = ok & (pickup > params.max_pickup_m + TOL_M)
    for o in np.flatnonzero(far)[:5]:
        rc.fail("max-pickup", f"order {o}: pick-up distance {pickup[o]:.1f} m > R̄ = {params.max_pickup_m:g} m")
    _check_capacity(rc, v_assign, t_assign, t_pick, t_drop, served)
    rc.checked["events"] = len(events)
    return pd.DataFrame(
        {
            "request_s": request,
            "vehicle": v_assign,
            "assign_s": t_assign,
            "pickup_s": t_pick,
            "dropoff_s": t_drop,
            "cancelled": cancelled,
            "served": served,
            "ok": ok,
            "partner": partner,
            "odo_pick": odo_pick,
            "odo_drop": odo_drop,
            "odo_start": odo_start,
        }
    )


def _partners(rc: RunCheck, events: pd.DataFrame, n: int, assigned: np.ndarray) -> np.ndarray:
    """Each order's partner (-1: none).  The joining passenger's assignment names the first one (who may
    name it back): every named pair is two assigned orders, and no order is in two pairs."""
    a = events[events["event"] == "assign"]
    order, named = a["order"].to_numpy(), a["partner"].to_numpy()
    has = named >= 0
    lo, hi = np.minimum(order[has], named[has]), np.maximum(order[has], named[has])
    _, first = np.unique(lo * max(n, 1) + hi, return_index=True)  # a pair named from both sides counts once
    lo, hi = lo[first], hi[first]
    count = np.bincount(np.concatenate([lo, hi]), minlength=n)
    clash = (count[lo] > 1) | (count[hi] > 1) | ~assigned[lo] | ~assigned[hi]
    for k in np.flatnonzero(clash)[:5]:
        rc.fail(
            "event-log",
            f"orders {lo[k]} and {hi[k]} are named partners, but one of them is unassigned or "
            "named in another pair too",
        )
    partner = np.full(n, -1, dtype=np.int64)
    partner[lo[~clash]] = hi[~clash]
    partner[hi[~clash]] = lo[~clash]
    return partner


def _check_capacity(rc: RunCheck, vehicle, t_assign, t_pick, t_drop, served) -> None:
    """At most 2 passengers assigned-or-on-board, and at most 2 on board, per vehicle at any time."""
    o = np.flatnonzero(served)
    if not len(o):
        return
    for label, start in (("assigned or on board", t_assign), ("on board", t_pick)):
        veh = np.concatenate([vehicle[o], vehicle[o]])
        t = np.concatenate([start[o], t_drop[o]])
        delta = np.concatenate([np.ones(len(o)), -np.ones(len(o))])
        # Drop-offs before starts at the same instant: a vehicle can hand over at a node.
        srt = np.lexsort((delta, t, veh))
        load = pd.Series(delta[srt]).groupby(veh[srt]).cumsum().to_numpy()
        if (load > 2).any():
            rc.fail("capacity", f"a vehicle has {int(load.max())} passengers {label} at once")


# ------------------------------------------------------------------------- KPIs
# The KPIs are recomputed here from the per-order table of _check_events (event times, and odometers read
# at the matched trajectory entries), by code of their own: the occupied distance is the union of the
# passengers' odometer intervals per vehicle, the shared distance the overlap of a pair's intervals.
# rpbench.results.metrics (what the run used) steps through pick-up/drop-off events instead.
def _union_length(vehicle: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Total length of the union of the intervals [start, end] of each vehicle (odometer readings)."""
    keep = np.isfinite(start) & np.isfinite(end)
    vehicle, start, end = vehicle[keep], start[keep], end[keep]
    if not len(vehicle):
        return 0.0
    srt = np.lexsort((start, vehicle))
    vehicle, start, end = vehicle[srt], start[srt], end[srt]
    reach = pd.Series(end).groupby(vehicle).cummax().to_numpy()  # furthest end so far, per vehicle
    before = np.r_[-np.inf, reach[:-1]]
    before[np.r_[True, vehicle[1:] != vehicle[:-1]]] = -np.inf
    return float(np.maximum(0.0, end - np.maximum(start, before)).sum())


def _passenger_facts(tab: pd.DataFrame, solo: np.ndarray) -> dict[str, np.ndarray]:
    served = tab["served"].to_numpy()
    partner = tab["partner"].to_numpy()
    pooled = served & (partner >= 0)
    p = np.maximum(partner, 0)
    pick, drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    ride = drop - pick
    shared = np.where(pooled, np.maximum(0.0, np.minimum(drop, drop[p]) - np.maximum(pick, pick[p])), 0.0)
    return {
        "served": served,
        "pooled": pooled,
        "partner": partner,
        "ride": ride,
        "shared": shared,
        "detour": ride - solo,
        "pickup_m": pick - tab["odo_start"].to_numpy(),
        "response_s": (tab["assign_s"] - tab["request_s"]).to_numpy(),
        "pickup_s": (tab["pickup_s"] - tab["assign_s"]).to_numpy(),
    }


def _mean(x: np.ndarray, mask: np.ndarray) -> float:
    return float(x[mask].mean()) if mask.any() else float("nan")


def _simulation_kpis(tab: pd.DataFrame, solo: np.ndarray, params: Params, bound_km: float | None) -> dict:
    """docs/simulator.md's KPI definitions, from the event log and the odometers."""
    x = _passenger_facts(tab, solo)
    served, pooled = x["served"], x["pooled"]
    n, n_served, n_pooled = len(tab), int(served.sum()), int(pooled.sum())
    occupied_km = (
        _union_length(
            tab["vehicle"].to_numpy()[served], tab["odo_pick"].to_numpy()[served], tab["odo_drop"].to_numpy()[served]
        )
        / 1000.0
    )
    solo_km = float(solo[served].sum()) / 1000.0
    fare = np.where(pooled, params.fare_pooled_cny_per_km, params.fare_solo_cny_per_km)
    revenue = float((fare * solo)[served].sum()) / 1000.0
    alt = params.fare_solo_cny_per_km * (x["ride"] - x["shared"]) + params.fare_pooled_cny_per_km * x["shared"]
    pay = params.driver_pay_cny_per_km * occupied_km
    out = {
        "orders": n,
        "served": n_served,
        "cancelled": int(tab["cancelled"].sum()),
        "pooled_passengers": n_pooled,
        "pairs": n_pooled // 2,
        "response_rate": n_served / n if n else float("nan"),
        "pairing_ratio": n_pooled / n_served if n_served else float("nan"),
        "pairing_ratio_of_orders": n_pooled / n if n else float("nan"),
        "platform_profit_cny": revenue - pay,
        "platform_profit_alt_cny": float(alt[served].sum()) / 1000.0 - pay,
        "avg_response_time_s": _mean(x["response_s"], served),
        "avg_pickup_time_s": _mean(x["pickup_s"], served),
        "avg_pickup_distance_m": _mean(x["pickup_m"], served),
        "avg_detour_m": _mean(x["detour"], pooled),
        "avg_shared_m": _mean(x["shared"], pooled),
        "total_occupied_km": occupied_km,
        "total_solo_served_km": solo_km,
        "total_saving_km": solo_km - occupied_km,
    }
    if bound_km is not None:  # the competitive ratio against the folder's proven bound
        out["competitive_ratio_bound"] = out["total_saving_km"] / bound_km if bound_km else float("nan")
    return out


def _compare_kpis(
    rc: RunCheck, kind: str, recomputed: dict, reported: pd.DataFrame, claims: dict | None = None
) -> None:
    """Every recomputed KPI is reported and equal; every reported one is recomputed, a solver claim that
    passed its consistency test (``claims``: key -> failure message or None) or listed as unverifiable."""
    seen: dict[str, float | None] = {}
    for key, value in zip(reported["kpi"].to_numpy(), reported["value"].to_numpy(), strict=True):
        if key in seen:
            rc.fail("kpi", f"KPI {key} is reported twice")
        seen[key] = _as_number(value)
        if seen[key] is None:
            rc.fail("kpi", f"KPI {key}: reported {value!r} is not a number")
    for key, value in recomputed.items():
        if key not in seen:
            rc.fail("kpi", f"KPI {key} is not reported in kpis.csv")
        elif seen[key] is not None and not _same(seen[key], float(value)):
            rc.fail("kpi", f"KPI {key}: reported {seen[key]!r}, recomputed {float(value)!r}")
    for message in (claims or {}).values():
        if message is not None:
            rc.fail("kpi", message)
    allowed = set(recomputed) | set(claims or {}) | UNVERIFIED_KPIS[kind]
    for key in sorted(set(seen) - allowed):
        rc.fail("kpi", f"KPI {key} in kpis.csv is not a KPI rpbench reports for a {kind} run")
    for key in sorted(set(seen) & UNVERIFIED_KPIS[kind]):  # timings and sizes: plausible at least
        if seen[key] is not None and not (np.isnan(seen[key]) or 0 <= seen[key] < np.inf):
            rc.fail("kpi", f"KPI {key}: reported {seen[key]!r}, not a time or size (finite, >= 0)")
    rc.checked["kpis"] = len(recomputed)


# ----------------------------------------------------------------------- hourly
def _hourly_expected(tab: pd.DataFrame, solo: np.ndarray) -> pd.DataFrame:
    """Per request hour (metrics.hourly's definitions): a pair's saving, l_A + l_B - (last drop-off odometer
    - first pick-up odometer), counts in the hour of its earlier request."""
    x = _passenger_facts(tab, solo)
    request = tab["request_s"].to_numpy()
    hour = np.floor(request / 3600.0).astype(np.int64)
    served, pooled, partner = x["served"], x["pooled"], x["partner"]
    lead = np.flatnonzero(pooled & (partner > np.arange(len(tab))))
    b = partner[lead]
    pick, drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    saving = solo[lead] + solo[b] - (np.maximum(drop[lead], drop[b]) - np.minimum(pick[lead], pick[b]))
    pair_hour = np.floor(np.minimum(request[lead], request[b]) / 3600.0).astype(np.int64)
    frame = pd.DataFrame(
        {
            "hour": hour,
            "served": served,
            "pooled": pooled,
            "detour": np.where(pooled, x["detour"], np.nan),
            "shared": np.where(pooled, x["shared"], np.nan),
            "pickup_m": np.where(served, x["pickup_m"], np.nan),
            "pickup_s": np.where(served, x["pickup_s"], np.nan),
        }
    )
    g = frame.groupby("hour")
    n_served = g["served"].sum()
    out = pd.DataFrame(
        {
            "orders": g.size(),
            "response_rate": g["served"].mean(),
            "pairing_ratio": g["pooled"].sum() / n_served.where(n_served > 0),
            "avg_detour_m": g["detour"].mean(),
            "avg_shared_m": g["shared"].mean(),
            "total_saving_km": pd.Series(saving / 1000.0).groupby(pair_hour).sum(),
            "avg_pickup_m": g["pickup_m"].mean(),
            "avg_pickup_time_s": g["pickup_s"].mean(),
        }
    )
    out["total_saving_km"] = out["total_saving_km"].fillna(0.0)
    return out.loc[g.size().index]


def _check_hourly(
    fc: RunCheck, f: _Folder, runs: list[RunCheck], tables: dict[str, pd.DataFrame], per_hour: set[str]
) -> None:
    """hourly.csv (plotted as hourly.png) equals its recomputation ``tables``: a run's wrong rows fail that
    run's ``hourly`` check, rows of a run without per-hour figures (not in ``per_hour``) the folder's."""
    path = f.path / "hourly.csv"
    if not tables:
        return
    if not path.is_file():
        fc.skip("hourly", "the folder has no hourly.csv")
        return
    try:
        hourly = results.read_csv(path)
    except ResultsError as exc:
        fc.fail("hourly", one_line(exc))
        return
    if not {"hour", "run"} <= set(hourly.columns):
        fc.fail("hourly", "hourly.csv lacks its hour or run column")
        return
    hourly = hourly.assign(run=hourly["run"].astype(str), hour=pd.to_numeric(hourly["hour"], errors="coerce"))
    for name in sorted(set(hourly["run"]) - per_hour):
        fc.fail("hourly", f"hourly.csv has rows of run {name!r}, which has no per-hour figures in this folder")
    for rc in runs:
        if rc.run in tables:
            _compare_hourly(rc, hourly[hourly["run"] == rc.run].set_index("hour"), tables[rc.run])


def _compare_hourly(rc: RunCheck, rows: pd.DataFrame, expected: pd.DataFrame) -> None:
    if rows.index.has_duplicates or set(rows.index) != set(expected.index):
        rc.fail(
            "hourly",
            f"hourly.csv has hours {sorted(map(str, rows.index))}, the run's orders request in "
            f"hours {sorted(map(str, expected.index))}",
        )
        return
    for column in expected.columns:
        if column not in rows.columns:
            rc.fail("hourly", f"hourly.csv lacks the column {column}")
            continue
        for hour in expected.index:
            value = _as_number(rows.loc[hour, column])
            if value is None or not _same(value, float(expected.loc[hour, column])):
                rc.fail(
                    "hourly",
                    f"hour {hour}: {column} reported {_show(rows.loc[hour, column])}, recomputed "
                    f"{float(expected.loc[hour, column])!r}",
                )
    rc.checked["hours"] = len(expected)


# ----------------------------------------------------------------------- report
def _check_report(fc: RunCheck, f: _Folder) -> None:
    """The KPI tables of report.md (what most readers read) are the rendering of kpis.csv, which the runs'
    ``kpi`` checks verify: a number edited in report.md alone fails here."""
    path = f.path / "report.md"
    if not path.is_file():
        fc.skip("report", "the folder has no report.md")
        return
    try:
        expected = _metric_tables(report_markdown(f.path, f.path.name))
    except (RpbenchError, KeyError, ValueError, TypeError, IndexError) as exc:
        fc.skip(
            "report",
            f"kpis.csv or meta.json cannot be rendered ({type(exc).__name__}: {one_line(exc)}); the kpi checks say why",
        )
        return
    found = _metric_tables(path.read_text(errors="replace"))
    unmatched = set()
    if len(found) != len(expected):
        unmatched.add(f"({len(found)} KPI tables in report.md, {len(expected)} rendered)")
    for want, have in zip(expected, found, strict=True):
        shown = dict(have)
        for label, cells in want:
            if label not in shown:
                unmatched.add(label)
            elif shown[label] != cells:
                fc.fail(
                    "report",
                    f"report.md shows {label}: {' | '.join(shown[label])}; kpis.csv renders {' | '.join(cells)}",
                )
        unmatched |= set(shown) - {label for label, _ in want}
    if unmatched:  # a row deleted, or worded by another rpbench version: nothing false is shown
        fc.skip(
            "report",
            f"report.md rows not compared (absent from report.md or from today's rendering): "
            f"{', '.join(sorted(unmatched))}",
        )
    fc.checked["report_tables"] = len(expected)


def _metric_tables(text: str) -> list[list[tuple[str, list[str]]]]:
    """The markdown tables whose header starts with "| Metric |": per row its label and its cells (the header,
    where a run may be marked unproven, is not compared)."""
    tables, current = [], None
    for line in text.splitlines():
        if line.startswith("| Metric |"):
            current = []
            tables.append(current)
        elif current is not None and line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not set("".join(cells)) <= set("-: "):  # not the |---|---:| line
                current.append((cells[0], cells[1:]))
        else:
            current = None
    return tables


# ---------------------------------------------------------------- pair geometry
@dataclass
class _Geometry:
    """Both service orders of pairs with ``x`` picked up first and ``y`` joining: the vehicle turns towards
    o_y at node h after x rode ``delta`` metres, ``pre`` metres before h (POOL of docs/algorithms.md §1.1, written
    again here from the distance table)::

        FOFO (x dropped first): L = δ + l(h, o_y) + l(o_y, d_x) + l(d_x, d_y)
        FOLO (x dropped last):  L = δ + l(h, o_y) + l_y + l(d_y, d_x)
    """

    head: np.ndarray  # δ + l(h, o_y)
    pk: np.ndarray  # pre + l(h, o_y): y's pick-up distance
    l_oy_dx: np.ndarray
    l_dx_dy: np.ndarray
    fofo_len: np.ndarray
    folo_len: np.ndarray
    fofo_ok: np.ndarray  # both detours <= D̄
    folo_ok: np.ndarray
    l_x: np.ndarray
    l_y: np.ndarray

    @classmethod
    def of(cls, f: _Folder, x, y, h, delta, pre, max_detour_m: float) -> _Geometry:
        dist, o, d, solo = f.distances.dist, f.col("origin"), f.col("destination"), f.solo
        p = dist[h, o[y]]
        l_oy_dx, l_dx_dy, l_dy_dx = dist[o[y], d[x]], dist[d[x], d[y]], dist[d[y], d[x]]
        head = delta + p
        fofo_len = head + l_oy_dx + l_dx_dy
        folo_len = head + solo[y] + l_dy_dx
        lim = max_detour_m + DETOUR_TOL_M
        return cls(
            head=head,
            pk=pre + p,
            l_oy_dx=l_oy_dx,
            l_dx_dy=l_dx_dy,
            fofo_len=fofo_len,
            folo_len=folo_len,
            fofo_ok=(head + l_oy_dx - solo[x] <= lim) & (l_oy_dx + l_dx_dy - solo[y] <= lim),
            folo_ok=folo_len - solo[x] <= lim,
            l_x=solo[x],
            l_y=solo[y],
        )

    def rule_order(self, rule: str) -> np.ndarray:
        """FOFO? as the order rule picks: the feasible order with the smaller L (tie: FOFO), or the smaller L."""
        if rule == "min_then_check":
            return self.fofo_len <= self.folo_len
        return self.fofo_ok & (~self.folo_ok | (self.fofo_len <= self.folo_len))

    def served(self, fofo: np.ndarray) -> dict[str, np.ndarray]:
        """Lengths, rides, detours, shared distance and saving in the service order ``fofo``."""
        length = np.where(fofo, self.fofo_len, self.folo_len)
        ride_x = np.where(fofo, self.head + self.l_oy_dx, length)
        ride_y = np.where(fofo, self.l_oy_dx + self.l_dx_dy, self.l_y)
        return {
            "ok": np.where(fofo, self.fofo_ok, self.folo_ok),
            "length": length,
            "detour_x": ride_x - self.l_x,
            "detour_y": ride_y - self.l_y,
            "shared": np.where(fofo, self.l_oy_dx, self.l_y),
            "pk": self.pk,
            "saving": self.l_x + self.l_y - length,
        }


def _paths(f: _Folder, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shortest path of each order ``x`` (as the simulator drives it), flattened: ``(offsets, nodes,
    cum)`` with ``cum`` the distance from the order's origin to each node."""
    o, d = f.col("origin"), f.col("destination")
    unique, inverse = np.unique(x, return_inverse=True)
    if not len(unique):
        return np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0)
    off_u, nodes_u = f.distances.paths_batch(o[unique], d[unique])
    lengths = np.diff(off_u)[inverse]
    offsets = np.r_[0, np.cumsum(lengths)].astype(np.int64)
    within = np.arange(offsets[-1]) - np.repeat(offsets[:-1], lengths)
    nodes = nodes_u[np.repeat(off_u[:-1][inverse], lengths) + within].astype(np.int64)
    cum = f.distances.dist[np.repeat(o[x], lengths), nodes]
    return offsets, nodes, cum


def _first_true(mask: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Flat index of the first True of each segment ``[offsets[i], offsets[i+1])``; -1 where there is none."""
    hits = np.flatnonzero(mask)
    pos = np.searchsorted(hits, offsets[:-1])
    cand = hits[np.minimum(pos, len(hits) - 1)] if len(hits) else np.zeros(len(offsets) - 1, np.int64)
    return np.where((pos < len(hits)) & (cand < offsets[1:]), cand, -1)


def _bound_geometry(f: _Folder, params: Params, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, _Geometry]:
    """docs/bound.md's orientation "x first, y joins": (allowed, geometry with the vehicle at h*).

    Allowed: ``t_y - t_x`` in ``[-K_y, K_x + (R̄ + l_x)/v]``, and h*, the first node of x's shortest path
    within R̄ of o_y, exists with its predecessor within ``v (t_y + K_y - t_x)`` of o_x.
    """
    t, k = f.col("request_s"), f.col("patience_s")
    v, r_max = params.speed_mps, params.max_pickup_m
    gap = t[y] - t[x]
    allowed = (-k[y] - TOL_S <= gap) & (gap <= k[x] + (r_max + TOL_M + f.solo[x]) / v + TOL_S)
    h = f.col("origin")[x].astype(np.int64)
    delta = np.zeros(len(x))
    for block in np.array_split(np.flatnonzero(allowed), max(1, int(allowed.sum()) // 20000)):
        if not len(block):
            continue
        off, nodes, cum = _paths(f, x[block])
        lengths = np.diff(off)
        near = f.distances.dist[nodes, np.repeat(f.col("origin")[y[block]], lengths)] <= r_max + TOL_M
        first = _first_true(near, off)
        reach = v * (t[y[block]] + k[y[block]] - t[x[block]]) + TOL_M
        turned_late = (first > off[:-1]) & (cum[np.maximum(first - 1, 0)] > reach)
        found = (first >= 0) & ~turned_late
        allowed[block[~found]] = False
        h[block[found]] = nodes[first[found]]
        delta[block[found]] = cum[first[found]]
    return allowed, _Geometry.of(f, x, y, h, delta, np.zeros(len(x)), params.max_detour_m)


def _orientation_weight(f: _Folder, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per pair, the saving with x first and y joining under the bound's rule (the feasible service order
    with the smaller route), or -inf where that orientation is not allowed."""
    allowed, g = _bound_geometry(f, f.params, x, y)
    r = g.served(g.rule_order("min_feasible"))
    return np.where(allowed & r["ok"], r["saving"], -np.inf)


def _weights(f: _Folder, a: np.ndarray, b: np.ndarray, a_first_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(weight, edge) of pairs (a, b) in the upper bound's graph: the largest saving over the allowed
    orientations (only "a first": ``a_first_only``); ``edge`` is False (weight -inf) when none is allowed."""
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    weight = _orientation_weight(f, a, b)
    if not a_first_only:
        weight = np.fmax(weight, _orientation_weight(f, b, a))
    return weight, np.isfinite(weight)


def bound_weights(
    distances,
    orders: pd.DataFrame,
    solo: np.ndarray,
    params: Params,
    a: np.ndarray,
    b: np.ndarray,
    a_first_only: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """(weight, edge) of pairs (a, b) in the upper bound's graph (docs/bound.md), computed here, apart from
    the enumeration of rpbench.oracle.pairs.  ``distances`` is the network's DistanceOracle; ``orders``
    holds request_s, patience_s, origin and destination."""
    f = _Folder(
        Path("."),
        {},
        params,
        orders,
        pd.DataFrame(),
        distances.network,
        distances,
        np.asarray(solo, dtype=np.float64),
        pd.DataFrame(),
    )
    return _weights(f, a, b, a_first_only)


# ------------------------------------------------------------ bound certificate
def _check_certificate(rc: RunCheck, tab: pd.DataFrame, f: _Folder, saving_km: float, bound_km: float | None) -> None:
    """Every pair of the run is a bound edge whose weight covers its realised saving; saving <= bound."""
    partner, ok = tab["partner"].to_numpy(), tab["ok"].to_numpy()
    t_pick = tab["pickup_s"].to_numpy()
    both = (partner >= 0) & ok & ok[np.maximum(partner, 0)]
    me = np.flatnonzero(both)
    first_me = (t_pick[me] < t_pick[partner[me]]) | ((t_pick[me] == t_pick[partner[me]]) & (me < partner[me]))
    a = me[first_me]  # picked up first
    b = partner[a]
    odo_pick, odo_drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    occupied = np.maximum(odo_drop[a], odo_drop[b]) - odo_pick[a]
    realised = f.solo[a] + f.solo[b] - occupied
    own = _orientation_weight(f, a, b)  # the run's pick-up order, computed once
    weight = np.fmax(own, _orientation_weight(f, b, a))
    edge, own_edge = np.isfinite(weight), np.isfinite(own)
    for k in np.flatnonzero(~own_edge)[:5]:
        rc.fail(
            "bound-certificate",
            f"pair ({a[k]}, {b[k]}) is not an edge of the upper bound's graph with "
            f"order {a[k]} first (time window or detours at its origin)",
        )
    over = edge & (realised > weight + CERT_TOL_M)
    for k in np.flatnonzero(over)[:5]:
        rc.fail(
            "bound-certificate",
            f"pair ({a[k]}, {b[k]}): realised saving {realised[k]:.3f} m exceeds the "
            f"bound's edge weight {weight[k]:.3f} m",
        )
    rc.checked["certified_pairs"] = int((own_edge & ~over).sum())
    if bound_km is None:
        return
    if not np.isfinite(bound_km):
        rc.fail("bound-certificate", "the folder's upper bound is not finite (its solver proved no bound)")
    elif saving_km > bound_km + CERT_TOL_M / 1000.0 * max(1, len(a)):
        rc.fail("bound-certificate", f"saving {saving_km:.3f} km exceeds the upper bound {bound_km:.3f} km")


# ------------------------------------------------------------------- oracles
def _check_oracle(f: _Folder, name: str, run_dir: Path) -> tuple[RunCheck, pd.DataFrame | None]:
    """An offline run: a matching of feasible pairs (§4.2, or the bound's) whose stored figures and KPIs
    are recomputed here."""
    rc = RunCheck(name)
    rec = f.meta["runs"][name]
    rules = _oracle_rules(rc, rec["rules"], f.params)
    pairs = _read_table(run_dir / "pairs.csv.gz", PAIR_COLUMNS)
    rows = _pair_rows(rc, pairs, f)
    if rows is None:
        rc.skip("kpi", "the pairs name unknown orders (see [oracle-pairs])")
        return rc, None
    a, b = rows
    request = f.col("request_s")
    for col, which in (("first_request_s", a), ("second_request_s", b)):
        bad = np.flatnonzero(~(np.abs(pairs[col].to_numpy() - request[which]) <= TOL_S))  # NaN is wrong too
        if len(bad):
            rc.fail("oracle-pairs", f"{len(bad)} pairs' stored {col} differ from orders.csv.gz's request times")
    fofo = pairs["service_order"].to_numpy() == "FOFO"
    strange = ~np.isin(pairs["service_order"].to_numpy(), ("FOFO", "FOLO"))
    if strange.any():
        rc.fail("oracle-pairs", f"{int(strange.sum())} pairs have a service order other than FOFO/FOLO")
    if rules["window"] == "bound":
        route = _check_bound_pairs(rc, pairs, a, b, fofo, f)
    else:
        route = _check_paper_pairs(rc, rules, pairs, a, b, fofo, f)
    _check_stored_route(rc, pairs, route)
    over = np.flatnonzero(np.maximum(route["detour_x"], route["detour_y"]) > f.params.max_detour_m + TOL_M)
    if len(over):
        rc.fail(
            "max-detour",
            f"{len(over)} pairs detour a passenger by more than D̄ = {f.params.max_detour_m:g} m, "
            f"e.g. pair ({pairs['first_id'].iloc[over[0]]}, {pairs['second_id'].iloc[over[0]]})",
        )
    recomputed, claims = _oracle_kpis(rec, rules, pairs, route, f, f.reported(name))
    _compare_kpis(rc, "oracle", recomputed, f.reported(name), claims)
    rc.checked.update({"pairs": len(pairs), "orders": f.n})
    if rules["window"] != "bound":
        return rc, None
    hour = np.floor(np.minimum(request[a], request[b]) / 3600.0).astype(np.int64)
    by_hour = pd.Series(pairs["saving_m"].to_numpy() / 1000.0).groupby(hour).sum()
    table = pd.DataFrame({column: np.nan for column in HOURLY_COLUMNS}, index=by_hour.index)
    table["total_saving_km"] = by_hour  # the bound's rows of hourly.csv: only its matching's saving
    return rc, table


def _oracle_rules(rc: RunCheck, recorded: dict, params: Params) -> dict:
    """The rules the pairs are checked by: K̄, D̄, R̄ and v are the folder's parameters (a rule recorded
    otherwise fails ``oracle-rules`` and is not used); the flags are the run's."""
    for key in RULE_NUMBERS:
        if not _same(float(recorded[key]), float(getattr(params, key)), rtol=1e-12, atol=1e-9):
            rc.fail(
                "oracle-rules", f"rule {key} = {recorded[key]!r} is not the folder's parameter {getattr(params, key)!r}"
            )
    rules = {key: float(getattr(params, key)) for key in RULE_NUMBERS}
    rules.update({key: bool(recorded[key]) for key in RULE_FLAGS})
    rules["order_rule"] = recorded.get("order_rule", "min_feasible")
    rules["window"] = recorded.get("window", "patience")
    if rules["order_rule"] not in ("min_feasible", "min_then_check"):
        rc.fail("oracle-rules", f"unknown order rule {rules['order_rule']!r}")
        rules["order_rule"] = "min_feasible"
    if rules["window"] not in ("patience", "bound"):
        rc.fail("oracle-rules", f"unknown pair window {rules['window']!r}")
        rules["window"] = "patience"
    if rules["window"] == "bound" and (
        rules["pickup_check"]
        or rules["allow_enroute"]
        or not rules["both_pickup_orders"]
        or rules["order_rule"] != "min_feasible"
    ):
        rc.fail(
            "oracle-rules",
            "the upper bound's rules are fixed (both pick-up orders, no pick-up test, no "
            "en-route geometry, the best feasible service order); meta.json records others",
        )
    return rules


def _pair_rows(rc: RunCheck, pairs: pd.DataFrame, f: _Folder):
    """(a, b): the row positions of each pair's first and second order, or None when they name unknown ids."""
    index = pd.Series(np.arange(f.n), index=f.col("order_id"))
    unknown = ~pairs["first_id"].isin(index.index) | ~pairs["second_id"].isin(index.index)
    if unknown.any():
        k = int(np.flatnonzero(unknown.to_numpy())[0])
        rc.fail(
            "oracle-pairs",
            f"{int(unknown.sum())} pairs name order ids that are not in orders.csv.gz, e.g. "
            f"({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]})",
        )
        return None
    a = index[pairs["first_id"]].to_numpy()
    b = index[pairs["second_id"]].to_numpy()
    if (a == b).any():
        rc.fail("oracle-pairs", f"{int((a == b).sum())} pairs pair an order with itself")
    counts = np.bincount(np.concatenate([a, b]), minlength=f.n)
    if (counts > 1).any():
        rc.fail("oracle-pairs", f"order {int(np.argmax(counts))} appears in {int(counts.max())} pairs")
    return a, b


def _check_paper_pairs(rc: RunCheck, rules: dict, pairs: pd.DataFrame, a, b, fofo, f: _Folder) -> dict:
    """The paper's oracles (§4.2): waiting pairs request within K̄ of each other, the vehicle at the first
    order's origin; en-route pairs (allow_enroute) join the first order's ride at the next node of its path
    after ``s = v (t_b - t_a - K̄)``, ``0 < s < l_a``.  Returns the pairs recomputed in the stored order."""
    t, k_bar, v = f.col("request_s"), rules["planner_patience_s"], rules["speed_mps"]
    enroute = pairs["enroute"].to_numpy()
    gap = t[b] - t[a]
    s = v * (gap - k_bar)
    waiting = ~enroute
    ids = (pairs["first_id"].to_numpy(), pairs["second_id"].to_numpy())

    def fail(mask: np.ndarray, what: str) -> None:
        if mask.any():
            k = int(np.flatnonzero(mask)[0])
            rc.fail(
                "oracle-pairs",
                f"{int(mask.sum())} pairs {what}, e.g. ({ids[0][k]}, {ids[1][k]}) requested {gap[k]:.0f} s apart",
            )

    fail(waiting & (np.abs(gap) > k_bar + TOL_S), f"of waiting orders request more than K̄ = {k_bar:g} s apart")
    in_window = (gap > k_bar) & (s > 0) & (s < f.solo[a])
    fail(
        enroute & ~in_window,
        "are en-route pairs outside the en-route window (the second order requests after K̄, while the first one rides)",
    )
    if not rules["allow_enroute"]:
        fail(enroute, "are en-route pairs in an oracle whose rules do not allow them")
    if not rules["both_pickup_orders"]:
        later_first = (gap < 0) | ((gap == 0) & (ids[0] > ids[1]))
        fail(waiting & later_first, "pick the later order up first, which the rules do not allow")
    h, delta, pre = f.col("origin")[a].astype(np.int64), np.zeros(len(a)), np.zeros(len(a))
    en = np.flatnonzero(enroute & in_window)
    if len(en):
        off, nodes, cum = _paths(f, a[en])
        first = _first_true(cum >= np.repeat(s[en], np.diff(off)), off)  # the next node at or after s
        first = np.where(first < 0, off[1:] - 1, first)  # s < l_a: never, but no crash
        h[en], delta[en] = nodes[first], cum[first]
        pre[en] = delta[en] - s[en]
    g = _Geometry.of(f, a, b, h, delta, pre, rules["max_detour_m"])
    route = g.served(fofo)
    feasible = route["ok"] & ((route["pk"] <= rules["max_pickup_m"] + DETOUR_TOL_M) | (not rules["pickup_check"]))
    fail(~feasible, "are not feasible under the rules (a detour > D̄, or a pick-up > R̄ with pickup_check)")
    chosen = g.rule_order(rules["order_rule"])
    fail(
        (chosen != fofo) & (np.abs(g.fofo_len - g.folo_len) > TOL_M),
        f"are not served in the order the rule {rules['order_rule']} picks",
    )
    if rules["both_pickup_orders"] and waiting.any():
        o_b = f.col("origin")[b].astype(np.int64)
        rev = _Geometry.of(f, b, a, o_b, np.zeros(len(a)), np.zeros(len(a)), rules["max_detour_m"])
        other = rev.served(rev.rule_order(rules["order_rule"]))
        other_ok = other["ok"] & ((other["pk"] <= rules["max_pickup_m"] + DETOUR_TOL_M) | (not rules["pickup_check"]))
        fail(
            waiting & other_ok & (other["saving"] > route["saving"] + TOL_M),
            "are not in the pick-up order of the larger saving (§4.2: both orders tried, the larger wins)",
        )
    return route


def _check_bound_pairs(rc: RunCheck, pairs: pd.DataFrame, a, b, fofo, f: _Folder) -> dict:
    """The upper bound's pairs: edges of its graph in the stored orientation, of the largest weight."""
    allowed, g = _bound_geometry(f, f.params, a, b)
    route = g.served(fofo)
    not_edge = ~(allowed & route["ok"])
    if not_edge.any():
        k = int(np.flatnonzero(not_edge)[0])
        rc.fail(
            "oracle-pairs",
            f"{int(not_edge.sum())} pairs are not edges of the upper bound's graph with the "
            f"stored first order, e.g. ({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]})",
        )
    weight, _ = _weights(f, a, b)
    stored = pairs["saving_m"].to_numpy()
    if not np.allclose(weight[~not_edge], stored[~not_edge], rtol=0, atol=TOL_M):
        rc.fail("oracle-pairs", "stored weights differ from the largest realisable savings recomputed here")
    off = ~not_edge & (
        (g.rule_order("min_feasible") != fofo) & (np.abs(g.fofo_len - g.folo_len) > TOL_M)
        | (route["saving"] < weight - TOL_M)
    )
    if off.any():
        rc.fail(
            "oracle-pairs", f"{int(off.sum())} pairs are not in the orientation and service order of the largest weight"
        )
    return route


STORED_ROUTE = (
    ("saving_m", "saving"),
    ("length_m", "length"),
    ("detour_first_m", "detour_x"),
    ("detour_second_m", "detour_y"),
    ("shared_m", "shared"),
    ("pickup_m", "pk"),
)


def _check_stored_route(rc: RunCheck, pairs: pd.DataFrame, route: dict) -> None:
    """The figures pairs.csv.gz stores are the recomputed ones."""
    for column, key in STORED_ROUTE:
        stored = pairs[column].to_numpy()
        bad = ~np.isclose(stored, route[key], rtol=0, atol=TOL_M)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            rc.fail(
                "oracle-pairs",
                f"{int(bad.sum())} pairs' stored {column} differ from the recomputed ones, e.g. "
                f"({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]}): stored "
                f"{stored[k]:.3f} m, recomputed {route[key][k]:.3f} m",
            )


def _oracle_kpis(
    rec: dict, rules: dict, pairs: pd.DataFrame, route: dict, f: _Folder, reported: pd.DataFrame
) -> tuple[dict, dict]:
    """(recomputed KPIs, solver claims -> failure message or None).  The objective is the matching's value
    in model units (savings rounded to ``unit_m``; the bound's rounded up, docs/bound.md)."""
    n, count = f.n, len(pairs)
    unit = float(rec.get("unit_m", 0.01))
    stored = pairs["saving_m"].to_numpy()
    bound = rules["window"] == "bound"
    objective = float((np.ceil(stored / unit) if bound else np.round(stored / unit)).sum() * unit)
    detours = np.concatenate([route["detour_x"], route["detour_y"]])
    out = {
        "orders": n,
        "pairs": count,
        "pooled_passengers": 2 * count,
        "pairing_ratio": 2 * count / n if n else float("nan"),
        "avg_detour_m": float(detours.mean()) if count else float("nan"),
        "avg_shared_m": float(route["shared"].mean()) if count else float("nan"),
        "objective_m": objective,
    }
    have = {k: _as_number(v) for k, v in zip(reported["kpi"], reported["value"], strict=True)}
    optimal = rec.get("status", "optimal") == "optimal"
    claims = {}
    if not bound:
        out["total_saving_km"] = float(route["saving"].sum()) / 1000.0
    elif optimal:
        out["total_saving_km"] = objective / 1000.0  # the rounded-up optimum is the bound
    else:
        rep = have.get("total_saving_km")
        claims["total_saving_km"] = (
            None
            if rep is None or rep >= objective / 1000.0 - 1e-6
            else (
                f"KPI total_saving_km: the reported bound {rep!r} km lies below its own matching's "
                f"{objective / 1000.0!r} km"
            )
        )
    bound_m, gap = have.get("bound_m"), have.get("gap")
    claims["bound_m"] = None
    if bound_m is not None and not np.isnan(bound_m):
        if bound_m < objective - max(unit, 1e-9 * abs(objective)):
            claims["bound_m"] = f"KPI bound_m: the solver's bound {bound_m!r} lies below its solution's {objective!r}"
        elif gap == 0 and not _same(bound_m, objective):
            claims["bound_m"] = f"KPI bound_m: reported {bound_m!r} with a gap of 0, recomputed objective {objective!r}"
    pairs_bound = have.get("pairs_bound")
    claims["pairs_bound"] = None
    if rec.get("variant", 1) == 2 and pairs_bound is not None:
        if not pairs_bound >= count or (optimal and pairs_bound != count):
            claims["pairs_bound"] = (
                f"KPI pairs_bound: the proven maximum number of pairs {pairs_bound!r} does not "
                f"{'equal' if optimal else 'cover'} the {count} pairs of the "
                f"{'optimal ' if optimal else ''}matching"
            )
    elif pairs_bound is not None and not np.isnan(pairs_bound):
        claims["pairs_bound"] = f"KPI pairs_bound: reported {pairs_bound!r} for an oracle that proves none"
    return out, claims


# ------------------------------------------------------ multi-day / sweep parents
def _listed_children(meta: dict) -> list[str] | None:
    """The child folders a parent's meta.json lists: ``children`` (recorded since rpbench writes it), else the
    multi-day ``dates`` or the sweep points' labels (the folders are named after them); None: no list."""
    for listed in (
        meta.get("children"),
        meta.get("dates") if meta.get("kind") == "multi-day" else None,
        [p.get("label") for p in meta.get("points", []) if isinstance(p, dict)]
        if meta.get("kind") == "sweep" and isinstance(meta.get("points"), list)
        else None,
    ):
        if isinstance(listed, list) and listed and all(isinstance(x, str) for x in listed):
            return listed
    return None


def _check_parent(parent: Path, meta: dict) -> tuple[FolderResult, list[Path]]:
    """A multi-day or sweep parent: every listed child folder is there (a deleted day or point fails
    ``manifest``), and its summary tables are its children's KPIs.  Returns the children to check."""
    fc = RunCheck(FOLDER)
    what = "day" if meta["kind"] == "multi-day" else "sweep point"
    found = {p.relative_to(parent).as_posix(): p for p in results.run_folders(parent) if p != parent}
    listed = _listed_children(meta)
    if listed is None:
        fc.skip("manifest", f"meta.json lists no {what} folders")
        listed = []
    for name in listed:
        if not (parent / name).is_dir():
            fc.fail("manifest", f"{what} folder {name}/ listed in meta.json is missing (deleted?)")
    for name in sorted(set(found) - set(listed)):
        if listed:
            fc.fail("manifest", f"{name}/ is not a {what} folder meta.json lists")
    fc.checked["children"] = len(listed)
    _check_parent_tables(fc, parent, meta)
    children = sorted(set(found.values()) | {parent / name for name in listed if (parent / name).is_dir()})
    return FolderResult(str(parent), folder_check=fc), children


def _check_parent_tables(fc: RunCheck, parent: Path, meta: dict) -> None:
    """by_day.csv and summary.csv (multi-day) or sweep.csv are the children's kpis.csv, reshaped and averaged;
    the children's own checks verify those."""
    try:
        if meta["kind"] == "multi-day":
            table = by_day_table(parent)
            _compare_table(fc, parent / "by_day.csv", table, ["date", "run", "kpi"], ["value"])
            stats = table.groupby(["run", "kpi"], sort=False)["value"].agg(["mean", "std", "min", "max", "count"])
            _compare_table(
                fc, parent / "summary.csv", stats.reset_index(), ["run", "kpi"], ["mean", "std", "min", "max", "count"]
            )
        else:
            _compare_table(fc, parent / "sweep.csv", sweep_table(parent), ["label", "run", "kpi"], ["point", "value"])
    except (RpbenchError, KeyError, ValueError, TypeError) as exc:
        fc.skip(
            "parent-tables",
            f"the children's KPI tables cannot be gathered ({type(exc).__name__}: "
            f"{one_line(exc)}); their own checks say why",
        )


def _compare_table(fc: RunCheck, path: Path, expected: pd.DataFrame, keys: list[str], values: list[str]) -> None:
    if not path.is_file():
        fc.skip("parent-tables", f"the folder has no {path.name}")
        return
    try:
        found = results.read_csv(path)
    except ResultsError as exc:
        fc.fail("parent-tables", one_line(exc))
        return
    if not set(keys + values) <= set(found.columns):
        fc.fail("parent-tables", f"{path.name} lacks column(s) of {', '.join(keys + values)}")
        return

    def keyed(table: pd.DataFrame) -> pd.DataFrame:
        return table.assign(**{k: table[k].astype(str) for k in keys}).set_index(keys)[values]

    have, want = keyed(found), keyed(expected)
    if have.index.has_duplicates:
        fc.fail("parent-tables", f"{path.name}: a row repeats")
        return
    extra, lost = set(have.index) - set(want.index), set(want.index) - set(have.index)
    # Rows of KPIs this rpbench does not know (an older version's ratio rows), or ratio rows it renders and an
    # older version did not: not compared, and said so.
    other = {k for k in extra if k[-1] not in KNOWN_KPIS} | {k for k in lost if k[-1] in RATIO_KPIS}
    if other:
        fc.skip(
            "parent-tables",
            f"{path.name}: rows of {', '.join(sorted({k[-1] for k in other}))} not compared "
            "(rendered by another rpbench version)",
        )
    extra, lost = sorted(extra - other), sorted(lost - other)
    if extra or lost:
        fc.fail(
            "parent-tables",
            f"{path.name}: rows {extra[:3]} are not in the children's kpis.csv, rows {lost[:3]} are missing",
        )
        return
    for column in values:
        for key, value in want[column].items():
            rep = _as_number(have.loc[key, column])
            if rep is None or not _same(rep, float(value)):
                fc.fail(
                    "parent-tables",
                    f"{path.name}: {column} of {key} is {_show(have.loc[key, column])}, the "
                    f"children's kpis.csv give {float(value)!r}",
                )
    fc.checked[path.stem] = len(want)


# ---------------------------------------------------------------------- output
def format_report(checks: list[RunCheck]) -> str:
    lines = []
    for rc in checks:
        if rc.ok:
            facts = ", ".join(f"{k} {v}" for k, v in rc.checked.items())
            lines.append(f"{rc.run}: OK ({facts})")
        else:
            lines.append(f"{rc.run}: FAILED")
            for check, messages in rc.violations.items():
                lines.append(f"  [{check}] {len(messages)} violation(s): {messages[0]}")
                for m in messages[1:3]:
                    lines.append(f"  [{check}]   {m}")
        for check, reason in rc.skipped.items():
            lines.append(f"  [{check}] skipped: {reason}")
    return "\n".join(lines)
