"""Seeker/taker states and taker classes (docs/algorithms.md §2.2, A4, A5)."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.predict.states import build_states

from .conftest import make_instance


@pytest.mark.parametrize("origin_state", [True, False])
def test_states_follow_the_oracle_paths(origin_state):
    inst = make_instance(seed=3, size=5, n_od=10)
    oracle = inst.network.distances()
    sp = build_states(inst.network, oracle, inst.rates, tau0_s=77.0, speed_mps=5.0, include_origin_state=origin_state)
    for w in range(len(inst.rates)):
        o, d = int(inst.rates.origin[w]), int(inst.rates.destination[w])
        nodes = oracle.path_nodes(o, d)
        s = slice(sp.od_state_off[w], sp.od_state_off[w + 1])
        first = 0 if origin_state else 1
        assert sp.k[s].tolist() == list(range(first, len(nodes)))
        assert sp.head[s].tolist() == nodes[first:].tolist()
        lengths = np.concatenate([[0.0], inst.network.arc_length_m[oracle.path_arcs(o, d)]])[first:]
        np.testing.assert_allclose(sp.pre_m[s], lengths / 2)
        expected_tau = np.where(sp.k[s] == 0, 77.0, lengths / 5.0)
        np.testing.assert_allclose(sp.tau_s[s], expected_tau)
        np.testing.assert_allclose(
            sp.delta_m[s],
            np.cumsum(np.concatenate([[0.0], lengths[1:]])) if origin_state else np.cumsum(lengths),
            atol=1e-9,
        )
        assert sp.solo_m[w] == pytest.approx(oracle.dist[o, d])


def test_classes_group_interchangeable_states():
    inst = make_instance(seed=4, size=4, n_od=30)
    sp = build_states(inst.network, inst.network.distances(), inst.rates, tau0_s=120.0, speed_mps=8.0)
    assert np.all(np.diff(sp.class_head) >= 0)  # numbered by head node
    for c in range(sp.n_classes):
        members = sp.class_members[sp.class_off[c] : sp.class_off[c + 1]]
        assert np.all(sp.cls[members] == c)
        assert np.all(sp.head[members] == sp.class_head[c])
        assert np.all(sp.pre_m[members] == sp.class_pre_m[c])
        assert np.all(inst.rates.destination[sp.od[members]] == sp.class_dest[c])
        key = sp.od[members].astype(np.int64) * 1000 + sp.k[members]
        assert np.all(np.diff(key) > 0)  # members in (w, k) order
        # the remaining distance is l_w - δ for every member (δ cancels from the geometry)
        np.testing.assert_allclose(sp.solo_m[sp.od[members]] - sp.delta_m[members], sp.class_rest_m[c], atol=1e-6)
