"""The offline oracle: Oracle-1 (maximum saving) and Oracle-2 (maximum pairs) over a whole period.

docs/algorithms.md §4.  The paper's oracle (Eqs. 16-20, its "linear program"
over ``x_ij`` for all ``i, j`` with ``x_ij = x_ji`` and ``e(i,i) = 0``) is a
maximum-weight matching in the general graph of feasible pairs (§4.1):

* Oracle-1: maximise ``Σ e_ij`` over the pairs with ``e_ij > 0`` (A11, A19);
* Oracle-2: maximise the number of pairs over every feasible pair, ties
  broken by maximum total saving (A20).

Candidate pairs and their savings come from :mod:`rpbench.oracle.pairs`
(§4.2, A18).  The matching is solved by any solver preset whose backend
solves :class:`~rpbench.model.PairingModel` exactly.  The saving is reported
once per pair; the seed's double sum counts every pair twice (§4.1, O-T7),
so its objective is ``2 S``.  The oracle reports the matching, not a
vehicle simulation of it: response rate and pick-up times of the paper's
Table 2 need the simulator.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from rpbench.backends import BACKEND_REGISTRY, Backend, Preset, SolveOptions, backend_class, load_preset, solve
from rpbench.backends.cardinality import maximum_cardinality_matching
from rpbench.exceptions import ParameterError, PresetError, RpbenchError
from rpbench.model import PairingModel, Solution, Status, Structure, quantize
from rpbench.oracle.pairs import CandidatePairs, PairRules, find_candidates
from rpbench.scenarios.base import Scenario

#: Oracle variant -> PairingModel objective (§4.3).
VARIANTS = {1: "weight", 2: "cardinality_then_weight"}

#: Resolution of the savings in the model (1 cm).  Exact integer algorithms have a
#: bounded range -- PyMatching keeps weights exact only below 2**24, and its
#: reduction needs about twice the largest saving (plus Oracle-2's bonus) --
#: so 1 mm overflows on Haikou trips of 30+ km while 1 cm does not.  Every
#: backend sees the same rounded values; reported savings are the unrounded sums.
#: The solver proves the optimum of the *rounded* savings, which may miss the
#: unrounded optimum by up to one unit per pair (:attr:`OracleResult.rounding_slack_m`
#: bounds it): 0.5 m per pair at :data:`MAX_UNIT_M`, a few parts in ten thousand of a
#: pair's typical saving of a kilometre or more.
UNIT_M = 0.01
#: The sane range of ``unit_m``: coarser units let rounding change the optimum by more than the savings'
#: own precision (``--unit-m 5000`` rounds nearly every saving to 0 or 1 unit); finer than 1 µm the
#: rounded savings of 100 km trips leave float64's exact integers (2**53).
MIN_UNIT_M = 1e-6
MAX_UNIT_M = 1.0

#: KPI keys shared with the strategies' reports (NaN where undefined).
KPI_KEYS = ("orders", "pairs", "pooled_passengers", "pairing_ratio", "avg_detour_m", "avg_shared_m", "total_saving_km")


@dataclass(frozen=True, eq=False)
class OracleResult:
    """One oracle solve: the matching, its KPIs, and where the time went."""

    variant: int
    scenario: str
    rules: PairRules
    solver: str
    n_orders: int
    n_candidates: int  # feasible pairs found (§4.2)
    n_evaluated: int  # pairs inside the time windows, tested with POOL
    model: PairingModel
    solution: Solution
    pairs: pd.DataFrame  # the chosen pairs, one row each
    timings: dict = field(default_factory=dict)

    @property
    def status(self) -> Status:
        return self.solution.status

    @functools.cached_property
    def max_pairs(self) -> int:
        """The proven largest number of pairs (Edmonds, 0.7 s on the full day: computed once)."""
        return maximum_pairs(self.model)

    @property
    def total_saving_m(self) -> float:
        """S = Σ e over chosen pairs, each pair counted once (O-T7)."""
        return float(self.pairs["saving_m"].sum())

    @property
    def is_upper_bound(self) -> bool:
        """Is this the proven upper bound's matching (docs/bound.md), not one of the paper's oracles?"""
        return self.rules.window == "bound"

    @property
    def upper_bound_m(self) -> float:
        """The proven upper bound on any strategy's saving: the optimum of the rounded-up weights, or the
        solver's dual bound when it stopped early (NaN without one).  Only for :attr:`is_upper_bound`."""
        sol, unit = self.solution, self.model.unit_m
        if sol.status is Status.OPTIMAL:
            return sol.objective * unit
        return sol.bound * unit if sol.bound is not None else float("nan")

    @property
    def rounding_slack_m(self) -> float:
        """A proven bound on how far the unrounded optimum may lie above :attr:`total_saving_m` because the
        model rounds each saving to ``unit_m`` (NaN for the upper bound, whose rounding is upwards, and for an
        unproven solve).

        Each saving is within ``unit/2`` of its rounded value, and the rounded optimum is ``V``; so any
        matching of ``P`` pairs is worth at most ``unit (V + P/2)`` unrounded, while the chosen one is worth
        :attr:`total_saving_m`.  ``P`` is the number of pairs Oracle-2 proves maximal, or at most half the
        orders for Oracle-1.
        """
        if self.is_upper_bound or self.status is not Status.OPTIMAL:
            return float("nan")
        unit = self.model.unit_m
        rounded = float(np.sum(self.model.values[self.solution.chosen]))
        most_pairs = len(self.pairs) if self.variant == 2 else self.n_orders // 2
        return max(0.0, unit * (rounded + most_pairs / 2) - self.total_saving_m)

    @property
    def seed_objective_m(self) -> float:
        """The paper's double-counted objective Σ_i Σ_j e(i,j) x_ij = 2 S (§4.1)."""
        return 2.0 * self.total_saving_m

    def kpis(self) -> dict:
        """Flat KPI dictionary (``KPI_KEYS`` first, then solver fields)."""
        p = self.pairs
        n_pairs = len(p)
        detours = np.concatenate([p["detour_first_m"].to_numpy(), p["detour_second_m"].to_numpy()])
        sol, unit = self.solution, self.model.unit_m
        return {
            "orders": self.n_orders,
            "pairs": n_pairs,
            "pooled_passengers": 2 * n_pairs,
            "pairing_ratio": 2 * n_pairs / self.n_orders if self.n_orders else float("nan"),
            # Per paired passenger; both members of a pair share the same distance.
            "avg_detour_m": float(detours.mean()) if n_pairs else float("nan"),
            "avg_shared_m": float(p["shared_m"].mean()) if n_pairs else float("nan"),
            # the upper bound reports the proven bound; an oracle the saving of its pairs
            "total_saving_km": (self.upper_bound_m if self.is_upper_bound else self.total_saving_m) / 1000.0,
            "variant": self.variant,
            "solver": self.solver,
            "status": sol.status.value,
            "objective_m": sol.objective * unit,
            "bound_m": sol.bound * unit if sol.bound is not None else float("nan"),
            "gap": sol.gap if sol.gap is not None else float("nan"),
            "candidates": self.n_candidates,
            "edges": self.model.n_cols,
            # Oracle-2's certificate: the proven maximum number of pairs (Oracle-1 does not need it)
            "pairs_bound": float(self.max_pairs) if self.variant == 2 else float("nan"),
            **self.timings,
        }


