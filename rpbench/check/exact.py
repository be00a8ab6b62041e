"""``exact-optimum``: an ``exact`` run realised the offline optimum its plan claims, pair by pair.

An ``exact`` run (:mod:`rpbench.strategies.exact`) carries its plan in ``runs/NAME/exact-plan/plan.json``
and names its SHA-256 in meta.json (``artefacts: {"exact-plan": DIGEST}``).  The checker reads the plan
with its own code and verifies: the digest; that the model was proven optimal (status ``optimal``, the
solver's bound below the objective + 1 block); that the plan's pairs sum to its objective, in whole blocks;
that the run formed exactly those pairs; and that the run's total saving, recomputed from its odometers,
is the objective.  It does not re-solve the model: that the model's optimum is OPT is the proof of
docs/bound.md ("Exact optima on lattice cities"), and that HiGHS or CP-SAT found it is their claim,
cross-checked by the tests.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.check.core import CERT_TOL_M, RunCheck
from rpbench.check.folder import Folder
from rpbench.files.digests import file_sha256
from rpbench.strategies.exact import EXACT_PLAN, PLAN_FILE


def plan_problem(folder: Path, digest: str) -> str | None:
    """What is wrong with the plan copy in ``folder`` before it is compared with the run (None: intact)."""
    path = folder / PLAN_FILE
    if not path.is_file():
        return f"missing: the run folder holds no {folder.name}/{PLAN_FILE}"
    if file_sha256(path) != digest:
        return f"{PLAN_FILE} is not the plan the run recorded (its SHA-256 differs)"
    return None


def check_exact_plan(rc: RunCheck, f: Folder, name: str, run_dir: Path, tab: pd.DataFrame, saving_km: float) -> None:
    """The run's pairs and saving are the plan's, and the plan is a proven optimum (see the module docstring)."""
    digest = (f.meta["runs"][name].get("artefacts") or {}).get(EXACT_PLAN)
    if digest is None:
        return
    problem = plan_problem(run_dir / EXACT_PLAN, str(digest))
    if problem is not None:
        rc.fail("exact-optimum", f"{name}/{EXACT_PLAN}: {problem}")
        return
    try:
        plan = json.loads((run_dir / EXACT_PLAN / PLAN_FILE).read_text(encoding="utf-8"))
        status, block = str(plan["status"]), float(plan["block_m"])
        objective_m, blocks, bound = (
            float(plan["objective_m"]),
            int(plan["objective_blocks"]),
            float(plan["bound_blocks"]),
        )
        pairs = np.array(plan["pairs"], dtype=np.float64).reshape(-1, 3)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        rc.fail("exact-optimum", f"{name}/{EXACT_PLAN}/{PLAN_FILE} is unreadable ({type(exc).__name__}: {exc})")
        return
    if status != "optimal" or not bound < blocks + 1:
        rc.fail("exact-optimum", f"the plan is not proven optimal (status {status}, {blocks} blocks, bound {bound:g})")
    if abs(blocks * block - objective_m) > CERT_TOL_M or abs(pairs[:, 2].sum() - objective_m) > CERT_TOL_M * max(
        1, len(pairs)
    ):
        rc.fail(
            "exact-optimum",
            f"the plan's objective {objective_m:.3f} m is not its {blocks} blocks of {block:g} m nor the sum of its "
            f"pairs' savings {pairs[:, 2].sum():.3f} m",
        )
    partner, ok = tab["partner"].to_numpy(), tab["ok"].to_numpy()
    mine = np.flatnonzero((partner >= 0) & ok & (partner > np.arange(len(partner))))
    formed = {(int(a), int(partner[a])) for a in mine}
    planned = {(int(min(a, b)), int(max(a, b))) for a, b in pairs[:, :2].astype(np.int64)}
    if formed != planned:
        extra, missing = sorted(formed - planned)[:3], sorted(planned - formed)[:3]
        rc.fail(
            "exact-optimum",
            f"the run formed {len(formed)} pairs, the plan {len(planned)}: not in the plan {extra}, missing {missing}",
        )
    if abs(saving_km * 1000.0 - objective_m) > CERT_TOL_M * max(1, len(pairs)):
        rc.fail(
            "exact-optimum",
            f"the run saved {saving_km * 1000.0:.3f} m, the plan's proven optimum is {objective_m:.3f} m",
        )
    rc.checked["exact_pairs"] = len(planned)
