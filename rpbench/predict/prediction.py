"""The public entry point: :func:`predict` and the :class:`Prediction` the dispatcher queries.

``predict(network, rates, params, config)`` returns the prediction from the
disk cache (:mod:`.cache`) or else takes the states (:mod:`.states`) and
matching sets (:mod:`.match_sets`) from the seeker/taker structure
(:mod:`.list_cache`, built once per machine), solves the fixed point
(:mod:`.fixed_point`), derives the expected savings (:mod:`.savings`) and
caches the result.  The heavy matching sets are not kept: a
:class:`Prediction` holds per-OD and per-state arrays only.
"""

from __future__ import annotations

import dataclasses
import resource
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

import rpbench.predict.cache as cache
from rpbench.exceptions import ParameterError
from rpbench.network import RoadNetwork
from rpbench.predict.config import PredictConfig
from rpbench.predict.fixed_point import SolveInfo, System, solve_fixed_point
from rpbench.predict.list_cache import load_lists
from rpbench.predict.match_sets import Matching
from rpbench.predict.rates import OdRates
from rpbench.predict.savings import SavingsResult, savings_result, waiting_saving
from rpbench.predict.states import StateSpace
from rpbench.scenarios.base import Params

#: Seconds a solve runs before its progress bar appears (a cached or small prediction shows none).
PROGRESS_DELAY_S = 3.0


@dataclass(frozen=True)
class Lookup:
    """Per-passenger predictions for arrays of (origin, destination) node indices (0 where unknown)."""

    e_vacant: np.ndarray  # ē(p): expected saving when matched with a vacant vehicle (Eq. 9)
    p_seeker: np.ndarray  # p_s(w)
    e_seeker: np.ndarray  # ē(s(w)) (Eq. 11)
    pairing_prob: np.ndarray  # P_w
    known: np.ndarray  # bool: the OD is in the rate table


@dataclass(frozen=True, eq=False)
class PredictionModel:
    """The full model before solving: states, matching sets and rates (large; not cached)."""

    network: RoadNetwork
    rates: OdRates
    params: Params
    config: PredictConfig
    space: StateSpace
    matching: Matching
    build_s: dict

    @property
    def system(self) -> System:
        return System.build(self.space, self.matching, self.rates.rate_per_s, self.config)


