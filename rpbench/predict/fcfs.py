"""First-come-first-served validation simulator (the dispatch rule the model assumes; TR-B §5).

Orders of every OD arrive as independent Poisson processes with the same
rates λ_w as the prediction.  Each new order looks, in its seeker's priority
order (the model's own matching list), for a taker state that is occupied
right now and pairs at once with the taker in the best one (within a class:
member order ``(w, k)``; within a state: the earliest taker).  Otherwise it
becomes a taker: it waits ``τ_0`` at its origin (state k = 0), then rides its
shortest path at speed v, one state per link, available to later seekers
the whole time; unpaired at the destination, it rode alone.  Vehicles are
unlimited and a pair is never revisited, exactly as in the model.

Using the model's matching sets (same geometry, same ``pre = len/2``
convention) isolates what the validation is about: the stochastic
approximations of the fixed point (Poisson opportunities, independence of
states, Little's-law occupancy), not the geometry.

:func:`validate` compares the per-OD pairing probability, ride distance and
shared distance with the prediction for ODs with enough simulated orders,
and reports MAPE and RMSE like TR-B (their Haikou MAPE: 3-17 % for the
pairing probability, about 2 % for the ride distance).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rpbench.exceptions import ParameterError
from rpbench.predict.prediction import Prediction, PredictionModel


@dataclass(frozen=True, eq=False)
class FcfsResult:
    """Per-OD sums over the orders requested inside the measurement window."""

    hours: float
    warmup_s: float
    seed: int
    orders: np.ndarray  # per OD: orders measured
    paired: np.ndarray  # ... of which paired (as seeker or taker)
    as_seeker: np.ndarray  # ... paired at request time
    ride_m: np.ndarray  # Σ ride distance
    shared_m: np.ndarray  # Σ shared distance
    saving_m: np.ndarray  # Σ pair saving E of the order's pair
    simulated_orders: int
    time_s: float


def simulate(model: PredictionModel, *, hours: float, seed: int = 0, warmup_s: float | None = None) -> FcfsResult:
    """Simulate ``hours`` of stationary Poisson demand after a warm-up (default: the longest trip time)."""
    if not np.isfinite(hours) or hours <= 0:
        raise ParameterError(f"--hours {hours!r} must be > 0")
    t_start = time.perf_counter()
    sp, m = model.space, model.matching
    lam = model.rates.rate_per_s
    off = sp.od_state_off
    n_od = len(lam)
    total = np.add.reduceat(sp.tau_s, off[:-1]) if sp.n_states else np.zeros(n_od)
    total = np.where(np.diff(off) > 0, total, 0.0)
    longest = float(total.max()) if n_od else 0.0
    warmup = longest if warmup_s is None else float(warmup_s)
    horizon = warmup + hours * 3600.0 + longest  # measured orders all resolve
    rng = np.random.default_rng(seed)
    counts = rng.poisson(lam * horizon)
    od_of = np.repeat(np.arange(n_od), counts)
    t_req = rng.uniform(0.0, horizon, size=len(od_of))
    order = np.lexsort((od_of, t_req))
    od_of, t_req = od_of[order], t_req[order]

    # State lookup: composite key (od, start time within the trip) -> current state of a taker.
    start_in_trip = _segment_inclusive(sp.tau_s, off) - sp.tau_s if sp.n_states else np.zeros(0)
    span = 2.0 * max(longest, 1.0)
    state_key = sp.od.astype(np.float64) * span + start_in_trip
    member_rank = np.empty(sp.n_states, dtype=np.int64)
    member_rank[sp.class_members] = np.arange(sp.n_states) - np.repeat(sp.class_off[:-1], sp.class_size)
    solo = sp.solo_m
    has_states = np.diff(off) > 0
    lists = _SeekerLists(m)

    ride = solo[od_of].copy()
    shared = np.zeros(len(od_of))
    saving = np.zeros(len(od_of))
    paired = np.zeros(len(od_of), dtype=bool)
    as_seeker = np.zeros(len(od_of), dtype=bool)
    act_id = np.zeros(0, dtype=np.int64)  # active (unpaired) takers: order index, OD, start time
    act_od = np.zeros(0, dtype=np.int64)
    act_t = np.zeros(0)
    for i in range(len(od_of)):
        t, w = t_req[i], int(od_of[i])
        if len(act_id):
            alive = t - act_t < total[act_od]
            if not alive.all():
                act_id, act_od, act_t = act_id[alive], act_od[alive], act_t[alive]
        j = lists.best(w, act_od, t - act_t, state_key, span, sp, member_rank, act_t) if len(act_id) else None
        if j is None:
            if has_states[w]:
                act_id = np.append(act_id, i)
                act_od = np.append(act_od, w)
                act_t = np.append(act_t, t)
            continue
        taker, state, rank = j
        e, sh, det = lists.pair_values(w, rank)
        k = int(act_id[taker])
        c = sp.cls[state]
        paired[[i, k]] = True
        as_seeker[i] = True
        ride[i] = solo[w] + det
        ride[k] = sp.delta_m[state] + sp.class_rest_m[c] - e - det + sh
        shared[[i, k]] = sh
        saving[[i, k]] = e
        act_id, act_od, act_t = np.delete(act_id, taker), np.delete(act_od, taker), np.delete(act_t, taker)

    window = (t_req >= warmup) & (t_req < warmup + hours * 3600.0)
    sums = [
        np.bincount(od_of[window], weights=x[window], minlength=n_od)
        for x in (np.ones(len(od_of)), paired, as_seeker, ride, shared, saving)
    ]
    return FcfsResult(
        hours=float(hours),
        warmup_s=warmup,
        seed=int(seed),
        orders=sums[0].astype(np.int64),
        paired=sums[1],
        as_seeker=sums[2],
        ride_m=sums[3],
        shared_m=sums[4],
        saving_m=sums[5],
        simulated_orders=len(od_of),
        time_s=time.perf_counter() - t_start,
    )


class _SeekerLists:
    """Per-seeker class ranks, built on first use (class id -> position in the priority list)."""

    def __init__(self, matching) -> None:
        self.m = matching
        self.cache: dict[int, tuple[np.ndarray, ...]] = {}

    def _get(self, w: int):
        hit = self.cache.get(w)
        if hit is None:
            cls, e, sh, det = self.m.seeker(w)
            by_cls = np.argsort(cls, kind="stable")
            hit = (cls[by_cls].astype(np.int64), by_cls, e, sh, det)
            self.cache[w] = hit
        return hit

    def best(self, w, act_od, elapsed, state_key, span, sp, member_rank, act_t):
        """(active-taker index, its state, rank in w's list) of the best occupied match, or None."""
        sorted_cls, pos, *_ = self._get(w)
        if len(sorted_cls) == 0:
            return None
        state = np.searchsorted(state_key, act_od * span + elapsed, side="right") - 1
        cls = sp.cls[state]
        at = np.minimum(np.searchsorted(sorted_cls, cls), len(sorted_cls) - 1)
        found = np.flatnonzero(sorted_cls[at] == cls)
        if len(found) == 0:
            return None
        rank = pos[at[found]]
        pick = found[np.lexsort((act_t[found], member_rank[state[found]], rank))[0]]
        return int(pick), int(state[pick]), int(pos[at[pick]])

    def pair_values(self, w: int, rank: int) -> tuple[float, float, float]:
        _, _, e, sh, det = self._get(w)
        return float(e[rank]), float(sh[rank]), float(det[rank])


def _segment_inclusive(values: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Inclusive cumulative sum restarted at each segment (segments are short: one trip's states)."""
    out = np.cumsum(values)
    lens = np.diff(offsets)
    base = np.repeat(np.concatenate([[0.0], out])[offsets[:-1]], lens)
    return out - base


def validate(prediction: Prediction, result: FcfsResult, *, min_samples: int = 20) -> tuple[dict, pd.DataFrame]:
    """Predicted vs simulated per-OD P_w, ride and shared distance; MAPE / RMSE over ODs with enough orders."""
    n = result.orders
    with np.errstate(divide="ignore", invalid="ignore"):
        sim_p = result.paired / n
        sim_ride = result.ride_m / n
        sim_shared = result.shared_m / n
    od = prediction.od
    table = pd.DataFrame(
        {
            "od": np.arange(len(n)),
            "orders": n,
            "pred_pairing_prob": od.pairing_prob,
            "sim_pairing_prob": sim_p,
            "pred_p_seeker": od.p_seeker,
            "sim_p_seeker": result.as_seeker / np.maximum(n, 1),
            "pred_ride_m": od.ride_m,
            "sim_ride_m": sim_ride,
            "pred_shared_m": od.shared_m,
            "sim_shared_m": sim_shared,
        }
    )
    sel = table[table["orders"] >= min_samples]
    metrics: dict = {
        "min_samples": int(min_samples),
        "ods_compared": len(sel),
        "orders_compared": int(sel["orders"].sum()),
        "hours": result.hours,
        "simulated_orders": result.simulated_orders,
        "sim_time_s": round(result.time_s, 3),
    }
    for name in ("pairing_prob", "p_seeker", "ride_m", "shared_m"):
        pred, sim = sel[f"pred_{name}"].to_numpy(), sel[f"sim_{name}"].to_numpy()
        pos = sim > 0
        metrics[name] = {
            "mape_pct": float(np.mean(np.abs(pred[pos] - sim[pos]) / sim[pos]) * 100) if pos.any() else None,
            "rmse": float(np.sqrt(np.mean((pred - sim) ** 2))) if len(sim) else None,
            "mean_pred": float(pred.mean()) if len(pred) else None,
            "mean_sim": float(sim.mean()) if len(sim) else None,
        }
    if len(sel):
        p, k = sel["sim_pairing_prob"].to_numpy(), sel["orders"].to_numpy()
        # Sampling noise alone: the binomial relative standard error of a simulated P_w.
        noise = np.sqrt(np.clip(p * (1 - p), 0, None) / k) / np.where(p > 0, p, np.nan)
        metrics["pairing_prob"]["sampling_noise_pct"] = float(np.nanmean(noise) * 100)
    lam = prediction.rates.rate_per_s
    measured = n.sum()
    metrics["overall"] = {
        "pred_pairing_rate": float((lam * od.pairing_prob).sum() / lam.sum()) if lam.sum() > 0 else 0.0,
        "sim_pairing_rate": float(result.paired.sum() / measured) if measured else 0.0,
        "pred_ride_m": float((lam * od.ride_m).sum() / lam.sum()) if lam.sum() > 0 else 0.0,
        "sim_ride_m": float(result.ride_m.sum() / measured) if measured else 0.0,
        "pred_shared_m": float((lam * od.shared_m).sum() / lam.sum()) if lam.sum() > 0 else 0.0,
        "sim_shared_m": float(result.shared_m.sum() / measured) if measured else 0.0,
    }
    return metrics, table
