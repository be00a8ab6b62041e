"""Expected savings and distances from a solved fixed point (docs/algorithms.md §2.7, paper Eqs. 8-11).

One more sweep over the seeker lists with the final ρ accumulates, per taker
class c, the opportunity-weighted sums ``Σ_s η^s E`` (weights
``λ_s Π_{c' ≻_s c} Q_c'``) and, per seeker, the pairing-rate-weighted sums
``Σ_t ρ_t η_t^s E`` (over a class: ``λ_s Π_{c' ≻ c} Q_c' (1 - Q_c)``, by
telescoping).  Then::

    (8')  ē(t)   = Σ_s η_t^s E / Σ_s η_t^s                     (0 when η_t = 0)
    (9')  ē(p)   = Σ_k π_k ē(t_k),  π_k = p_{t_k} Π_{j<k} (1 - p_{t_j})
    (11') ē(s)   = Σ_t E ρ_t η_t^s / Σ_t ρ_t η_t^s            (0 when p_s = 0)
          P_w    = p_s + (1 - p_s) Σ_k π_k
    (10') ē(0,p) = [1 - (1 - r_w)^{n_rem}] [p_s ē(s) + (1 - p_s) ē(p)]   (at dispatch time, see Prediction.e_wait)

The same weights give the TR-B per-OD outputs: expected ride, shared and
detour distance (unconditional, as a seeker, as a taker), in the column
conventions of the authors' published predictions (A12: savings are *not*
doubled; ``E`` is already the pair's total saving).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rpbench.predict._arrays import segment_sums
from rpbench.predict.fixed_point import Evaluation, PairSums, System, evaluate


@dataclass(frozen=True, eq=False)
class SavingsResult:
    """Per-OD and per-state results (arrays; distances in metres)."""

    # per OD
    p_seeker: np.ndarray  # p_s
    pairing_prob: np.ndarray  # P_w
    taker_paired: np.ndarray  # Σ_k π_k: P(paired | became a taker)
    e_seeker: np.ndarray  # ē(s)
    e_vacant: np.ndarray  # ē(p)
    solo_m: np.ndarray  # l_w
    seeker_detour_m: np.ndarray  # mean detour when paired as seeker
    seeker_shared_m: np.ndarray  # mean shared distance when paired as seeker
    taker_ride_m: np.ndarray  # E[ride | taker] (unpaired takers ride l_w)
    taker_detour_m: np.ndarray  # E[detour | taker]
    taker_shared_m: np.ndarray  # E[shared | taker]
    ride_m: np.ndarray  # E[ride]  (TR-B L_w)
    shared_m: np.ndarray  # E[shared] (TR-B E_w)
    # per state
    e_taker: np.ndarray  # ē(t)
    state_pair_prob: np.ndarray  # π_k (conditional on being a taker)
    state_ride_m: np.ndarray  # taker's ride when paired in this state
    state_shared_m: np.ndarray
    state_detour_m: np.ndarray

    #: The per-state fields (the rest are per OD).
    STATE_FIELDS = ("e_taker", "state_pair_prob", "state_ride_m", "state_shared_m", "state_detour_m")

    @property
    def detour_m(self) -> np.ndarray:
        return self.ride_m - self.solo_m

    @cached_property  # read for every waiting passenger of every FL round
    def e_bracket(self) -> np.ndarray:
        """``p_s ē(s) + (1 - p_s) ē(p)``: the expected saving once assigned (second bracket of Eq. 10)."""
        return self.p_seeker * self.e_seeker + (1.0 - self.p_seeker) * self.e_vacant


def savings_result(system: System, rho: np.ndarray) -> tuple[Evaluation, SavingsResult]:
    """Re-evaluate the map at ``rho`` (the solver's final ρ) and derive every expected quantity."""
    sp = system.space
    sums = PairSums.zeros(sp.n_classes, sp.n_od)
    ev = evaluate(system, rho, sums)
    h = ev.class_h
    with np.errstate(divide="ignore", invalid="ignore"):
        cls_mean = np.where(h > 0, sums.by_class[:, 1:].T / h, 0.0)  # E, shared, seeker detour | class
        s_rate = sums.by_seeker[:, 0]
        seek_mean = np.where(s_rate > 0, sums.by_seeker[:, 1:].T / s_rate, 0.0)
    e_cls, shared_cls, sdet_cls = cls_mean
    c = sp.cls
    e_taker = e_cls[c]
    state_shared = shared_cls[c]
    ride_from_h = sp.class_rest_m[c] - e_cls[c] - sdet_cls[c] + state_shared
    state_ride = sp.delta_m + ride_from_h
    solo = sp.solo_m
    state_detour = state_ride - solo[sp.od]
    pi = ev.p_taker * np.exp(-ev.log_not_taker)  # P(paired in state k | taker)
    off = sp.od_state_off
    x = ev.eta * sp.tau_s
    taker_paired = -np.expm1(-segment_sums(x, off))  # Σ_k π_k, telescoped (never > 1)
    e_vacant = segment_sums(pi * e_taker, off)
    taker_ride = segment_sums(pi * state_ride, off) + (1.0 - taker_paired) * solo
    taker_detour = segment_sums(pi * state_detour, off)
    taker_shared = segment_sums(pi * state_shared, off)
    p_s = ev.p_seeker
    e_seeker, seeker_shared, seeker_detour = seek_mean
    ride = p_s * (solo + seeker_detour) + (1.0 - p_s) * taker_ride
    shared = p_s * seeker_shared + (1.0 - p_s) * taker_shared
    return ev, SavingsResult(
        p_seeker=p_s,
        pairing_prob=np.minimum(1.0, p_s + (1.0 - p_s) * taker_paired),
        taker_paired=taker_paired,
        e_seeker=e_seeker,
        e_vacant=e_vacant,
        solo_m=solo,
        seeker_detour_m=seeker_detour,
        seeker_shared_m=seeker_shared,
        taker_ride_m=taker_ride,
        taker_detour_m=taker_detour,
        taker_shared_m=taker_shared,
        ride_m=ride,
        shared_m=shared,
        e_taker=e_taker,
        state_pair_prob=pi,
        state_ride_m=state_ride,
        state_shared_m=state_shared,
        state_detour_m=state_detour,
    )


def waiting_saving(
    bracket: np.ndarray, k_p, *, planner_patience_s: float, dt_s: float, response_rate: float
) -> np.ndarray:
    """ē(0,p) of Eq. (10'): ``[1 - (1 - r_w)^{n_rem}] * bracket``, ``bracket = p_s ē(s) + (1 - p_s) ē(p)``.

    ``n_rem = max(0, floor(K̄/Δt) - k_p)`` with the planner patience K̄ (A10) and
    ``k_p = ceil((t - t_req)/Δt)``, the passenger's round (1 at the first batch that sees it).
    """
    rounds = np.floor(planner_patience_s / dt_s + 1e-9)  # guard 90/10 = 8.999... style rounding
    n_rem = np.maximum(0.0, rounds - np.asarray(k_p, dtype=np.float64))
    return (1.0 - (1.0 - response_rate) ** n_rem) * bracket
