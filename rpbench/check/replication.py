"""``rpbench check`` for a replication folder: its files, its report, and the checks that still apply to the
authors' engine.

Folder checks (the run ``(folder)``): ``manifest`` — every file meta.json lists is there with its SHA-256,
and no file was added under records/ or engines/; ``paths`` — no name read from the folder (a listed file,
a row's date, strategy or engine) leads outside it (``..``, an absolute path, a symbolic link out);
``report`` — report.md's tables are their rendering from runs.csv.  rpbench's own engine's rows: its run's
results folder (``engines/``) passes the full checker (``engine-folder`` when it cannot be read), and the
row shows that folder's KPIs (``engine-rows``).

The authors' vehicles teleport (they jump to the last node of their route), so
there is no trajectory to hold a run to: every check built on vehicle positions
and odometers is skipped, by name, with that reason.  What still applies is
re-verified from the folder's own files:

* ``assignment``: every served order is served once, never before its request
  nor after its patience ran out (plus one round), a vehicle takes at most one
  passenger per round (or, RTV, one two-request trip of mutual partners), pool
  partners are mutual and share the vehicle;
* ``accounting``: each pair's saving is l_a + l_b - (ride_a + ride_b - shared)
  and its detours ride - l, shared <= both rides; the reported KPIs (served,
  pooled passengers, response rate over the recorded denominator, pairing ratio,
  total saving, mean detour) are recomputed from the records.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.check.core import FOLDER, KPI_COLUMNS, FolderResult, RunCheck, as_number, same
from rpbench.check.folder import read_results_table
from rpbench.check.verify import check_results
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.files.digests import file_sha256
from rpbench.results import store as results
from rpbench.results.layout import ENGINES_DIR, FLEET, KPIS, META, RECORDS_DIR, engine_folder, records_file

#: A date, strategy or engine name as the folder's file names use it: no separator, no ``..``.
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
#: The KPIs of rpbench's own engine that runs.csv shows, read off its results folder's kpis.csv.
ENGINE_KPIS = (
    "orders",
    "served",
    "pooled_passengers",
    "pairing_ratio",
    "total_saving_km",
    "avg_detour_m",
    "avg_shared_m",
    "avg_response_time_s",
    "avg_pickup_time_s",
)
REPLICATION_TOL_M = 1e-3
#: The columns of an authors' run's records that the audit reads.
RECORD_COLUMNS = (
    "order_id", "vehicle", "assign_s", "request_s", "patience_s", "pooled", "partner",
    "detour_m", "shared_m", "ride_m", "solo_m",
)  # fmt: skip
ROUND_S = 10.0

SKIPPED = {
    "movement": "the authors' vehicles jump to the last node of their route (teleport): no trajectory exists",
    "trajectories": "no trajectories are written for the authors' engine (teleporting vehicles)",
    "pickup-places": "pick-ups are not at a position on a driven route (teleport, or measured from the first "
    "passenger's origin)",
    "capacity-in-time": "on-board intervals need trajectories (teleport)",
    "occupied-distance": "the authors' ledger sums pair savings, not driven distance",
    "bound-certificate": "the upper bound (docs/bound.md) assumes rpbench's movement rules",
    "digest": "the engine reads the scenario from the data folder; the input is named in meta.json",
}


def audit_run(records: pd.DataFrame, row: dict) -> tuple[dict[str, list[str]], dict[str, int]]:
    """Violations and counts of checks on one run's passenger records against its reported row."""
    bad: dict[str, list[str]] = {}
    checked = {"assignment": 0, "accounting": 0}

    def fail(check: str, msg: str) -> None:
        bad.setdefault(check, []).append(msg)

    rec = records
    if rec["order_id"].duplicated().any():
        fail("assignment", f"order {int(rec.loc[rec['order_id'].duplicated(), 'order_id'].iloc[0])} served twice")
    early = rec["assign_s"] < rec["request_s"] - 1e-9
    if early.any():
        fail("assignment", f"order {int(rec.loc[early, 'order_id'].iloc[0])} assigned before its request")
    late = rec["assign_s"] - rec["request_s"] > np.maximum(rec["patience_s"], 90.0) + ROUND_S + 1e-9
    if late.any():
        fail("assignment", f"order {int(rec.loc[late, 'order_id'].iloc[0])} assigned after its patience ran out")
    # One passenger per vehicle and round, except RTV's two-request trip: two mutual partners at once.
    for (vehicle, t), group in rec.groupby(["vehicle", "assign_s"]):
        if len(group) == 1:
            continue
        ids, partners = group["order_id"].tolist(), group["partner"].tolist()
        if len(group) > 2 or sorted(ids) != sorted(partners):
            fail(
                "assignment",
                f"vehicle {int(vehicle)} took {len(group)} passengers in the round at {t:g} s that are not one trip",
            )
    checked["assignment"] += 4 * len(rec)
    pooled = rec[rec["pooled"].astype(bool)]
    by_id = rec.drop_duplicates("order_id").set_index("order_id")  # a duplicate is reported above
    for _, r in pooled.iterrows():
        p = int(r["partner"])
        if p not in by_id.index or int(by_id.at[p, "partner"]) != int(r["order_id"]):
            fail("assignment", f"order {int(r['order_id'])}: partner {p} is not mutual")
            continue
        if int(by_id.at[p, "vehicle"]) != int(r["vehicle"]):
            fail("assignment", f"order {int(r['order_id'])} and its partner {p} ride different vehicles")
        if abs(r["detour_m"] - (r["ride_m"] - r["solo_m"])) > REPLICATION_TOL_M:
            fail("accounting", f"order {int(r['order_id'])}: detour {r['detour_m']:.3f} m != ride - solo")
        if r["shared_m"] > min(r["ride_m"], by_id.at[p, "ride_m"]) + REPLICATION_TOL_M:
            fail("accounting", f"order {int(r['order_id'])}: shared distance longer than a ride")
        checked["accounting"] += 3
    lead = pooled[pooled["order_id"] < pooled["partner"]]
    partner = by_id.loc[lead["partner"].astype(np.int64)]
    saving_m = (
        lead["solo_m"].to_numpy()
        + partner["solo_m"].to_numpy()
        - (lead["ride_m"].to_numpy() + partner["ride_m"].to_numpy() - lead["shared_m"].to_numpy())
    )
    served = len(rec)
    recomputed = {
        "served": served,
        "pooled_passengers": len(pooled),
        "response_rate": served / row["response_denominator"] if row.get("response_denominator") else np.nan,
        "pairing_ratio": len(pooled) / served if served else np.nan,
        "total_saving_km": float(saving_m.sum()) / 1000.0,
        "avg_detour_m": float(pooled["detour_m"].mean()) if len(pooled) else np.nan,
    }
    for key, value in recomputed.items():
        reported = np.nan if row.get(key) is None else as_number(row.get(key))
        if reported is None:
            fail("accounting", f"{key}: runs.csv shows the text {row.get(key)!r}, recomputed {value!r}")
            continue
        both_nan = not np.isfinite(value) and not np.isfinite(reported)
        if not both_nan and not np.isclose(value, reported, rtol=1e-9, atol=1e-6):
            fail("accounting", f"{key}: reported {reported!r}, recomputed {value!r}")
        checked["accounting"] += 1
    return bad, checked


