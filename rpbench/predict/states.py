"""Seeker and taker states (docs/algorithms.md §2.2, A4, A5).

Every OD ``w`` has one seeker state ``s(w)`` (instantaneous, at the origin)
and taker states ``t(k, w)``:

* ``k = 0``, the origin/pick-up state: ``h = o_w``, ``δ = 0``, ``pre = 0``,
  sojourn ``τ_0`` (a configuration value, A4);
* ``k >= 1``, one per link ``a_k`` of the shortest path ``P_w`` the simulator
  drives (the distance oracle's predecessor path): ``h`` = head node of
  ``a_k``, ``δ`` = path length from ``o_w`` to ``h``, ``pre = len(a_k)/2``,
  ``τ_k = len(a_k)/v``.

**Taker classes.**  The pair geometry of §1.1 depends on the taker only
through ``(h, pre, d_w)`` and ``l(h, d_w) = l_w - δ`` (``h`` lies on a shortest
path to ``d_w``, so ``δ`` cancels from every detour and from the saving).
States that share the entry (the link ``a_k``, or the origin node for
``k = 0``) and the destination are therefore interchangeable for every
seeker; they form a *class*.  The matching sets are built and stored per
class, which is exact and cuts the work about threefold on Haikou.  Within a
class, members are ordered by ``(w, k)``, the spec's tie-break (§2.4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.network import Distances, RoadNetwork
from rpbench.predict.rates import OdRates


@dataclass(frozen=True, eq=False)
class StateSpace:
    """Taker states (flat arrays, grouped by OD in ``(w, k)`` order) and their classes."""

    od_state_off: np.ndarray  # int64 (W+1): states of OD w are [off[w], off[w+1])
    solo_m: np.ndarray  # float64 (W,): l_w
    od: np.ndarray  # int32 per state
    k: np.ndarray  # int32 per state (0 = origin state)
    head: np.ndarray  # int32 node h
    arc: np.ndarray  # int32 arc index of a_k (-1 for k = 0)
    pre_m: np.ndarray  # float64 expected residual distance to h
    tau_s: np.ndarray  # float64 sojourn τ
    delta_m: np.ndarray  # float64 path length o_w -> h
    cls: np.ndarray  # int32 class of each state
    class_head: np.ndarray  # int32 (C,)
    class_dest: np.ndarray  # int32 (C,)
    class_pre_m: np.ndarray  # float64 (C,)
    class_rest_m: np.ndarray  # float64 (C,): l(h, d)
    class_members: np.ndarray  # int64 state indices sorted by (class, w, k); classes sorted by head node
    class_off: np.ndarray  # int64 (C+1)

    @property
    def n_od(self) -> int:
        return len(self.solo_m)

    @property
    def n_states(self) -> int:
        return len(self.od)

    @property
    def n_classes(self) -> int:
        return len(self.class_head)

    @property
    def class_size(self) -> np.ndarray:
        return np.diff(self.class_off)

    def problem(self, n_od: int, n_nodes: int, n_arcs: int) -> str | None:
        """What makes states read from disk unsafe to sweep (None when every index is in range).

        Vectorised checks of every index the compiled kernels follow without
        bounds checks: array types and lengths, offsets monotone from 0 to the
        array they cut, state, class, node and arc numbers in range.
        """
        n, c = self.n_states, self.n_classes
        per_state = ("od", "k", "head", "arc", "pre_m", "tau_s", "delta_m", "cls", "class_members")
        per_class = ("class_head", "class_dest", "class_pre_m", "class_rest_m")
        lengths = {"od_state_off": n_od + 1, "solo_m": n_od, "class_off": c + 1}
        lengths.update({name: n for name in per_state} | {name: c for name in per_class})
        for name, length in lengths.items():
            a = getattr(self, name)
            if a.ndim != 1 or len(a) != length:
                return f"{name} has shape {a.shape}, expected ({length},)"
        for name in ("od", "k", "head", "arc", "cls", "class_head", "class_dest", "class_members"):
            if getattr(self, name).dtype.kind != "i":
                return f"{name} is of type {getattr(self, name).dtype}, expected integers"
        for name, total in (("od_state_off", n), ("class_off", n)):
            off = getattr(self, name)
            if off.dtype != np.int64 or off[0] != 0 or off[-1] != total or np.any(np.diff(off) < 0):
                return f"{name} is not monotone from 0 to {total}"
        ranges = {
            "od": (0, n_od),
            "k": (0, None),
            "head": (0, n_nodes),
            "arc": (-1, n_arcs),
            "cls": (0, c),
            "class_head": (0, n_nodes),
            "class_dest": (0, n_nodes),
            "class_members": (0, n),
        }
        for name, (lo, hi) in ranges.items():
            a = getattr(self, name)
            if len(a) and (a.min() < lo or (hi is not None and a.max() >= hi)):
                return f"{name} holds values outside [{lo}, {hi if hi is not None else 'inf'})"
        return None


def build_states(
    network: RoadNetwork,
    oracle: Distances,
    rates: OdRates,
    *,
    tau0_s: float,
    speed_mps: float,
    include_origin_state: bool = True,
) -> StateSpace:
    """Enumerate the taker states of every OD along the oracle's shortest paths."""
    if not speed_mps > 0:
        raise ParameterError(f"speed_mps = {speed_mps!r} must be > 0")
    dist = oracle.dist
    o = rates.origin.astype(np.int64)
    d = rates.destination.astype(np.int64)
    path_off, path_nodes = oracle.paths_batch(o, d)
    n_links = np.diff(path_off) - 1
    first_k = 0 if include_origin_state else 1
    count = n_links + 1 - first_k
    od_state_off = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    od = np.repeat(np.arange(len(o), dtype=np.int32), count)
    k = (np.arange(od_state_off[-1]) - np.repeat(od_state_off[:-1], count) + first_k).astype(np.int32)
    pos = path_off[:-1][od] + k
    head = path_nodes[pos].astype(np.int32)
    link = k > 0
    arc = np.full(len(od), -1, dtype=np.int32)
    arc[link] = network.arc_index(path_nodes[pos[link] - 1], head[link])
    if np.any(arc[link] < 0):
        raise ParameterError("a shortest path uses a node pair that is not an arc of the network")
    length = np.zeros(len(od))
    length[link] = network.arc_length_m[arc[link]]
    tau = np.where(link, length / speed_mps, float(tau0_s))
    delta = np.asarray(dist[o[od], head], dtype=np.float64)  # prefix of a shortest path = l(o_w, h)

    # Classes: (head, entry, destination) with entry = arc for k >= 1, n_arcs + origin node for k = 0.
    # Numbering them by head node first lets the matching gather a head's classes as one range.
    n_entries = network.n_arcs + network.n_nodes
    entry = np.where(link, arc.astype(np.int64), network.n_arcs + head.astype(np.int64))
    key = (head.astype(np.int64) * n_entries + entry) * network.n_nodes + d[od]
    _, cls = np.unique(key, return_inverse=True)
    cls = cls.astype(np.int32).ravel()
    members = np.argsort(cls, kind="stable").astype(np.int64)  # (class, w, k) order
    n_classes = int(cls.max()) + 1 if len(cls) else 0
    class_off = np.concatenate([[0], np.cumsum(np.bincount(cls, minlength=n_classes))]).astype(np.int64)
    rep = members[class_off[:-1]]
    class_head = head[rep]
    class_dest = d[od[rep]].astype(np.int32)
    return StateSpace(
        od_state_off=od_state_off,
        solo_m=np.asarray(dist[o, d], dtype=np.float64),
        od=od,
        k=k,
        head=head,
        arc=arc,
        pre_m=length / 2.0,
        tau_s=tau,
        delta_m=delta,
        cls=cls,
        class_head=class_head,
        class_dest=class_dest,
        class_pre_m=length[rep] / 2.0,
        class_rest_m=np.asarray(dist[class_head, class_dest], dtype=np.float64),
        class_members=members,
        class_off=class_off,
    )
