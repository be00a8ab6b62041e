"""A comparison folder's inputs, read and validated once (:class:`Folder`), and the folder's own checks
``manifest``, ``inputs-digest`` and ``orders``.

An input that does not parse — a file missing or truncated, a column missing or not of its kind, a node
outside the network, meta.json without its parameters — is one :class:`ResultsError` line: the folder is
unreadable.  The digest meta.json records at run time is :func:`rpbench.results.digest.inputs_digest`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.check.core import (
    FLEET_COLUMNS,
    KPI_COLUMNS,
    ORDER_COLUMNS,
    RULE_FLAGS,
    RULE_NUMBERS,
    TOL_M,
    RunCheck,
    as_number,
)
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.network import Distances, RoadNetwork
from rpbench.results.digest import inputs_digest
from rpbench.results.layout import CHECK, FLEET, KPIS, META, NETWORK, ORDERS, RUNS
from rpbench.results.legacy import current_names
from rpbench.scenarios.base import Params


# ---------------------------------------------------------------------- reading
@dataclass
class Folder:
    """A comparison folder's inputs, read and validated once."""

    path: Path
    meta: dict
    params: Params
    orders: pd.DataFrame
    fleet: pd.DataFrame
    network: RoadNetwork
    distances: Distances
    solo: np.ndarray
    kpis: pd.DataFrame

    @property
    def n(self) -> int:
        return len(self.orders)

    def col(self, name: str) -> np.ndarray:
        return self.orders[name].to_numpy()

    def reported(self, run: str) -> pd.DataFrame:
        return self.kpis[self.kpis["run"] == run]


def read_folder(folder: Path) -> Folder:
    """Read a comparison folder's inputs; a published light copy, or an input that does not parse, is one
    :class:`ResultsError` line."""
    meta = results.read_meta(folder)
    if not (folder / RUNS).is_dir() and (folder / CHECK).is_file():
        raise ResultsError(
            f"{str(folder)!r} is a published light copy without event logs or inputs: {CHECK} holds "
            f"the verdict on the full folder; rerun the command in its {META} to check it again"
        )
    params = _read_params(folder, meta)
    _read_run_records(folder, meta)
    network = results.load_network(folder / NETWORK)
    orders = read_results_table(folder / ORDERS, ORDER_COLUMNS)
    _require(
        folder / ORDERS,
        orders,
        network.n_nodes,
        nodes=("origin", "destination"),
        finite=("request_s", "patience_s", "solo_m"),
    )
    if orders["order_id"].duplicated().any():
        raise ResultsError(
            f"results file {str(folder / ORDERS)!r}: order ids repeat "
            f"(e.g. {int(orders['order_id'][orders['order_id'].duplicated()].iloc[0])})"
        )
    fleet = read_results_table(folder / FLEET, FLEET_COLUMNS)
    _require(folder / FLEET, fleet, network.n_nodes, nodes=("initial_node",), finite=())
    if not np.array_equal(fleet["vehicle"].to_numpy(), np.arange(len(fleet))):
        raise ResultsError(f"results file {str(folder / FLEET)!r}: vehicles are not numbered 0..{len(fleet) - 1}")
    kpis = current_names(read_results_table(folder / KPIS, KPI_COLUMNS))  # an older rpbench's names read as today's
    distances = network.distances()
    solo = distances.dist[orders["origin"].to_numpy(), orders["destination"].to_numpy()]
    return Folder(folder, meta, params, orders, fleet, network, distances, solo, kpis)


def _read_params(folder: Path, meta: dict) -> Params:
    """The run's parameters, all of them: a missing one is not replaced by its default (it may be the
    threshold a violation hides behind), an unknown one is not ignored."""
    where = str(folder / META)
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
    where = str(folder / META)
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


def read_results_table(path: Path, columns: dict[str, str]) -> pd.DataFrame:
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
    """One column as its kind (see :func:`read_results_table`)."""
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


def _require(path: Path, table: pd.DataFrame, n_nodes: int, *, nodes: tuple[str, ...], finite: tuple[str, ...]) -> None:
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