@dataclass(frozen=True, eq=False)
class Prediction:
    """Solved prediction: per-OD and per-state results plus solver facts."""

    node_id: np.ndarray  # file node ids of the network (index -> id)
    rates: OdRates
    params: dict
    config: PredictConfig
    od: SavingsResult
    state_od: np.ndarray  # per state: OD index
    state_k: np.ndarray  # per state: k (0 = origin state)
    state_head: np.ndarray  # per state: head node index
    state_tau_s: np.ndarray
    rho: np.ndarray
    p_taker: np.ndarray
    eta: np.ndarray
    lam_taker: np.ndarray
    info: dict  # summary facts (see summary())
    from_cache: bool = False

    #: Per-state arrays stored beside the per-OD outcome (``od_<field>``) in the disk cache.
    STATE_FIELDS = ("state_od", "state_k", "state_head", "state_tau_s", "rho", "p_taker", "eta", "lam_taker")

    def arrays(self) -> tuple[dict[str, np.ndarray], dict]:
        """(arrays, facts) as the disk cache stores them: a lean prediction (``info["lean"]``) without its
        per-state arrays."""
        lean = self.info.get("lean", False)
        arrays = {
            f"od_{f.name}": getattr(self.od, f.name)
            for f in dataclasses.fields(SavingsResult)
            if not (lean and f.name in SavingsResult.STATE_FIELDS)
        }
        if not lean:
            arrays.update({name: getattr(self, name) for name in self.STATE_FIELDS})
        return arrays, self.info

    @classmethod
    def from_arrays(
        cls, stored: tuple[dict[str, np.ndarray], dict], *, node_id: np.ndarray, rates: OdRates, config: PredictConfig
    ) -> Prediction:
        """A prediction from the disk cache's (arrays, facts)."""
        arrays, info = stored
        empty = np.zeros(0)  # per-state arrays not read (a slim load) stay empty
        od = SavingsResult(**{f.name: arrays.get(f"od_{f.name}", empty) for f in dataclasses.fields(SavingsResult)})
        return cls(
            node_id=node_id,
            rates=rates,
            params=info.get("params", {}),
            config=config,
            od=od,
            info=info,
            from_cache=True,
            **{name: arrays.get(name, empty) for name in cls.STATE_FIELDS},
        )

    @classmethod
    def per_state_members(cls) -> frozenset[str]:
        """The disk cache's per-state members (skipped by a slim load)."""
        return frozenset(cls.STATE_FIELDS) | {f"od_{name}" for name in SavingsResult.STATE_FIELDS}

    def slim(self) -> Prediction:
        """The same prediction without its per-state arrays (what a dispatcher needs: per-OD values)."""
        empty = np.zeros(0)
        od = dataclasses.replace(self.od, **{name: empty for name in SavingsResult.STATE_FIELDS})
        per_state: dict[str, Any] = {name: empty for name in self.STATE_FIELDS}
        return dataclasses.replace(self, od=od, **per_state)

    @property
    def lean(self) -> bool:
        """Whether the prediction was solved and cached without its per-state arrays (:func:`predict`)."""
        return bool(self.info.get("lean", False))

    # ------------------------------------------------------------------ queries
    @cached_property
    def _keys(self) -> np.ndarray:
        return self.rates.key(len(self.node_id))  # sorted: the rates are canonical

    def _index(self, origins, destinations) -> tuple[np.ndarray, np.ndarray]:
        o = np.asarray(origins, dtype=np.int64)
        d = np.asarray(destinations, dtype=np.int64)
        keys = self._keys
        q = o * len(self.node_id) + d
        pos = np.clip(np.searchsorted(keys, q), 0, max(len(keys) - 1, 0))
        known = (keys[pos] == q) if len(keys) else np.zeros(q.shape, dtype=bool)
        return pos, known

    def lookup(self, origins, destinations) -> Lookup:
        """ē(p), p_s, ē(s), P_w for OD node-index arrays; an OD missing from the table gets 0 (§2.1)."""
        pos, known = self._index(origins, destinations)

        def take(values: np.ndarray) -> np.ndarray:
            return np.where(known, values[pos], 0.0) if len(values) else np.zeros(pos.shape)

        od = self.od
        return Lookup(
            e_vacant=take(od.e_vacant),
            p_seeker=take(od.p_seeker),
            e_seeker=take(od.e_seeker),
            pairing_prob=take(od.pairing_prob),
            known=known,
        )

    def e_wait(self, origins, destinations, k_p, params: Params) -> np.ndarray:
        """ē(0,p) of Eq. (10'): ``[1 - (1 - r_w)^{n_rem}] [p_s ē(s) + (1 - p_s) ē(p)]`` (0 for unknown ODs).

        ``n_rem = max(0, floor(K̄/Δt) - k_p)`` with the planner patience
        ``params.planner_patience_s`` (A10), ``r_w = params.response_rate``; ``k_p``
        is the passenger's round number (1 at the first batch that sees it).
        """
        pos, known = self._index(origins, destinations)
        bracket = self.od.e_bracket[pos] if len(self.od.e_bracket) else np.zeros(pos.shape)
        value = waiting_saving(
            bracket,
            k_p,
            planner_patience_s=params.planner_patience_s,
            dt_s=params.dt_s,
            response_rate=params.response_rate,
        )
        return np.where(known, value, 0.0)

    # ------------------------------------------------------------------ reports
    def per_od_table(self) -> pd.DataFrame:
        """One row per OD: rates, probabilities, expected distances and savings (metres).

        Columns ``matching_prob`` .. ``saved_distance_for_seeker`` follow the
        definitions of the authors' published predictions (A12: not doubled).
        """
        od, r = self.od, self.rates
        lam = r.rate_per_s
        return pd.DataFrame(
            {
                "od_id": r.od_id,
                "origin_id": self.node_id[r.origin],
                "destination_id": self.node_id[r.destination],
                "rate_per_s": lam,
                "solo_distance": od.solo_m,
                "p_seeker": od.p_seeker,
                "matching_prob": od.pairing_prob,
                "p_paired_as_taker": od.taker_paired,
                "e_seeker": od.e_seeker,
                "e_vacant": od.e_vacant,
                "e_assigned": od.e_bracket,
                "ride_distance": od.ride_m,
                "detour_distance": od.detour_m,
                "shared_distance": od.shared_m,
                "saved_distance": od.e_bracket,
                "ride_distance_for_taker": od.taker_ride_m,
                "detour_distance_for_taker": od.taker_detour_m,
                "shared_distance_for_taker": od.taker_shared_m,
                "saved_distance_for_taker": od.e_vacant,
                "ride_distance_for_seeker": od.p_seeker * (od.solo_m + od.seeker_detour_m)
                + (1.0 - od.p_seeker) * od.solo_m,
                "detour_distance_for_seeker": od.p_seeker * od.seeker_detour_m,
                "shared_distance_for_seeker": od.p_seeker * od.seeker_shared_m,
                "saved_distance_for_seeker": od.p_seeker * od.e_seeker,
            }
        )

    def summary(self) -> dict[str, Any]:
        """Facts for ``rpbench predict --json`` (ODs, states, pairs, iterations, residual, converged, ...)."""
        lam = self.rates.rate_per_s
        total = float(lam.sum())
        out = dict(self.info)
        out.update(
            {
                "from_cache": self.from_cache,
                "mean_pairing_prob": float((lam * self.od.pairing_prob).sum() / total) if total > 0 else 0.0,
                "mean_p_seeker": float((lam * self.od.p_seeker).sum() / total) if total > 0 else 0.0,
            }
        )
        return out


