"""Policy evaluation: the value V of each state under the policy that generated the transitions.

Two methods, the same Bellman equation of the observed transitions (docs/value-function.md §2):

* ``exact`` (default) — the certainty-equivalence solution, which batch TD(0) converges to
  (Sutton 1988): with ``n_s`` transitions leaving state s,
  ``V(s) = (1/n_s) Σ_{s->s'} [r + γ_{ss'} V(s')]``, one sparse linear system ``(I - P) V = r̄``.
  ``P``'s rows sum to less than 1 (every transition lasts at least one batch interval, so γ_{ss'} < 1),
  so the system has exactly one solution.  Deterministic, no step size.
* ``td`` — online TD(0) as Xu et al.: ``V(s) += α [r + γ V(s') - V(s)]`` over the transitions in time
  order, ``epochs`` passes from V = 0.

States no transition leaves are not part of the equation; :func:`evaluate_policy` gives them the mean
value of the visited states of their time bin (weighted by visits), so a dispatcher looking one up
reads a typical value of that time, not 0.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit
from scipy.sparse.linalg import spsolve

from rpbench.valuefn.cells import Grid
from rpbench.valuefn.transitions import Transitions

LEARN_METHODS = ("exact", "td")


def evaluate_policy(
    tr: Transitions, grid: Grid, *, method: str = "exact", learning_rate: float = 0.05, epochs: int = 20
) -> tuple[np.ndarray, np.ndarray]:
    """``(values, visits)``, both of shape ``(n_cells, n_bins)``: V of every state and how many transitions
    leave it (unvisited states hold their bin's visit-weighted mean value)."""
    if method not in LEARN_METHODS:
        raise ValueError(f"method {method!r} unknown; expected one of {', '.join(LEARN_METHODS)}")
    n = grid.n_states
    visits = np.bincount(tr.state, minlength=n).astype(np.int64)
    if method == "exact":
        values = exact_values(tr, n, visits)
    else:
        order = np.lexsort((tr.state, tr.t_s))
        values = np.zeros(n)
        _td0(values, tr.state[order], tr.next_state[order], tr.reward_m[order], tr.gamma[order], learning_rate, epochs)
    values, visits = values.reshape(grid.n_cells, grid.n_bins), visits.reshape(grid.n_cells, grid.n_bins)
    return fill_unvisited(values, visits), visits


def exact_values(tr: Transitions, n_states: int, visits: np.ndarray) -> np.ndarray:
    """The solution of ``V = r̄ + P V`` over the visited states (0 elsewhere)."""
    seen = np.flatnonzero(visits)
    index = np.full(n_states, -1, np.int64)
    index[seen] = np.arange(len(seen))
    m = len(seen)
    if m == 0:
        return np.zeros(n_states)
    weight = 1.0 / visits[tr.state]
    r_bar = np.bincount(index[tr.state], weights=tr.reward_m * weight, minlength=m)
    go = tr.next_state >= 0  # every next state is a later observation, hence itself visited
    p = sp.csr_matrix(
        ((tr.gamma * weight)[go], (index[tr.state[go]], index[tr.next_state[go]])), shape=(m, m)
    )  # duplicates are summed
    solved = spsolve((sp.identity(m, format="csc") - p).tocsc(), r_bar)
    out = np.zeros(n_states)
    out[seen] = np.atleast_1d(solved)
    return out


@njit(cache=True)
def _td0(values, state, next_state, reward, gamma, alpha, epochs):  # pragma: no cover - compiled
    for _ in range(epochs):
        for i in range(len(state)):
            target = reward[i]
            if next_state[i] >= 0:
                target += gamma[i] * values[next_state[i]]
            values[state[i]] += alpha * (target - values[state[i]])


def fill_unvisited(values: np.ndarray, visits: np.ndarray) -> np.ndarray:
    """``values`` with each unvisited state set to its time bin's visit-weighted mean (0 for an empty bin)."""
    total = visits.sum(axis=0)
    mean = np.divide((values * visits).sum(axis=0), total, out=np.zeros(values.shape[1]), where=total > 0)
    return np.where(visits > 0, values, mean[None, :])