def check_manifest(fc: RunCheck, f: Folder) -> list[str]:
    """A deleted or added run folder fails here; returns the runs to check (listed, present, recorded)."""
    listed = _listed_runs(f.meta)
    present = results.run_names(f.path)
    if listed is None:
        fc.fail("manifest", f'{META}\'s manifest is malformed (expected {{"runs": [run names]}})')
        listed = list(f.meta["runs"])
    if not listed and not present:
        raise ResultsError(f"results folder {str(f.path)!r} holds no runs (no {RUNS}/<name>/ folders)")
    for name in listed:
        if name not in present:
            fc.fail("manifest", f"run {name!r} listed in {META} has no folder {RUNS}/{name}/ (deleted?)")
        if name not in f.meta["runs"]:
            fc.fail("manifest", f"run {name!r} is listed in the manifest but has no record in {META}'s runs")
    for name in present:
        if name not in listed:
            fc.fail("manifest", f"{RUNS}/{name}/ is not a run {META} lists")
    strategies = f.meta.get("strategies")
    if isinstance(strategies, list) and sorted(map(str, strategies)) != sorted(listed):
        fc.fail(
            "manifest",
            f"{META}'s strategies ({', '.join(map(str, strategies))}) are not its runs ({', '.join(listed)})",
        )
    stray = sorted(set(f.kpis["run"]) - set(listed))
    if stray:
        fc.fail("manifest", f"{KPIS} reports run(s) {', '.join(map(repr, stray))} that {META} does not list")
    fc.checked["runs"] = len(listed)
    return [name for name in listed if name in present and name in f.meta["runs"]]


def check_digest(fc: RunCheck, f: Folder) -> None:
    """The inputs, parameters and run options are those of the run: an edited file or a relaxed parameter
    (say max_detour_m raised to hide a violation) changes its SHA-256."""
    recorded = f.meta.get("inputs_digest")
    if recorded is None and "manifest" in f.meta:
        fc.fail(
            "inputs-digest",
            f"{META} has a manifest but no inputs_digest: rpbench writes both, so the digest was removed",
        )
        return
    if recorded is None:
        fc.skip(
            "inputs-digest",
            f"{META} records no inputs digest (a folder written before rpbench recorded "
            "one): edited inputs or parameters are caught only where another check breaks",
        )
        return
    if not (
        isinstance(recorded, dict)
        and isinstance(recorded.get("files"), dict)
        and isinstance(recorded.get("runs"), dict)
        and recorded.get("algorithm") == "sha256"
    ):
        fc.fail("inputs-digest", f"{META}'s inputs_digest is malformed (files, params, runs of sha256 digests)")
        return
    actual = inputs_digest(f.path, f.meta["params"], f.meta["runs"])
    for name, digest in actual["files"].items():
        if recorded["files"].get(name) != digest:
            fc.fail("inputs-digest", f"{name} is not the file the run wrote (its SHA-256 differs from {META}'s)")
    if recorded.get("params") != actual["params"]:
        fc.fail("inputs-digest", f"{META}'s params are not those of the run (their SHA-256 differs)")
    for name in sorted(set(actual["runs"]) | set(recorded["runs"])):
        if recorded["runs"].get(name) != actual["runs"].get(name):
            fc.fail(
                "inputs-digest",
                f"run {name!r}: its options/rules in {META} are not those of the run "
                "(SHA-256 differs, or the run is not in the digest)",
            )
    fc.checked["digests"] = len(actual["files"]) + 1 + len(actual["runs"])


def check_orders(fc: RunCheck, f: Folder) -> None:
    """Orders in request order, solo distances = the folder network's shortest paths, patience > 0."""
    request = f.col("request_s")
    if (np.diff(request) < 0).any():
        fc.fail("orders", f"{ORDERS} is not in request-time order")
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


def bound_km(f: Folder) -> float | None:
    """The reported upper bound (km) when the folder has a bound run (its own check verifies it)."""
    for name, run in f.meta["runs"].items():
        if run.get("kind") == "oracle" and run.get("rules", {}).get("window") == "bound":
            value = f.reported(name)
            value = value[value["kpi"] == "total_saving_km"]["value"]
            number = as_number(value.iloc[0]) if len(value) else None
            return float("nan") if number is None else number
    return None
