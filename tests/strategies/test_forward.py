"""FL and FL-no_delay utilities (paper Eqs. 15-17) on hand-made rounds with a stubbed prediction."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from helpers import line_network, round_state

from rpbench.scenarios.base import Params
from rpbench.strategies import Kind, make_strategy
from rpbench.strategies.forward import fraction


class FixedPrediction:
    """ē(p) and ē(0,p) given per origin node (the strategies only call lookup and e_wait)."""

    def __init__(self, e_vacant: dict, e_wait: dict):
        self._ev, self._ew = e_vacant, e_wait

    def lookup(self, o, d):
        return SimpleNamespace(e_vacant=np.array([self._ev.get(int(x), 0.0) for x in o]))

    def e_wait(self, o, d, k_p, params):
        return np.array([self._ew.get(int(x), 0.0) for x in o])


def strategy(name, prediction, mean_pickup_m=900.0):
    s = make_strategy(name)
    s.predictions = [prediction]
    s.mean_pickup_m = np.array([mean_pickup_m])
    return s


def column(rm, kind, first):
    idx = np.flatnonzero((rm.kind == kind) & (rm.first == first))
    assert len(idx) == 1
    return int(idx[0])


def test_fl_utilities_follow_eq_15_16():
    net = line_network(6)
    idx = lambda node: int(net.index_of([node])[0])  # noqa: E731
    state = round_state(
        net,
        [(1, 5), (2, 4)],
        [(0, 100.0)],
        waited=[3, 1],
        occupied=[{"node": 1, "origin": 0, "destination": 5, "delta": 1000.0, "pre": 50.0}],
    )
    pred = FixedPrediction({idx(1): 800.0, idx(2): 0.0}, {idx(1): 400.0, idx(2): 1000.0})
    rm = strategy("fl", pred, mean_pickup_m=700.0).build(state)
    alpha = Params().alpha
    # vacant: ē(p)²/(ē(p)+pk)·α^k, pk = 100 + l(0, 1) = 1100
    c = column(rm, Kind.VACANT, 0)
    assert rm.utility_m[c] == pytest.approx(800**2 / (800 + 1100) * alpha**3)
    # ē(p) = 0 gives 0 (0/0 := 0), never NaN
    assert rm.utility_m[column(rm, Kind.VACANT, 1)] == 0.0
    # joining the vehicle of A (0 -> 5) at node 1: e = l_A + l_B - L > 0, pk = pre + l(1, o_B)
    j = column(rm, Kind.JOIN, 0)
    e = state.v1_solo_m[0] + state.p_solo_m[0] - (1000.0 + 0.0 + 4000.0)  # FOFO: δ + p + l(1,5) + 0
    assert rm.utility_m[j] == pytest.approx(e * e / (e + 50.0) * alpha**3)
    # keep waiting: ē(0,p) - l̄
    assert rm.utility_m[column(rm, Kind.WAIT, 0)] == pytest.approx(400.0 - 700.0)
    assert rm.utility_m[column(rm, Kind.WAIT, 1)] == pytest.approx(1000.0 - 700.0)


def test_fl_no_delay_utilities_follow_eq_17():
    net = line_network(6)
    idx = lambda node: int(net.index_of([node])[0])  # noqa: E731
    state = round_state(net, [(1, 5)], [(0, 0.0)])
    rm = strategy("fl-nd", FixedPrediction({idx(1): 800.0}, {idx(1): 5000.0})).build(state)
    assert rm.utility_m[column(rm, Kind.VACANT, 0)] == pytest.approx(800.0 - 1000.0)
    assert rm.utility_m[column(rm, Kind.WAIT, 0)] == -1e6  # no waiting on purpose (A13)


def test_partially_occupied_options_without_saving_are_dropped():
    # A rides 0 -> 1; B at 2 -> 3 could only be collected after A's drop-off: e <= 0 (A11).
    net = line_network(6)
    state = round_state(net, [(2, 3)], [], occupied=[{"node": 1, "origin": 0, "destination": 1, "delta": 1000.0}])
    for name in ("fl", "fl-nd"):
        rm = strategy(name, FixedPrediction({}, {})).build(state)
        assert not (rm.kind == Kind.JOIN).any()
    assert (make_strategy("mb").build(state).kind == Kind.JOIN).any()  # MB keeps any feasible pair


@pytest.mark.parametrize("e, pk", [(500.0, 300.0), (2000.0, 10.0), (50.0, 2900.0)])
def test_proposition_1_properties(e, pk):
    alpha = Params().alpha
    u = lambda e_, pk_, k: fraction(np.array(e_ * e_), np.array(e_ + pk_)) * alpha**k  # noqa: E731
    # Property 1: same saving and pick-up -> the passenger who waited longer first
    assert u(e, pk, 4) > u(e, pk, 3)
    # Property 2: same rounds and pick-up -> the larger saving first
    assert u(e + 1.0, pk, 2) > u(e, pk, 2)
    # Property 3: after K/Δt rounds ē(0,p) = 0, so waiting (-l̄) loses to any match (utility >= 0)
    assert u(e, pk, 9) > 0.0 - 900.0


def test_fraction_zero_over_zero():
    assert fraction(np.array([0.0, 4.0]), np.array([0.0, 2.0])).tolist() == [0.0, 2.0]


def test_unknown_options_rejected():
    from rpbench.exceptions import ParameterError

    with pytest.raises(ParameterError, match="unknown option"):
        make_strategy("fl", colour="red")
    with pytest.raises(ParameterError, match="option rates = 'weekly' must be one of auto, month, history, scenario"):
        make_strategy("fl", rates="weekly")


@pytest.mark.slow
def test_fl_runs_on_the_toy_city(tmp_path):
    from rpbench.harness.comparison import run_comparison
    from rpbench.scenarios import ScenarioRequest
    from rpbench.spec import RunSpec

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=8), ["mb", "fl-nd", "fl"])
    outcome = run_comparison(spec, tmp_path / "fl", progress=False)
    folder, table = outcome.folder, outcome.table
    import json

    meta = json.loads((folder / "meta.json").read_text())
    # τ_0 and l̄ come from the MB run of the same scenario (A4)
    assert meta["runs"]["fl"]["options"]["mean_pickup_m"] == pytest.approx(table.loc["avg_pickup_distance_m", "mb"])
    assert meta["runs"]["fl"]["options"]["tau0_s"] == pytest.approx(table.loc["avg_pickup_time_s", "mb"])
    from rpbench.check import check_folder

    assert all(rc.ok for rc in check_folder(folder))
