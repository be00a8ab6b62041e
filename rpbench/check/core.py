"""The checker's verdicts (:class:`RunCheck`, :class:`FolderResult`), tolerances, KPI lists and column schemas.

Every other module of the checker builds on this one and on nothing of the package face, so the package
imports in one direction: core, then the folder's inputs (:mod:`.folder`), the checks, the entry points.  The
KPI names come from where rpbench defines them (:mod:`rpbench.results.metrics`, :mod:`rpbench.results.ratios`);
the values are recomputed here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.ratios import DERIVED_KPIS

TOL_M = 1e-6
TOL_S = 1e-6
#: POOL's inclusive detour tolerance (rpbench.geometry.TOLERANCE_M): a detour of exactly D̄ is allowed.
DETOUR_TOL_M = 1e-9
#: A recomputed KPI may differ from the reported one by this much (relative, plus :data:`KPI_ATOL`): the
#: checker sums the same odometer readings in another order; a report prints 3 to 6 significant digits.
KPI_RTOL = 1e-8
KPI_ATOL = 1e-6
#: Tolerance of the bound certificate: a realised saving may exceed its edge weight by float rounding only.
CERT_TOL_M = 1e-3
#: The name under which a folder's own checks are reported.
FOLDER = "(folder)"
#: ``rpbench check`` exit statuses.
EXIT_OK, EXIT_FAILED, EXIT_UNREADABLE = 0, 1, 2
EVENT_KINDS = ("request", "assign", "pickup", "dropoff", "cancel", "reposition")
#: Reported figures the files cannot reproduce (timings: a run's wall time, a strategy's one-off
#: ``prepare()``, the oracle's stages; sizes of the oracle's enumeration and model; the solver's gap): listed
#: in docs/guarantees.md; any other KPI in kpis.csv must be one the checker recomputes.
UNVERIFIED_KPIS = {
    "simulation": {"wall_s", "prepare_s"},
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
#: The bound's matching statistics, under their own names (they bound nothing).
BOUND_KPIS = tuple(BOUND_MATCHING_KPIS.get(k, k) for k in ORACLE_KPIS)
KNOWN_KPIS = {
    *SIMULATION_KPIS,
    *ORACLE_KPIS,
    *BOUND_KPIS,
    *DERIVED_KPIS,
    *UNVERIFIED_KPIS["simulation"],
    *UNVERIFIED_KPIS["oracle"],
}
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
EVENT_SCHEMA = {"t_s": "float", "event": "str", "order": "int", "vehicle": "int", "node": "int", "partner": "int"}
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
    def ran(self) -> bool:
        """Did any check run (count something)?  A run whose every check was skipped is not OK, only skipped."""
        return any(v for v in self.checked.values())

    @property
    def status(self) -> str:
        return "failed" if not self.ok else "ok" if self.ran else "skipped"


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


def format_report(checks: list[RunCheck]) -> str:
    """The verdicts as ``rpbench check`` prints them: per run OK with its counts, SKIPPED when no check could
    be made, or FAILED with the first three messages of each failed check; then the skipped checks and why."""
    lines = []
    for rc in checks:
        if rc.ok and not rc.ran:
            lines.append(f"{rc.run}: SKIPPED (no check could be made)")
        elif rc.ok:
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


# ----------------------------------------------------------------- reported values
def as_number(value: Any) -> float | None:
    """A reported value (a table cell) as a float (NaN for an empty cell), None when it is text."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number


def show(value: Any) -> str:
    """A value for a message: a number as a plain float (not ``np.float64(...)``), text quoted."""
    number = as_number(value)
    return repr(number) if number is not None else repr(str(value))


def same(reported: float, value: float, rtol: float = KPI_RTOL, atol: float = KPI_ATOL) -> bool:
    """Equal up to the tolerance; two NaN (an undefined KPI, reported empty) are equal."""
    if np.isnan(reported) or np.isnan(value):
        return bool(np.isnan(reported) and np.isnan(value))
    return bool(np.isclose(reported, value, rtol=rtol, atol=atol))