def audit_folder(folder: Path) -> tuple[RunCheck, list[RunCheck]]:
    """The folder's own checks (``manifest``, ``paths``, ``report``) and one verdict per row of runs.csv."""
    meta = results.read_meta(folder)
    root = folder.resolve()
    fc = RunCheck(FOLDER)
    manifest = check_replication_manifest(fc, folder, root, meta)
    runs_csv = folder / "runs.csv"
    if not runs_csv.is_file():
        raise ResultsError(f"replication folder {str(folder)!r} has no runs.csv")
    if not inside(root, runs_csv):
        raise ResultsError(f"{str(runs_csv)!r} leads outside the replication folder (a symbolic link)")
    try:
        rows = pd.read_csv(runs_csv)
    except (OSError, ValueError) as exc:
        raise ResultsError(f"cannot read {str(runs_csv)!r}: {exc}") from None
    missing = [c for c in ("date", "strategy", "engine") if c not in rows.columns]
    if missing:
        raise ResultsError(f"{str(runs_csv)!r} lacks the column(s) {', '.join(missing)}")
    check_replication_report(fc, folder, root, rows, meta)
    dates = {str(d) for d in meta.get("dates") or []}
    out = [audit_row(folder, root, row, manifest, dates) for row in rows.to_dict("records")]
    return fc, out


