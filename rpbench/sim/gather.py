"""The round state's per-passenger and per-vehicle arrays, gathered by compiled kernels (numba).

A round reads a dozen fields of the waiting passengers and of the partly occupied vehicles' riders
from the simulator's order arrays; as numpy gathers and ``where`` passes that was some forty calls a
round, each costing more than its work.  These kernels compute the same numbers with the same
floating-point operations (:meth:`Simulator._round_state` documents what each field is).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def fleet_split(load: np.ndarray, paired: np.ndarray, on_duty: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The on-duty vacant vehicles (V0) and those with one unpaired passenger (V1), each in id order."""
    n0 = n1 = 0
    for v in range(len(load)):
        if on_duty[v]:
            if load[v] == 0:
                n0 += 1
            elif load[v] == 1 and not paired[v]:
                n1 += 1
    v0, v1 = np.empty(n0, np.int64), np.empty(n1, np.int64)
    n0 = n1 = 0
    for v in range(len(load)):
        if on_duty[v]:
            if load[v] == 0:
                v0[n0] = v
                n0 += 1
            elif load[v] == 1 and not paired[v]:
                v1[n1] = v
                n1 += 1
    return v0, v1


@njit(cache=True, nogil=True)
def passengers(
    p: np.ndarray,
    origin: np.ndarray,
    destination: np.ndarray,
    solo: np.ndarray,
    request: np.ndarray,
    t: float,
    dt: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per waiting passenger: origin, destination, solo distance, request time and rounds waited
    ``max(1, ceil((t - t_request) / Δt - 1e-9))`` (A10)."""
    n = len(p)
    o, d, s, r = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n), np.empty(n)
    waited = np.empty(n, np.int64)
    for i in range(n):
        q = p[i]
        o[i], d[i], s[i], r[i] = origin[q], destination[q], solo[q], request[q]
        waited[i] = np.int64(max(1.0, np.ceil((t - request[q]) / dt - 1e-9)))
    return o, d, s, r, waited


@njit(cache=True, nogil=True)
def riders(
    v1_order: np.ndarray,
    state: np.ndarray,
    onboard_state: int,
    origin: np.ndarray,
    destination: np.ndarray,
    solo: np.ndarray,
    pickup_odo: np.ndarray,
    node_next: np.ndarray,
    pre_next: np.ndarray,
    odo_next: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per V1 vehicle from its rider A: h, δ, pre (A's origin, 0, 0 until A is picked up, A14), whether A is
    on board, and A's origin, destination and solo distance."""
    n = len(v1_order)
    node, delta, pre = np.empty(n, np.int64), np.zeros(n), np.zeros(n)
    onboard = np.empty(n, np.bool_)
    o, d, s = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    for i in range(n):
        a = v1_order[i]
        onboard[i] = state[a] == onboard_state
        o[i], d[i], s[i] = origin[a], destination[a], solo[a]
        if onboard[i]:
            node[i], pre[i], delta[i] = node_next[i], pre_next[i], odo_next[i] - pickup_odo[a]
        else:
            node[i] = origin[a]
    return node, delta, pre, onboard, o, d, s


def load_gather_kernels() -> None:
    """Load (or compile) the kernels now: the first call of each costs a one-off load of its machine code."""
    i, f = np.zeros(1, np.int64), np.zeros(1)
    fleet_split(i, np.zeros(1, np.bool_), np.zeros(1, np.bool_))
    passengers(i, i, i, f, f, 0.0, 1.0)
    riders(i, np.zeros(1, np.int8), 3, i, i, f, f, i, f, f)