# ---------------------------------------------------------------------- build
def build_prediction_model(
    network: RoadNetwork,
    rates: OdRates,
    params: Params | None = None,
    config: PredictConfig | None = None,
    *,
    use_cache: bool = True,
) -> PredictionModel:
    """States and matching sets: the τ_0-independent structure from the disk cache (built once), τ_0 applied."""
    params = params or Params()
    config = config or PredictConfig()
    if len(rates) and (rates.origin.max() >= network.n_nodes or rates.destination.max() >= network.n_nodes):
        raise ParameterError("OD rates refer to nodes outside this network; build them for the same network")
    lists = load_lists(network, rates, params, config, use_cache=use_cache)
    return PredictionModel(
        network, rates, params, config, lists.space_for(config.tau0_s), lists.matching, lists.build_s
    )


def solve_prediction_model(
    model: PredictionModel, *, progress: Callable[[int, float], None] | None = None, rho0: np.ndarray | None = None
) -> Prediction:
    """Solve the fixed point of a built model (optionally warm-started) and derive the per-OD outcome.

    ``progress(iteration, residual)`` is called after every sweep; without it, a
    progress bar on stderr shows the sweeps and the savings pass once they
    have taken :data:`PROGRESS_DELAY_S` (only when stderr is a terminal).
    """
    system = model.system
    with _sweep_bar(progress) as report:
        ev, info = solve_fixed_point(system, progress=report, rho0=rho0)
        report(-1, info.residual)
        t0 = time.perf_counter()
        ev, out = savings_result(system, ev.rho)
        savings_s = time.perf_counter() - t0
    return _prediction(model, ev, out, info, savings_s)


@contextmanager
def _sweep_bar(progress: Callable[[int, float], None] | None) -> Iterator[Callable[[int, float], None]]:
    """``progress`` itself, or the updates of a delayed tqdm bar (iteration -1: the savings pass starts)."""
    if progress is not None:
        caller = progress

        def forward(it: int, res: float) -> None:
            if it >= 0:
                caller(it, res)

        yield forward
        return
    start = time.perf_counter()
    bar = tqdm(
        desc="prediction fixed point",
        unit=" sweeps",
        file=sys.stderr,
        leave=False,
        disable=None,
        delay=PROGRESS_DELAY_S,
    )  # off when stderr is not a terminal

    def update(it: int, res: float) -> None:
        if it < 0:
            bar.set_postfix_str(f"residual {res:.1e}; expected savings", refresh=False)
            if time.perf_counter() - start >= PROGRESS_DELAY_S:  # tqdm's delay holds for its updates only
                bar.refresh()
            return
        bar.set_postfix_str(f"residual {res:.1e}", refresh=False)
        bar.update(1)

    with bar:
        yield update