def maximum_pairs(model: PairingModel) -> int:
    """The largest number of pairs of any matching (Oracle-2's stage 1), proven.

    Edmonds' algorithm with a Tutte-Berge set as certificate
    (:mod:`rpbench.backends.cardinality`); it lets a report state Oracle-2's
    cardinality as proven even when a solver stopped early on the weight.
    """
    if model.n_cols == 0:
        return 0
    return maximum_cardinality_matching(model.n_orders, model.col_a, model.col_b).size


def check_variant(variant) -> int:
    try:
        v = int(variant)
    except (TypeError, ValueError):
        v = None
    if v not in VARIANTS or isinstance(variant, bool) or (isinstance(variant, float) and variant != v):
        raise ParameterError(
            f"oracle variant {variant!r} unknown; expected 1 (maximum saving) or 2 (maximum pairs, ties by saving)"
        )
    return v


def oracle_model(
    candidates: CandidatePairs, variant: int, *, unit_m: float = UNIT_M
) -> tuple[PairingModel, np.ndarray]:
    """The PairingModel of a variant and, per column, its row in ``candidates``.

    Oracle-1 keeps the pairs whose quantised saving is positive (a pair with
    ``e <= 0`` never raises the total, A11); Oracle-2 keeps every feasible pair.
    The upper bound's savings are rounded *up* to the unit, so the optimum of
    the model is a bound on the unrounded one (docs/bound.md).
    """
    variant = check_variant(variant)
    if candidates.rules.window == "bound":
        values = np.ceil(np.asarray(candidates.saving_m, dtype=np.float64) / unit_m)
    else:
        values = quantize(candidates.saving_m, unit_m)
    rows = np.flatnonzero(values > 0) if variant == 1 else np.arange(len(candidates))
    model = PairingModel(
        candidates.n_orders,
        candidates.low[rows],
        candidates.high[rows],
        values[rows],
        objective=VARIANTS[variant],
        unit_m=unit_m,
        name=f"oracle-{variant}",
    )
    return model, rows


