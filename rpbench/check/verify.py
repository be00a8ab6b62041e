"""Which checks a comparison folder gets, and in which order (:mod:`.tree` dispatches any folder).

A comparison folder goes to its folder checks (:mod:`.folder`), each run's (:mod:`.lookahead`, :mod:`.events`,
:mod:`.kpis` and :mod:`.certificate` for a simulation, :mod:`.oracle` for an offline run), then the rows and
tables built over all runs (:mod:`.ratios`, ``hourly``, ``report``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.check.artefacts import check_artefacts
from rpbench.check.certificate import check_certificate
from rpbench.check.core import EVENT_SCHEMA, FOLDER, FolderResult, RunCheck
from rpbench.check.events import check_event_log, check_events, check_movement
from rpbench.check.exact import check_exact_plan
from rpbench.check.folder import (
    Folder,
    bound_km,
    check_digest,
    check_manifest,
    check_orders,
    read_folder,
    read_results_table,
)
from rpbench.check.kpis import (
    budget_expected,
    check_hourly,
    check_report,
    compare_kpis,
    decision_expected,
    hourly_expected,
    simulation_kpis,
)
from rpbench.check.lookahead import check_clairvoyant
from rpbench.check.oracle import check_oracle
from rpbench.check.page import check_page
from rpbench.check.ratios import check_ratios
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.results.layout import EVENTS, RUNS, TRAJECTORIES
from rpbench.results.ratios import RATIO_KPIS


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
    assert found.folder_check is not None  # set whenever the folder could be read
    return ([found.folder_check] if not found.folder_check.ok else []) + found.runs


def _check_comparison(folder: Path) -> tuple[RunCheck, list[RunCheck]]:
    """A comparison folder: its own checks, every run's, then hourly.csv and report.md over all runs."""
    f = read_folder(folder)
    fc = RunCheck(FOLDER)
    names = check_manifest(fc, f)
    check_digest(fc, f)
    check_orders(fc, f)
    bound = bound_km(f)
    runs, hourly = [], {}
    savings: dict[str, float | None] = {}  # each simulated run's saving, recomputed (None: it could not be)
    for name in names:
        rc, table = _check_run(f, name, bound, savings)
        runs.append(rc)
        if table is not None:
            hourly[name] = table
    check_ratios(fc, f, runs, savings)
    if not any(f.meta["runs"][name]["kind"] == "simulation" for name in names):
        hourly = {}  # hourly.csv is written for the strategy runs (and then the bound's split)
    per_hour = {
        name
        for name in names
        if f.meta["runs"][name]["kind"] == "simulation"
        or f.meta["runs"][name].get("rules", {}).get("window") == "bound"
    }
    check_hourly(fc, f, runs, hourly, per_hour)
    check_report(fc, f.path)
    check_page(fc, f)
    return fc, runs


def _check_run(
    f: Folder, name: str, bound: float | None, savings: dict[str, float | None]
) -> tuple[RunCheck, pd.DataFrame | None]:
    """One run's checks, and its expected rows of hourly.csv (None: an oracle without any).  A malformation
    the checker did not foresee makes the run unreadable (exit status 2), never a traceback."""
    run_dir = f.path / RUNS / name
    try:
        if f.meta["runs"][name]["kind"] == "oracle":
            return check_oracle(f, name, run_dir)
        return _check_simulation(f, name, run_dir, bound, savings)
    except RpbenchError:
        raise
    except (ValueError, TypeError, KeyError, IndexError, OverflowError, AttributeError) as exc:
        raise ResultsError(f"{str(run_dir)!r} cannot be checked: {type(exc).__name__}: {one_line(exc)}") from None


def _check_simulation(
    f: Folder, name: str, run_dir: Path, bound: float | None, savings: dict[str, float | None]
) -> tuple[RunCheck, pd.DataFrame | None]:
    """A simulation run: its clairvoyant flag, movement (nothing else can be read without it), then the event
    log, the service rules, the KPIs and the bound certificate; its recomputed saving goes to ``savings``."""
    rc = RunCheck(name)
    check_clairvoyant(rc, f, name)
    savings[name] = None
    events = read_results_table(run_dir / EVENTS, EVENT_SCHEMA)
    traj = results.load_trajectories(run_dir / TRAJECTORIES)
    if not check_movement(rc, traj, f.network, f.fleet["initial_node"].to_numpy(), f.params):
        for check in ("service", "max-pickup", "max-detour", "kpi", "competitive-ratio", "bound-certificate", "hourly"):
            rc.skip(check, "the trajectories cannot be read per vehicle (see [movement])")
        return rc, None
    events = check_event_log(rc, events, f, len(f.fleet))
    tab = check_events(rc, events, f, traj)
    kpis = simulation_kpis(tab, f.solo, f.params)
    reported = f.reported(name)
    kpis |= decision_expected(rc, f, name, reported)
    budget, claims = budget_expected(rc, f, name, reported)
    claims |= dict.fromkeys(RATIO_KPIS)  # derived from the other runs too: ``competitive-ratio`` checks them
    compare_kpis(rc, "simulation", kpis | budget, reported, claims)
    savings[name] = float(kpis["total_saving_km"])
    check_certificate(rc, tab, f, kpis["total_saving_km"], bound)
    check_artefacts(rc, f, name, run_dir)
    check_exact_plan(rc, f, name, run_dir, tab, kpis["total_saving_km"])
    rc.checked["orders"] = f.n
    rc.checked["served"] = int(tab["served"].sum())
    return rc, hourly_expected(tab, f.solo)