def audit_row(folder: Path, root: Path, row: dict, manifest: dict | None, dates: set[str]) -> RunCheck:
    """One row of runs.csv: its records audited (an authors' run), its results folder checked and compared
    (rpbench's engine), or skipped with the reason (an ablation step)."""
    date, strategy, engine = str(row["date"]), str(row["strategy"]), str(row["engine"])
    rc = RunCheck(f"{date}/{strategy}/{engine}")
    bad_name = [v for v in (date, strategy, engine) if not NAME.fullmatch(v)]
    if bad_name or (dates and date not in dates):
        what = f"names {bad_name[0]!r}, not a plain name" if bad_name else f"date {date!r} is not one of {META}'s dates"
        rc.fail("paths", f"runs.csv {what}: no file of the folder is read for it")
        return rc
    if engine.startswith("rpbench"):
        audit_engine(rc, folder, root, row, manifest)
        return rc
    path = records_file(folder, date, strategy, engine)
    if not inside(root, path):
        rc.fail("paths", f"{path.relative_to(folder).as_posix()} leads outside the folder (a symbolic link)")
        return rc
    name = path.relative_to(folder).as_posix()
    expected = (manifest is not None and name in manifest) or engine == "authors"
    if not path.is_file():
        if expected:
            rc.fail("records", f"{name} is missing (deleted?): the replication wrote the records of this run")
        else:
            for check in ("assignment", "accounting"):
                rc.skip(check, "records not kept for this ablation step")
        return rc
    try:
        records = pd.read_csv(path)
    except (OSError, ValueError) as exc:
        raise ResultsError(f"cannot read {str(path)!r}: {exc}") from None
    missing = [c for c in RECORD_COLUMNS if c not in records.columns]
    if missing:
        rc.fail("records", f"{name} lacks the column(s) {', '.join(missing)}: its run cannot be audited")
        return rc
    bad, checked = audit_run(records, row)
    rc.violations.update(bad)
    rc.checked.update(checked)
    for check, reason in SKIPPED.items():
        rc.skip(check, reason)
    return rc


def audit_engine(rc: RunCheck, folder: Path, root: Path, row: dict, manifest: dict | None) -> None:
    """rpbench's own engine: its results folder passes the full checker, and the row shows its KPIs."""
    path = engine_folder(folder, str(row["date"]), str(row["strategy"]), str(row["engine"]))
    name = path.relative_to(folder).as_posix()
    if not inside(root, path):
        rc.fail("paths", f"{name} leads outside the folder (a symbolic link)")
        return
    if not path.is_dir():
        if manifest is None:
            rc.skip("engine-rows", "a folder written before rpbench kept its own engine's runs (rerun replicate)")
        else:
            rc.fail("engine-rows", f"{name}/ is missing (deleted?): the replication wrote this run's results folder")
        return
    found = check_results(path)
    if found.error is not None:
        rc.fail("engine-folder", f"{name}: {found.error}")
        return
    for check in found.checks:
        for key, messages in check.violations.items():
            rc.violations.setdefault(key, []).extend(f"{name} {check.run}: {m}" for m in messages)
        for key, value in check.checked.items():
            rc.checked[key] = rc.checked.get(key, 0) + value
        for key, reason in check.skipped.items():
            rc.skip(key, reason)
    compare_engine_row(rc, path, name, row)


def compare_engine_row(rc: RunCheck, path: Path, name: str, row: dict) -> None:
    """The row's KPIs are its results folder's (which the checker recomputed), the response rate over the
    row's denominator, the vehicles its fleet."""
    try:
        kpis = read_results_table(path / KPIS, KPI_COLUMNS)
        fleet = pd.read_csv(path / FLEET)
    except (RpbenchError, OSError, ValueError) as exc:
        rc.fail("engine-rows", f"{name}: {one_line(exc)}")
        return
    strategy = str(row["strategy"])
    mine = kpis[kpis["run"] == strategy]
    have = dict(zip(mine["kpi"].astype(str), mine["value"], strict=True))
    expected: dict[str, float | None] = {k: as_number(have.get(k)) for k in ENGINE_KPIS}
    served, denominator = as_number(have.get("served")), as_number(row.get("response_denominator"))
    expected["response_rate"] = served / denominator if served is not None and denominator else float("nan")
    expected["vehicles"] = float(len(fleet))
    for key, value in expected.items():
        if key not in row:
            rc.fail("engine-rows", f"runs.csv has no {key} for this run")
            continue
        reported = as_number(row[key])
        if value is None or reported is None or not same(reported, value):
            rc.fail("engine-rows", f"{key}: runs.csv shows {row[key]!r}, {name} gives {value!r}")
    rc.checked["engine_rows"] = len(expected)


