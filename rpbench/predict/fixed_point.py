"""The fixed-point system (A1)-(A6) and its damped solver (docs/algorithms.md §2.5-§2.6).

The system reduces to a map on ρ (one value per taker state).  One
evaluation, :func:`evaluate`, computes from ρ::

    Q_c          = Π_{t∈c} (1 - ρ_t)                       per taker class c
    η_t^{s}      = λ_{w'} Π_{t' ≻_s t} (1 - ρ_t')          (A4)  running product along s's list
    p_s          = 1 - Π_{t∈T_s} (1 - ρ_t)                 (A1)
    η_t          = Σ_s η_t^s                                (A3)
    p_t          = 1 - exp(-η_t τ_t)                       (A2)
    λ_t(0,w)     = λ_w (1 - p_s(w)),  λ_t(k) = λ_t(k-1) (1 - p_t(k-1))     (A6, index typo fixed: resolution A2)
    ρ'_t         = λ_t (1 - e^{-η_t τ_t}) / η_t            (A5 with the missing /η: resolution A1; λ_t τ_t at η = 0)

Seeker lists hold taker classes (:mod:`.states`): the members of a class are
adjacent in every list, so a seeker's running product is carried per class
(``Q_c``) and the opportunity rate of member t is ``η_t = r_t H_c`` with
``H_c = Σ_s λ_s Π_{c' ≻_s c} Q_c'`` and ``r_t`` the product over earlier
members of the same class.  The sweep over the seekers' lists, and the
per-class and per-state passes around it, are compiled (:mod:`.kernels`):
a seeker's running product ``λ_s Π Q_c'`` is carried as a
product and its total ``log(1 - p_s)`` as a sum of ``log Q_c``; ``1 - e^{-x}``
is ``-expm1(-x)``, and ``log(1 - p_t) = -η_t τ_t`` exactly.  Everything is float64.

:func:`solve_fixed_point` iterates ``ρ <- (1-β)ρ + β clip(ρ')`` from ρ = 0 (A9): β halves
after ``grow_patience`` growing residuals in a row (floor ``beta_floor``), the
stop is ``max|ρ' - ρ| <= tol`` or ``max_iter``, and the returned evaluation is
recomputed from the final ρ so that all reported quantities are mutually
consistent.  ρ' is clipped to ``[0, rho_cap]`` (A8) and the clips counted.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from numba import get_num_threads

from rpbench.predict.anderson import AndersonMixing
from rpbench.predict.config import PredictConfig
from rpbench.predict.kernels import (
    CELL_ROW,
    SAVINGS_ROW,
    SWEEP_ROW,
    class_products,
    savings_blocks,
    sweep_blocks,
    taker_map,
)
from rpbench.predict.match_sets import CHUNK_PAIRS, Matching
from rpbench.predict.states import StateSpace


@dataclass(frozen=True, eq=False)
class System:
    """Everything one evaluation of the map needs (read-only)."""

    space: StateSpace
    matching: Matching
    rate_per_s: np.ndarray  # λ_w per OD
    config: PredictConfig
    work: dict = field(default_factory=dict, repr=False)  # sweep buffers, reused across iterations

    @classmethod
    def build(cls, space: StateSpace, matching: Matching, rate_per_s: np.ndarray, config: PredictConfig) -> System:
        return cls(space, matching, np.asarray(rate_per_s, dtype=np.float64), config)

    def scratch(self, rows: int, n_classes: int) -> np.ndarray:
        """Per-chunk class sums of a sweep, allocated once: fresh tens of megabytes every
        sweep would cost page faults (a large share of the time on a virtual machine)."""
        buf = self.work.get("chunk_h")
        if buf is None or buf.shape != (rows, n_classes):
            buf = self.work["chunk_h"] = np.empty((rows, n_classes))
        return buf


@dataclass(frozen=True, eq=False)
class Evaluation:
    """All variables computed from one ρ (per state unless noted)."""

    rho: np.ndarray  # the input ρ
    rho_next: np.ndarray  # clip(ρ'), the map's output
    clipped: np.ndarray  # bool: the clip of A8 was active
    eta: np.ndarray  # η_t
    p_taker: np.ndarray  # p_t
    lam_taker: np.ndarray  # λ_t
    log_not_taker: np.ndarray  # Σ_{j<k} η_j τ_j along the path (log of 1/Π_{j<k}(1-p_j))
    p_seeker: np.ndarray  # p_s per OD
    class_log_q: np.ndarray  # log Q_c per class
    class_h: np.ndarray  # H_c per class
    member_log_r: np.ndarray  # log r_t per state

    @property
    def residual(self) -> float:
        return float(np.max(np.abs(self.rho_next - self.rho))) if len(self.rho) else 0.0

    @property
    def clip_count(self) -> int:
        return int(self.clipped.sum())


@dataclass(frozen=True)
class SolveInfo:
    converged: bool
    residual: float
    iterations: int
    clip_count: int
    beta: float  # damping in force at the end
    time_s: float
    history: tuple = ()  # residual per iteration


SAVINGS_CHUNK_PAIRS = 1 << 22
SAVINGS_PARTS = 2


def sweep(
    system: System, class_log_q: np.ndarray, sums: PairSums | None = None, *, chunk_pairs: int = CHUNK_PAIRS
) -> tuple[np.ndarray, np.ndarray]:
    """One pass over all seeker lists: returns (H_c per class, log(1 - p_s) per OD).

    ``H_c = Σ_s λ_s Π_{c' ≻_s c} Q_c'`` and ``log(1 - p_s) = Σ_{c ∈ T_s} log Q_c``,
    computed by the compiled kernels one chunk of class blocks (:mod:`.blocks`)
    at a time, the chunks in parallel threads (the lists are usually memory
    maps).  With ``sums`` the pass also adds the
    savings pass's pair sums (:mod:`.savings`), their distances derived from
    the geometry (:func:`.kernels.savings_blocks`), and gives the chunks' pages
    of the lists back at once, so they never all sit in memory.
    """
    log_not_paired = np.zeros(len(system.rate_per_s))
    q = np.exp(class_log_q)
    m, lam = system.matching, system.rate_per_s
    blocks = m.blocks
    width = blocks.width
    block_args = (blocks.seeker_off, blocks.cls, blocks.cls_off)
    if sums is None:
        chunk_block = blocks.chunks(m.seeker_off, chunk_pairs)
        chunk_h = system.scratch(len(chunk_block) - 1, len(class_log_q))

        def sweep_chunk(k: int) -> None:
            chunk_h[k].fill(0.0)
            sweep_blocks(
                m.seeker_off,
                m.local,
                lam,
                q,
                class_log_q,
                *block_args,
                chunk_block[k],
                chunk_block[k + 1],
                chunk_h[k],
                log_not_paired,
                np.empty(width * int(SWEEP_ROW)),
            )

        _in_threads(sweep_chunk, len(chunk_block) - 1)
        return chunk_h.sum(axis=0), log_not_paired
    one_minus_q = -np.expm1(class_log_q)
    # The savings pass is the last over the lists.  Its chunks are cut into SAVINGS_PARTS runs of about
    # equal pairs; each run is walked in order by one task that sums its classes into its own part
    # (the parts are added in order: the result does not depend on the threads) and gives the list's
    # pages of a chunk back once it is summed, so the list never sits in memory whole.
    chunk_block = blocks.chunks(m.seeker_off, min(chunk_pairs, SAVINGS_CHUNK_PAIRS))
    runs = _cut(m.seeker_off[blocks.seeker_off[chunk_block]], SAVINGS_PARTS)
    parts = np.zeros((SAVINGS_PARTS, len(class_log_q), 4))
    geometry = m.geometry.kernel_args()
    dist = np.ascontiguousarray(m.geometry.distances())

    def savings_run(k: int) -> None:
        loc = np.empty(width * int(SAVINGS_ROW))
        nodes = np.empty(width, dtype=np.uint16 if len(dist) <= 1 << 16 else np.int64)
        cells = np.empty((len(dist), int(CELL_ROW)))
        todo, to_o = np.empty(len(dist), dtype=nodes.dtype), np.empty(len(dist))
        for c in range(runs[k], runs[k + 1]):
            b0, b1 = chunk_block[c], chunk_block[c + 1]
            savings_blocks(
                m.seeker_off,
                m.local,
                lam,
                q,
                class_log_q,
                one_minus_q,
                *block_args,
                b0,
                b1,
                parts[k],
                sums.by_seeker,
                log_not_paired,
                loc,
                nodes,
                geometry,
                dist,
                cells,
                todo,
                to_o,
            )
            m.release_seekers(int(blocks.seeker_off[b0]), int(blocks.seeker_off[b1]))

    _in_threads(savings_run, len(runs) - 1)
    for part in parts:
        np.add(sums.by_class, part, out=sums.by_class)
    return sums.by_class[:, 0].copy(), log_not_paired


def _in_threads(task: Callable[[int], None], n: int) -> None:
    """``task(0) .. task(n-1)`` on ``numba.get_num_threads()`` threads (the kernels release the GIL).
    Each task writes its own outputs, so the order they run in does not matter."""
    threads = min(n, get_num_threads())
    if threads <= 1:
        for k in range(n):
            task(k)
        return
    with ThreadPoolExecutor(threads) as pool:
        for _ in pool.map(task, range(n)):  # re-raises a task's exception here
            pass


def _cut(offsets: np.ndarray, parts: int | None = None) -> np.ndarray:
    """Boundaries cutting the groups of CSR ``offsets`` into ``parts`` ranges (default: one per thread) of
    about equal members; a group across a cut point goes to the later range, empty ranges are dropped."""
    parts = max(1, get_num_threads()) if parts is None else parts
    targets = offsets[-1] * np.arange(1, parts) / parts
    inner = np.searchsorted(offsets[1:], targets)
    return np.unique(np.concatenate([[0], inner, [len(offsets) - 1]])).astype(np.int64)


@dataclass(frozen=True, eq=False)
class PairSums:
    """Pair quantities summed with the sweep's weights: columns (1, E, shared, seeker detour).

    ``by_class[c]`` sums ``w``-weighted values over the seekers listing c
    (column 0 is H_c); ``by_seeker[s]`` sums them weighted by the pairing rate
    ``w (1 - Q_c)`` over s's list.
    """

    by_class: np.ndarray  # (classes, 4)
    by_seeker: np.ndarray  # (ODs, 4)

    @classmethod
    def zeros(cls, n_classes: int, n_od: int) -> PairSums:
        return cls(np.zeros((n_classes, 4)), np.zeros((n_od, 4)))


def evaluate(system: System, rho: np.ndarray, sums: PairSums | None = None) -> Evaluation:
    """All variables of (A1)-(A6) from ρ, and the map's output clip(ρ')."""
    sp, cfg = system.space, system.config
    class_log_q = np.empty(sp.n_classes)
    member_log_r = np.empty(sp.n_states)
    # The per-class and per-state passes run in threads too, on ranges of classes / ODs (each writes its own
    # entries, so the values do not depend on the split).
    class_cut = _cut(sp.class_off)
    _in_threads(
        lambda k: class_products(
            rho, sp.class_members, sp.class_off, class_log_q, member_log_r, class_cut[k], class_cut[k + 1]
        ),
        len(class_cut) - 1,
    )
    class_h, log_not_paired = sweep(system, class_log_q, sums)
    p_seeker = -np.expm1(log_not_paired)
    eta, p_taker, log_not_taker, lam_taker, rho_next = (np.empty(sp.n_states) for _ in range(5))
    clipped = np.empty(sp.n_states, dtype=bool)
    od_cut = _cut(sp.od_state_off)
    _in_threads(
        lambda k: taker_map(
            class_h,
            log_not_paired,
            member_log_r,
            sp.cls,
            sp.tau_s,
            sp.od_state_off,
            system.rate_per_s,
            cfg.rho_mode == "poisson",
            cfg.rho_cap,
            eta,
            p_taker,
            log_not_taker,
            lam_taker,
            rho_next,
            clipped,
            od_cut[k],
            od_cut[k + 1],
        ),
        len(od_cut) - 1,
    )
    return Evaluation(
        rho=rho,
        rho_next=rho_next,
        clipped=clipped,
        eta=eta,
        p_taker=p_taker,
        lam_taker=lam_taker,
        log_not_taker=log_not_taker,
        p_seeker=p_seeker,
        class_log_q=class_log_q,
        class_h=class_h,
        member_log_r=member_log_r,
    )


def solve_fixed_point(
    system: System, *, progress: Callable[[int, float], None] | None = None, rho0: np.ndarray | None = None
) -> tuple[Evaluation, SolveInfo]:
    """Damped fixed-point iteration (§2.6) from ρ = 0; returns the final consistent evaluation.

    ``rho0`` warm-starts the iteration (e.g. from the solution at a nearby
    demand level); the stopping rule is unchanged, so the result is the same
    fixed point to within the tolerance whenever that fixed point is unique.

    With ``config.accel == "anderson"`` each damped step is replaced by an
    Anderson-accelerated one (type II, depth ``anderson_depth``, on the same
    damped map; the history restarts whenever the residual grows, so the
    plain damped step is the fallback).  The fixed point, the stopping rule
    and the final re-evaluation are the same; only the number of sweeps changes.
    """
    cfg = system.config
    t0 = time.perf_counter()
    rho = np.zeros(system.space.n_states) if rho0 is None else np.array(rho0, dtype=np.float64)
    if rho.shape != (system.space.n_states,):
        raise ValueError(f"rho0 has shape {rho.shape}, expected ({system.space.n_states},)")
    beta = cfg.beta
    history: list[float] = []
    growing = 0
    converged = False
    accel = AndersonMixing(cfg.anderson_depth) if cfg.accel == "anderson" else None
    for it in range(1, cfg.max_iter + 1):
        ev = evaluate(system, rho)
        res = ev.residual
        history.append(res)
        if progress is not None:
            progress(it, res)
        if res <= cfg.tol:
            converged = True
            break
        grew = len(history) > 1 and res > history[-2]
        growing = growing + 1 if grew else 0
        if growing >= cfg.grow_patience and beta > cfg.beta_floor:
            beta = max(cfg.beta_floor, beta / 2.0)
            growing = 0
        step = beta * (ev.rho_next - rho)
        if accel is not None:
            if grew:
                accel.restart()
            step = accel.step(rho, ev.rho_next - rho, step, beta)
        rho = np.clip(rho + step, 0.0, cfg.rho_cap)
    # The last evaluation already used the final ρ unless the cap was hit with an update after it.
    if not converged:
        ev = evaluate(system, rho)
    info = SolveInfo(
        converged=converged,
        residual=ev.residual,
        iterations=len(history),
        clip_count=ev.clip_count,
        beta=beta,
        time_s=time.perf_counter() - t0,
        history=tuple(history),
    )
    return ev, info
