"""``rpbench check`` for a replication folder: the checks that still apply to the authors' engine.

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

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.results.check.core import FolderResult, RunCheck

RECORDS_DIR = "records"
TOL_M = 1e-3
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


def records_file(folder: Path, date: str, strategy: str, engine: str) -> Path:
    """Where a replication folder keeps one run's passenger records."""
    return folder / RECORDS_DIR / f"{date}_{strategy}_{engine}.csv.gz"


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
        if abs(r["detour_m"] - (r["ride_m"] - r["solo_m"])) > TOL_M:
            fail("accounting", f"order {int(r['order_id'])}: detour {r['detour_m']:.3f} m != ride - solo")
        if r["shared_m"] > min(r["ride_m"], by_id.at[p, "ride_m"]) + TOL_M:
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
        reported = row.get(key)
        reported = np.nan if reported is None else float(reported)
        both_nan = not np.isfinite(value) and not np.isfinite(reported)
        if not both_nan and not np.isclose(value, reported, rtol=1e-9, atol=1e-6):
            fail("accounting", f"{key}: reported {reported!r}, recomputed {value!r}")
        checked["accounting"] += 1
    return bad, checked


def audit_folder(folder: Path) -> list[tuple[str, dict, dict, dict]]:
    """(run name, violations, checked, skipped) per run with records; rows without records are listed too."""
    runs_csv = folder / "runs.csv"
    if not runs_csv.is_file():
        raise ResultsError(f"replication folder {str(folder)!r} has no runs.csv")
    try:
        rows = pd.read_csv(runs_csv)
    except (OSError, ValueError) as exc:
        raise ResultsError(f"cannot read {str(runs_csv)!r}: {exc}") from None
    out: list[tuple[str, dict, dict, dict]] = []
    for row in rows.to_dict("records"):
        name = f"{row['date']}/{row['strategy']}/{row['engine']}"
        path = records_file(folder, row["date"], row["strategy"], row["engine"])
        if str(row["engine"]).startswith("rpbench"):
            out.append(
                (
                    name,
                    {},
                    {},
                    {
                        "all": "rpbench's own engine: check its results folder "
                        "(rpbench run --scenario haikou-paper-input) with rpbench check"
                    },
                )
            )
            continue
        if not path.is_file():
            out.append(
                (
                    name,
                    {},
                    {},
                    {
                        "assignment": "records not kept for this ablation step",
                        "accounting": "records not kept for this ablation step",
                    },
                )
            )
            continue
        try:
            records = pd.read_csv(path)
        except (OSError, ValueError) as exc:
            raise ResultsError(f"cannot read {str(path)!r}: {exc}") from None
        bad, checked = audit_run(records, row)
        out.append((name, bad, checked, dict(SKIPPED)))
    return out


def check_replication(folder: Path) -> FolderResult:
    """A ``rpbench replicate`` folder: the checks that apply to the authors' engine, the rest skipped by
    name with the reason."""
    out = FolderResult(str(folder))
    try:
        for name, violations, checked, skipped in audit_folder(folder):
            out.runs.append(RunCheck(name, violations=violations, checked=checked, skipped=skipped))
    except RpbenchError as exc:
        out.error = one_line(exc)
    return out