def inside(root: Path, path: Path) -> bool:
    """Does ``path``, symbolic links followed, stay inside the folder ``root`` (resolved)?"""
    try:
        path.resolve().relative_to(root)
    except (ValueError, OSError, RuntimeError):
        return False
    return True


def check_replication_manifest(fc: RunCheck, folder: Path, root: Path, meta: dict) -> dict[str, str] | None:
    """``manifest``: every file meta.json lists is there with its SHA-256, and nothing was added under
    records/ or engines/; ``paths``: no listed name leads outside the folder.  None: no manifest."""
    manifest = meta.get("manifest")
    if manifest is None:
        fc.skip(
            "manifest",
            f"{META} lists no files (a folder written before rpbench recorded them): an edited or deleted "
            "file is caught only where another check breaks",
        )
        return None
    files = manifest.get("files") if isinstance(manifest, dict) else None
    if not isinstance(files, dict) or not all(isinstance(v, str) for v in files.values()):
        fc.fail("manifest", f'{META}\'s manifest is malformed (expected {{"files": {{path: sha256}}}})')
        return {}
    ok: dict[str, str] = {}
    for name, digest in files.items():
        path = folder / name
        if not inside(root, path) or Path(name).is_absolute() or ".." in Path(name).parts:
            fc.fail("paths", f"{META} lists {name!r}, which leads outside the folder: not read")
            continue
        ok[name] = digest
        if not path.is_file():
            fc.fail("manifest", f"{name} listed in {META} is missing (deleted?)")
        elif file_sha256(path) != digest:
            fc.fail("manifest", f"{name} is not the file the replication wrote (its SHA-256 differs from {META}'s)")
    for top in (RECORDS_DIR, ENGINES_DIR):
        for path in sorted((folder / top).rglob("*")) if (folder / top).is_dir() else []:
            name = path.relative_to(folder).as_posix()
            if path.is_symlink() and not inside(root, path):
                fc.fail("paths", f"{name} is a symbolic link out of the folder")
            elif path.is_file() and name not in files:
                fc.fail("manifest", f"{name} is not a file the replication wrote ({META} does not list it)")
    for name in ("runs.csv", "report.md", "report.html"):
        if name not in files and (name == "runs.csv" or (folder / name).exists()):
            fc.fail("manifest", f"{META}'s manifest does not list {name}")
    fc.checked["files"] = len(ok)
    return ok


def check_replication_report(fc: RunCheck, folder: Path, root: Path, rows: pd.DataFrame, meta: dict) -> None:
    """``report``: the tables of report.md are their rendering from runs.csv (and meta.json)."""
    from rpbench.replication.report import markdown

    path = folder / "report.md"
    if not path.is_file() or not inside(root, path):
        fc.skip("report", "the folder has no report.md")
        return
    shown = _table_lines(path.read_text(errors="replace"))
    flags = [meta["reference_outputs"]] if isinstance(meta.get("reference_outputs"), bool) else [True, False]
    try:
        renderings = [_table_lines(markdown(rows, meta, reference=flag)) for flag in flags]
    except (KeyError, ValueError, TypeError, IndexError) as exc:
        fc.fail("report", f"runs.csv cannot be rendered ({type(exc).__name__}: {one_line(exc)})")
        return
    if shown in renderings:
        fc.checked["report_lines"] = len(shown)
        return
    want = renderings[0]
    diff = [(k, a, b) for k, (a, b) in enumerate(zip(shown, want, strict=False)) if a != b]
    if diff:
        k, a, b = diff[0]
        fc.fail("report", f"report.md table line {k + 1} shows {a!r}; runs.csv renders {b!r}")
    else:
        fc.fail("report", f"report.md has {len(shown)} table lines, runs.csv renders {len(want)}")


def _table_lines(text: str) -> list[str]:
    """The table rows of a markdown report (its numbers; the prose may change between versions)."""
    return [line.rstrip() for line in text.splitlines() if line.startswith("|")]


def check_replication(folder: Path) -> FolderResult:
    """A ``rpbench replicate`` folder: its files against meta.json's manifest, report.md against runs.csv,
    the authors' runs from their records, rpbench's own from their results folders; the rest skipped by
    name with the reason."""
    out = FolderResult(str(folder))
    try:
        with np.errstate(all="ignore"):
            out.folder_check, out.runs = audit_folder(Path(folder))
    except RpbenchError as exc:
        out.error = one_line(exc)
    return out
