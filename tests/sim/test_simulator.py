"""The simulator on hand-built scenarios with hand-computed outcomes, and determinism."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import line_network, network_from_edges, scenario_of

from rpbench.backends.presets import load_preset
from rpbench.harness.comparison import simulate_strategy
from rpbench.model import Structure, TripPackingModel
from rpbench.results.metrics import TIMING_KPIS
from rpbench.sim.simulator import Simulator
from rpbench.strategies.base import RoundModel, Strategy


@pytest.fixture(scope="module")
def preset():
    return load_preset("highs")


def passengers(run) -> pd.DataFrame:
    return run.passengers


def test_pooled_pair_fofo(preset):
    # A rides 0 -> 3 from t = 0; B requests 1 -> 5 at t = 10 while A is on board between 0 and 1.
    sc = scenario_of(line_network(6), [(0.0, 0, 3), (10.0, 1, 5)], vehicles=[0])
    run = simulate_strategy(sc, "mb", preset, progress=False)
    tab = passengers(run)
    assert tab["pooled"].all()
    # FOFO: L = δ + p + l(1,3) + l(3,5) = 1000 + 0 + 2000 + 2000; e = 3000 + 4000 - 5000
    assert run.kpis["total_saving_km"] == pytest.approx(2.0)
    assert tab["detour_m"].to_numpy() == pytest.approx([0.0, 0.0], abs=1e-6)
    assert tab["shared_m"].to_numpy() == pytest.approx([2000.0, 2000.0])
    assert tab["dropoff_s"][0] < tab["dropoff_s"][1]  # A dropped first
    join = run.sim.events.query("event == 'assign' and order == 1").iloc[0]
    assert join["kind"] == "join" and bool(join["fofo"])


def test_pooled_pair_folo(preset):
    # A rides 0 -> 5; B joins 1 -> 3: FOFO would detour B by 4000 m > D̄, FOLO costs nobody anything.
    sc = scenario_of(line_network(6), [(0.0, 0, 5), (10.0, 1, 3)], vehicles=[0])
    run = simulate_strategy(sc, "mb", preset, progress=False)
    tab = passengers(run)
    assert tab["pooled"].all()
    assert run.kpis["total_saving_km"] == pytest.approx(2.0)
    assert tab["dropoff_s"][1] < tab["dropoff_s"][0]  # B dropped first (A last)
    assert not bool(run.sim.events.query("event == 'assign' and order == 1").iloc[0]["fofo"])


@pytest.mark.parametrize("spur, pooled", [(1499.5, True), (1500.5, False)])
def test_detour_threshold(preset, spur, pooled):
    # A rides 0 -> 3 along a line; B starts at node 9, a spur of length x off node 1, heading to 3.
    # Either service order detours A by 2x: accepted at 2999 m, rejected at 3001 m (D̄ = 3000 m).
    net = network_from_edges([(0, 1, 1000.0), (1, 2, 1000.0), (2, 3, 1000.0), (1, 9, spur)])
    sc = scenario_of(net, [(0.0, 0, 3), (10.0, 9, 3)], vehicles=[0, 0])
    run = simulate_strategy(sc, "mb", preset, progress=False)
    tab = passengers(run)
    assert bool(tab["pooled"].all()) is pooled
    assert tab["served"].all()  # the second vehicle serves B alone otherwise
    if pooled:
        assert tab["detour_m"][0] == pytest.approx(2 * spur)


def test_cancel_at_patience_expiry(preset):
    # The only vehicle is 5 km away (> R̄): the passenger can never be served.
    sc = scenario_of(line_network(8), [(3.0, 7, 6)], vehicles=[0], patience_s=47.5)
    run = simulate_strategy(sc, "mb", preset, progress=False)
    ev = run.sim.events
    cancel = ev[ev["event"] == "cancel"]
    assert len(cancel) == 1 and cancel["t_s"].iloc[0] == pytest.approx(3.0 + 47.5)
    assert run.kpis["response_rate"] == 0.0 and run.kpis["cancelled"] == 1


def test_join_while_driving_to_the_first_passenger(preset):
    # The vehicle starts 2 km before A's origin; B appears at A's origin while it is still on its way (A14).
    sc = scenario_of(line_network(6), [(0.0, 2, 4), (20.0, 2, 5)], vehicles=[0])
    run = simulate_strategy(sc, "mb", preset, progress=False)
    tab = passengers(run)
    ev = run.sim.events
    join = ev.query("event == 'assign' and order == 1").iloc[0]
    assert join["kind"] == "join" and join["t_s"] == 20.0
    assert ev.query("event == 'pickup' and order == 0")["t_s"].iloc[0] == pytest.approx(2000 / (30 / 3.6))
    assert tab["pickup_s"][0] == pytest.approx(tab["pickup_s"][1])  # both collected at o_A
    assert tab["pooled"].all() and tab["pickup_m"][1] == pytest.approx(0.0)


def test_same_seed_same_kpis(preset):
    from rpbench.scenarios import build_scenario

    a = simulate_strategy(build_scenario("toy", sample=0.25, seed=5), "mb", preset, progress=False)
    b = simulate_strategy(build_scenario("toy", sample=0.25, seed=5), "mb", preset, progress=False)
    ka = {k: v for k, v in a.kpis.items() if k not in TIMING_KPIS}
    kb = {k: v for k, v in b.kpis.items() if k not in TIMING_KPIS}
    assert pd.Series(ka).equals(pd.Series(kb))
    pd.testing.assert_frame_equal(a.sim.events, b.sim.events)


def test_vehicles_respect_capacity_and_thresholds(preset):
    from rpbench.scenarios import build_scenario

    sc = build_scenario("toy", sample=0.5, seed=2)
    for name in ("mb", "rtv"):
        tab = simulate_strategy(sc, name, preset, progress=False).passengers
        served = tab[tab["served"]]
        assert (served["pickup_m"] <= sc.params.max_pickup_m + 1e-6).all()
        assert (served["detour_m"] <= sc.params.max_detour_m + 1e-6).all()
        assert (served[~served["pooled"]]["detour_m"].abs() < 1e-6).all()
        assert np.isin(served["partner"][served["pooled"]], served.index).all()


def test_a_solver_failure_names_the_round_and_saves_its_model(monkeypatch, tmp_path):
    from rpbench.backends.highs import HighsBackend
    from rpbench.exceptions import SolverError
    from rpbench.model.instances import load_instance

    def broken(self, model, options, **kw):
        raise SolverError("HiGHS failed with model status kUnknown")

    monkeypatch.setattr(HighsBackend, "solve", broken)
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path))  # dumps go to <cache>/failed-rounds, never /tmp
    sc = scenario_of(line_network(6), [(0.0, 0, 3), (10.0, 1, 5)], vehicles=[0])
    with pytest.raises(SolverError, match=r"mb round 0 \(t=0 s\): solver preset 'highs': HiGHS failed .*rpbench bench"):
        simulate_strategy(sc, "mb", load_preset("highs"), progress=False)
    [dump] = (tmp_path / "failed-rounds").glob("mb-round00000-*.npz")
    model, meta = load_instance(dump)
    assert model.n_passengers == 1 and meta["strategy"] == "mb" and meta["round"] == 0


class _Mover(Strategy):
    """Keeps everyone waiting and sends every vacant vehicle to node 0, in every round (``idle``: also in rounds
    where nobody waits)."""

    name = "mover"
    label = "Mover"
    structure = Structure.TRIP_PACKING

    def __init__(self, idle: bool):
        super().__init__()
        self.idle = idle
        self.calls: list[tuple[str, float]] = []

    def build(self, state):
        empty = np.zeros(0, np.int64)
        model = TripPackingModel(state.n_passengers, state.n_v0 + state.n_v1, empty, empty, empty, np.zeros(0))
        return RoundModel(
            model, empty.astype(np.int8), empty, empty, empty, empty.astype(bool), np.zeros(0), np.zeros(0)
        )

    def reposition(self, state, rm, chosen):
        self.calls.append(("reposition", state.t_s))
        return state.v0_vehicle, np.zeros(state.n_v0, np.int64)

    def idle_moves(self, state):
        self.calls.append(("idle", state.t_s))
        return state.v0_vehicle, np.zeros(state.n_v0, np.int64)


class _WaitingMover(_Mover):
    idle_moves = Strategy.idle_moves  # does not move idle vehicles where nobody waits


def test_vehicles_are_moved_in_rounds_without_columns_and_where_nobody_waits():
    """A round whose model has no column still repositions; a strategy that overrides ``idle_moves`` is asked
    in the rounds where nobody waits too, and only such a strategy."""
    sc = scenario_of(line_network(6, 1000.0), [(50.0, 5, 4)], [3], patience_s=20.0)
    mover = _Mover(idle=True)
    res = Simulator(sc, mover, load_preset("highs")).run()
    kinds = {kind for kind, _ in mover.calls}
    assert kinds == {"reposition", "idle"}
    assert [t for kind, t in mover.calls if kind == "reposition"] == [50.0, 60.0, 70.0]
    assert (res.events["event"] == "reposition").sum() == len(mover.calls)
    waiting = _WaitingMover(idle=False)
    Simulator(sc, waiting, load_preset("highs")).run()
    assert {kind for kind, _ in waiting.calls} == {"reposition"}


def test_the_event_table_is_the_rows_sorted_stably_by_time_order_and_event():
    from rpbench.sim.simulator import EVENT_COLUMNS, EVENT_DTYPES

    sim = Simulator(scenario_of(line_network(6), [(0.0, 0, 5), (0.0, 1, 5), (3.0, 2, 4)], [0, 1]), None, None)  # type: ignore[arg-type]
    rng = np.random.default_rng(0)
    names = ["request", "assign", "pickup", "dropoff", "cancel", "reposition"]
    for _ in range(300):  # many ties in time and order, so the stable order and the event name decide
        t, o = float(rng.integers(0, 5)), int(rng.integers(-1, 4))
        vehicle, node, partner = (int(x) for x in rng.integers(-1, 4, 3))
        event = names[int(rng.integers(0, 6))]
        sim._event(t, event, o, vehicle, node, "vacant", rng.random(), rng.random(), partner, rng.random() < 0.5)
    want = (
        pd.DataFrame(sim.events, columns=EVENT_COLUMNS)
        .astype(EVENT_DTYPES)
        .sort_values(["t_s", "order", "event"], kind="stable")
        .reset_index(drop=True)
    )
    pd.testing.assert_frame_equal(sim._event_table(), want, check_exact=True)