def resolve_preset(solver: str | Preset | Backend, options: SolveOptions | None = None) -> Preset:
    """A preset from a preset name, a Preset, or a Backend object; ``options`` override its own."""
    if isinstance(solver, Backend):
        preset = Preset.of(solver, options)
    else:
        preset = solver if isinstance(solver, Preset) else load_preset(str(solver))
        if options is not None:
            preset = dataclasses.replace(preset, options=options)
    if not preset.adapter().supports(Structure.PAIRING):
        raise PresetError(
            f"solver {preset.name!r} (backend {preset.backend!r}) does not solve the pairing model "
            f"exactly; choose a backend that does: {', '.join(pairing_backends()) or 'none'}"
        )
    return preset


def pairing_backends() -> list[str]:
    """Registered backends that declare the pairing structure exact (modules that import)."""
    out = []
    for name in BACKEND_REGISTRY:
        try:
            if Structure.PAIRING in backend_class(name).exact:
                out.append(name)
        except (ImportError, RpbenchError):
            continue
    return out


def solve_oracle(
    scenario: Scenario,
    variant: int = 1,
    solver: str | Preset | Backend = "matching",
    *,
    rules: PairRules | None = None,
    candidates: CandidatePairs | None = None,
    options: SolveOptions | None = None,
    unit_m: float = UNIT_M,
) -> OracleResult:
    """Solve Oracle-``variant`` over all orders of ``scenario``.

    ``rules`` default to the scenario's K̄, D̄, R̄, v with the authors' flags
    (§4.2).  Pass ``candidates`` (from :func:`find_candidates`) to share one
    enumeration between both variants; ``options`` override the preset's;
    ``unit_m`` is the savings' resolution in the model (see :data:`UNIT_M`).
    """
    variant = check_variant(variant)
    preset = resolve_preset(solver, options)
    if candidates is None:
        rules = rules or PairRules.from_params(scenario.params)
        candidates = find_candidates(scenario.network.distances(), scenario.orders, rules)
    elif rules is not None and rules != candidates.rules:
        raise ParameterError("solve_oracle: `rules` differ from the rules the candidates were built with")
    if candidates.n_orders != len(scenario.orders):
        raise ParameterError(f"candidates cover {candidates.n_orders} orders, the scenario has {len(scenario.orders)}")

    t0 = time.perf_counter()
    model, rows = oracle_model(candidates, variant, unit_m=unit_m)
    model_s = time.perf_counter() - t0
    solution = solve(model, preset)  # a matching of the model: verified there

    chosen = rows[solution.chosen]
    pairs = candidates.take(chosen).to_frame(scenario.orders)
    timings = {
        "candidates_s": candidates.seconds,
        "model_s": model_s,
        "build_s": solution.build_s,
        "solve_s": solution.solve_s,
        "extract_s": solution.extract_s,
        "total_s": candidates.seconds + model_s + solution.total_s,
    }
    return OracleResult(
        variant=variant,
        scenario=scenario.name,
        rules=candidates.rules,
        solver=preset.name,
        n_orders=len(scenario.orders),
        n_candidates=len(candidates),
        n_evaluated=candidates.evaluated,
        model=model,
        solution=solution,
        pairs=pairs,
        timings=timings,
    )


__all__ = [
    "KPI_KEYS",
    "MAX_UNIT_M",
    "MIN_UNIT_M",
    "UNIT_M",
    "VARIANTS",
    "CandidatePairs",
    "OracleResult",
    "PairRules",
    "find_candidates",
    "oracle_model",
    "pairing_backends",
    "resolve_preset",
    "solve_oracle",
]