def cached_prediction(
    network: RoadNetwork, rates: OdRates, params: Params, config: PredictConfig, *, slim: bool = False
) -> Prediction | None:
    """The prediction for these inputs from the disk cache, or None; ``slim`` reads its per-OD arrays only.

    A lean entry (per-OD arrays only, :func:`predict` with ``lean``) serves a slim read; a full read
    finds nothing there (None), so the prediction is solved again and cached in full.
    """
    key = cache.cache_key(network, rates, params, config)
    hit = cache.load(key, len(rates), skip=Prediction.per_state_members() if slim else frozenset())
    if hit is None or (not slim and hit[1].get("lean", False)):
        return None
    return Prediction.from_arrays(hit, node_id=network.node_id, rates=rates, config=config)


def predict(
    network: RoadNetwork,
    rates: OdRates,
    params: Params | None = None,
    config: PredictConfig | None = None,
    *,
    use_cache: bool = True,
    progress: Callable[[int, float], None] | None = None,
    rho0: np.ndarray | None = None,
    lean: bool = False,
) -> Prediction:
    """The prediction for ``rates`` on ``network`` (cached on disk by inputs, parameters and network).

    When it is not cached, it is solved on the seeker/taker structure (built
    once per machine), warm-started from ``rho0`` if given, and then cached.
    ``lean``: what a dispatcher reads, the per-OD values only (:meth:`Prediction.slim`; ρ kept in memory, to
    warm-start another solve), cached so (a few MB instead of about 95 MB for the month table; a later full
    read solves it again).
    """
    params = params or Params()
    config = config or PredictConfig()
    if use_cache:
        hit = cached_prediction(network, rates, params, config, slim=lean)
        if hit is not None:
            return hit
    t0, c0 = time.perf_counter(), time.process_time()
    model = build_prediction_model(network, rates, params, config, use_cache=use_cache)
    prediction = solve_prediction_model(model, progress=progress, rho0=rho0)
    del model
    if lean:  # ρ stays in memory (a warm start for the next hour), not in the cache entry
        prediction = dataclasses.replace(prediction.slim(), rho=prediction.rho)
        prediction.info["lean"] = True
    prediction.info["time_s"] = round(time.perf_counter() - t0, 4)
    prediction.info["cpu_s"] = round(time.process_time() - c0, 4)  # wall > cpu when the machine is shared
    prediction.info["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)
    if use_cache:
        cache.save(cache.cache_key(network, rates, params, config), *prediction.arrays())
    return prediction


def _prediction(model: PredictionModel, ev, out: SavingsResult, info: SolveInfo, savings_s: float) -> Prediction:
    sp, m = model.space, model.matching
    relevant = {k: getattr(model.params, k) for k in cache.PARAM_FIELDS}
    facts = {
        "rates_source": model.rates.source,
        "ods": len(model.rates),
        "orders_per_hour": round(float(model.rates.rate_per_s.sum()) * 3600.0, 3),
        "states": sp.n_states,
        "taker_classes": sp.n_classes,
        "candidate_pairs": m.n_state_pairs(sp),
        "class_pairs": m.n_pairs,
        "stage1_candidates": int(m.stats.get("stage1_candidates", 0)),
        "iterations": info.iterations,
        "residual": info.residual,
        "converged": bool(info.converged),
        "clip_count": info.clip_count,
        "beta_final": info.beta,
        "timings_s": {
            **{k: round(v, 4) for k, v in model.build_s.items()},
            "solve_s": round(info.time_s, 4),
            "savings_s": round(savings_s, 4),
        },
        "matching_mb": round(m.nbytes / 2**20, 1),
        "params": relevant,
        "config": model.config.as_dict(),
    }
    return Prediction(
        node_id=model.network.node_id,
        rates=model.rates,
        params=relevant,
        config=model.config,
        od=out,
        state_od=sp.od,
        state_k=sp.k,
        state_head=sp.head,
        state_tau_s=sp.tau_s,
        rho=ev.rho,
        p_taker=ev.p_taker,
        eta=ev.eta,
        lam_taker=ev.lam_taker,
        info=facts,
    )
