"""Configuration of the prediction model (docs/algorithms.md §2, resolutions A1-A11).

The network-side parameters (R̄ ``max_pickup_m``, D̄ ``max_detour_m``, speed
``speed_mps``) come from :class:`rpbench.scenarios.base.Params`; everything that
only the prediction model uses lives here.  Defaults are the spec's.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.geometry import ORDER_RULES

#: Priority orders of a seeker's taker list (§2.4); all are "higher value first".
PRIORITIES = ("net_saving", "fl_utility", "pickup", "vehicle_distance", "authors_feng_grid")
#: How ρ is formed from λ_t, η_t, τ_t (A8): Little's law (the paper) or the Poisson form.
RHO_MODES = ("little", "poisson")
#: Fixed-point acceleration: none (the spec's plain damped iteration) or Anderson mixing.
ACCELERATIONS = ("none", "anderson")
#: Fallback sojourn of the origin/pick-up taker state (A4).
DEFAULT_TAU0_S = 120.0


@dataclass(frozen=True)
class PredictConfig:
    """Options of the seeker/taker model and of its damped fixed-point solver."""

    tau0_s: float = DEFAULT_TAU0_S  # τ_0: sojourn of the origin state (calibrated mean pick-up time, A4)
    include_origin_state: bool = True  # taker state k = 0 at the origin (A4)
    priority: str = "net_saving"  # §2.4 / A7
    keep_nonpositive: bool = False  # keep pairs with E <= 0 (A11 drops them)
    order_rule: str = "min_feasible"  # §1.1 / A6
    rho_mode: str = "little"  # A8
    beta: float = 0.5  # damping β (A9)
    beta_floor: float = 1.0 / 16.0
    grow_patience: int = 5  # halve β after this many growing residuals in a row
    tol: float = 1e-10  # stop when max|ρ' - ρ| <= tol
    max_iter: int = 2000
    rho_cap: float = 1.0 - 1e-12  # clip of ρ' (A8)
    accel: str = "none"  # "anderson": same fixed point in fewer sweeps
    anderson_depth: int = 5

    def __post_init__(self) -> None:
        if not np.isfinite(self.tau0_s) or self.tau0_s < 0:
            raise ParameterError(f"tau0_s = {self.tau0_s!r} must be a finite number >= 0 (seconds)")
        if self.priority not in PRIORITIES:
            raise ParameterError(f"priority {self.priority!r} unknown; expected one of {', '.join(PRIORITIES)}")
        if self.order_rule not in ORDER_RULES:
            raise ParameterError(f"order_rule {self.order_rule!r} unknown; expected one of {', '.join(ORDER_RULES)}")
        if self.rho_mode not in RHO_MODES:
            raise ParameterError(f"rho_mode {self.rho_mode!r} unknown; expected one of {', '.join(RHO_MODES)}")
        if not 0 < self.beta <= 1 or not 0 < self.beta_floor <= self.beta:
            raise ParameterError(
                f"damping beta = {self.beta!r} must lie in (0, 1] and beta_floor = {self.beta_floor!r} in (0, beta]"
            )
        if not self.tol > 0 or int(self.max_iter) < 1 or int(self.grow_patience) < 1:
            raise ParameterError("tol must be > 0, max_iter and grow_patience >= 1")
        if self.accel not in ACCELERATIONS:
            raise ParameterError(f"accel {self.accel!r} unknown; expected one of {', '.join(ACCELERATIONS)}")
        if int(self.anderson_depth) < 1:
            raise ParameterError(f"anderson_depth = {self.anderson_depth!r} must be >= 1")
        if not 0 < self.rho_cap < 1:
            raise ParameterError(f"rho_cap = {self.rho_cap!r} must lie in (0, 1)")

    def replace(self, **changes: Any) -> PredictConfig:
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise ParameterError(
                f"unknown prediction option(s) {', '.join(sorted(unknown))}; "
                f"known: {', '.join(f.name for f in dataclasses.fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)
