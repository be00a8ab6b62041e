"""VF (value-function dispatch): MB's weights plus the discounted value change, checked by hand on
line-network rounds; V ≡ 0 is MB exactly; a model is used only on scenarios held out from its training, which
it tells from the online view (what the simulator hands it)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from helpers import line_network, round_state, scenario_of

from rpbench.backends import load_preset
from rpbench.exceptions import ParameterError
from rpbench.harness.training import supply_model, train
from rpbench.scenarios.base import Params
from rpbench.scenarios.registry import build_scenario
from rpbench.sim.simulator import Simulator
from rpbench.strategies import Kind, make_strategy
from rpbench.strategies.myopic import MyopicBatch
from rpbench.strategies.value import VALUE_MODEL, ValueFunction, ValueOptions
from rpbench.valuefn.cells import Grid
from rpbench.valuefn.model import ValueModel, save_model
from rpbench.valuefn.training import CACHE_FOLDER, Settings, training_scenarios

SAMPLE = 0.4
NET = line_network(6)  # nodes 0-5, 1000 m apart
SPEED = 10.0
#: V(node, bin) = 100·node + 1000·bin + 7 on the line (node i is cell i), bins of 600 s, γ = 0.9 per bin.
LINE_MODEL = ValueModel(
    values=100.0 * np.arange(6)[:, None] + 1000.0 * np.arange(2)[None, :] + 7.0,
    visits=np.ones((6, 2), dtype=np.int64),
    node_cell=np.arange(6),
    cell_m=1000.0,
    bin_s=600.0,
    discount=0.9,
    network=NET.content_hash,
)


def v(node: int, bin_: int) -> float:
    return 100.0 * node + 1000.0 * bin_ + 7.0


def column(rm, kind) -> int:
    (idx,) = np.flatnonzero(rm.kind == kind)
    return int(idx)


def test_vacant_and_folo_join_utilities_follow_the_value_change():
    """t = 300 s; p: 2 -> 4 (2000 m).  Vacant vehicle 100 m before node 0: pk = 2100, it delivers p alone in
    (2100 + 2000) / 10 = 410 s, at node 4 in bin 1.  A (0 -> 5) rides a vehicle 50 m before node 1 after
    δ = 1000 m: FOLO 0-2-4-5, L = 5000, e = 5000 + 2000 - 5000, pk = 1050, still 50 + 5000 - 1000 m to
    drive (405 s) to A's drop-off at node 5, in bin 1."""
    state = round_state(
        NET,
        [(2, 4)],
        [(0, 100.0)],
        params=Params(speed_mps=SPEED),
        t=300.0,
        occupied=[{"node": 1, "origin": 0, "destination": 5, "delta": 1000.0, "pre": 50.0}],
    )
    rm = ValueFunction.with_model(LINE_MODEL).build(state)
    vac, join = column(rm, Kind.VACANT), column(rm, Kind.JOIN)
    assert not rm.fofo[join]
    assert rm.utility_m[vac] == pytest.approx(-2100.0 + 0.9 ** (410 / 600) * v(4, 1) - v(0, 0), rel=1e-12)
    assert rm.utility_m[join] == pytest.approx(2000.0 - 1050.0 + 0.9 ** (405 / 600) * v(5, 1) - v(1, 0), rel=1e-12)
    assert rm.utility_m[column(rm, Kind.WAIT)] == -1e6
    # the value change is weighted by value_weight; 0 gives MB's utilities
    twice = ValueFunction.with_model(LINE_MODEL, value_weight=2.0).build(state)
    assert twice.utility_m[vac] == pytest.approx(-2100.0 + 2 * (0.9 ** (410 / 600) * v(4, 1) - v(0, 0)), rel=1e-12)
    mb = MyopicBatch().build(state)
    assert (
        ValueFunction.with_model(LINE_MODEL, value_weight=0.0).build(state).utility_m.tolist() == mb.utility_m.tolist()
    )
    assert mb.utility_m[vac] == -2100.0 and mb.utility_m[join] == 2000.0 - 1050.0


def test_a_fofo_join_is_valued_at_the_new_passengers_drop_off():
    """A (0 -> 3) at node 1 after δ = 1000 m; p: 2 -> 5.  FOLO would detour A by 4000 m > D̄: FOFO 0-1-2-3-5,
    L = 5000, e = 3000 + 3000 - 5000, pk = 1000; 4000 m (400 s) to p's drop-off at node 5, still bin 0."""
    state = round_state(
        NET,
        [(2, 5)],
        [],
        params=Params(speed_mps=SPEED),
        t=0.0,
        occupied=[{"node": 1, "origin": 0, "destination": 3, "delta": 1000.0, "pre": 0.0}],
    )
    rm = ValueFunction.with_model(LINE_MODEL).build(state)
    join = column(rm, Kind.JOIN)
    assert rm.fofo[join]
    assert rm.utility_m[join] == pytest.approx(1000.0 - 1000.0 + 0.9 ** (400 / 600) * v(5, 0) - v(1, 0), rel=1e-12)


@pytest.fixture(scope="module")
def toy():
    return build_scenario("toy", sample=SAMPLE, seed=0)


@pytest.fixture(scope="module")
def models(toy, tmp_path_factory):
    """Model folders trained on seed 1 (held out from the test seed 0) and on seed 0 (not held out)."""
    root = tmp_path_factory.mktemp("models")
    out = {}
    for seed in (1, 0):
        model = train(training_scenarios(toy, "", (seed,)), Settings())
        out[seed] = (model, save_model(model, root / f"seed{seed}"), root / f"seed{seed}")
    return out


def test_a_zero_value_reproduces_mbs_event_log_and_a_learned_one_changes_it(toy, models):
    """With V ≡ 0 every weight is MB's: the same run, event for event (utilities included).  The model
    learned on seed 1 makes other decisions on seed 0."""
    grid = Grid.of(toy.network, 1000.0, 600.0, toy.horizon_s)
    zero = ValueModel(
        values=np.zeros((grid.n_cells, grid.n_bins)),
        visits=np.zeros((grid.n_cells, grid.n_bins), dtype=np.int64),
        node_cell=grid.node_cell,
        cell_m=grid.cell_m,
        bin_s=grid.bin_s,
        discount=0.9,
        network=toy.network.content_hash,
    )
    preset = load_preset("highs")
    mb = Simulator(toy, MyopicBatch(), preset).run()
    vf0 = Simulator(toy, ValueFunction.with_model(zero), preset).run()
    pd.testing.assert_frame_equal(mb.events, vf0.events)
    assert len(mb.events) > 300
    learned = Simulator(toy, ValueFunction.with_model(models[1][0]), preset).run()
    assert not mb.events.equals(learned.events)
    assigned = lambda events: events[events["event"] == "assign"][["order", "vehicle"]]  # noqa: E731
    assert not assigned(mb.events).reset_index(drop=True).equals(assigned(learned.events).reset_index(drop=True))
    assert vf0.artefacts == {} and learned.artefacts == {}  # a model given as it is has no folder to copy


def test_a_model_folder_loads_and_is_named_as_the_runs_artefact(toy, models):
    model, digest, folder = models[1]
    vf = ValueFunction(model=str(folder))
    vf.prepare(toy.online_view())
    assert vf.model_digest == digest and np.array_equal(vf.model.values, model.values)
    assert vf.artefacts() == {VALUE_MODEL: (digest, folder)}


def test_a_model_trained_on_the_test_seed_is_refused(toy, models):
    _, _, folder = models[0]
    with pytest.raises(ParameterError, match=r"trained on this scenario \(seed 0 is one of its training seeds\)"):
        ValueFunction(model=str(folder)).prepare(toy.online_view())
    # another sample of seed 0 is another draw: held out
    ValueFunction(model=str(folder)).prepare(build_scenario("toy", sample=0.2, seed=0).online_view())


def test_auto_refuses_the_test_seed_before_training(toy, tmp_path, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    with pytest.raises(ParameterError, match=r"seed 0 is one of its training seeds") as info:
        supply_model(ValueFunction(train_seeds=(3, 0)), toy)
    assert "\n" not in str(info.value)
    assert not (tmp_path / "cache" / CACHE_FOLDER).exists()  # refused before any training


def test_auto_trains_once_into_the_cache(toy, tmp_path, monkeypatch, models):
    """model=auto trains on train_seeds (the same model as train() gives) and a second run loads it."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    first = ValueFunction(train_seeds=(1,))
    supply_model(first, toy)
    (name,) = [p.name for p in (tmp_path / "cache" / CACHE_FOLDER).iterdir()]
    assert first.model_folder == tmp_path / "cache" / CACHE_FOLDER / name
    assert first.model_digest == models[1][1]  # the same training as the seed-1 folder, the same bytes
    second = ValueFunction(train_seeds=(1,))
    supply_model(second, toy)
    assert second.artefacts() == first.artefacts() == {VALUE_MODEL: (models[1][1], first.model_folder)}


def test_a_dated_scenarios_day_must_be_held_out(two_day_data, tmp_path, monkeypatch):
    """The default training days (2017-05-01..07) include 2017-05-01: refused; trained on 05-01, 05-02 runs."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    day1 = build_scenario("haikou-peak", data_dir=two_day_data, date="2017-05-01", sample=1.0)
    with pytest.raises(ParameterError, match="2017-05-01 is one of its training days"):
        supply_model(ValueFunction(), day1)
    day2 = build_scenario("haikou-peak", data_dir=two_day_data, date="2017-05-02", sample=1.0)
    vf = ValueFunction(train_dates="2017-05-01")
    supply_model(vf, day2)
    assert [r["date"] for r in vf.model.training["runs"]] == ["2017-05-01"]


def test_an_auto_model_is_the_harness_s_to_train(toy):
    """Outside the harness, model=auto has no model to dispatch with: one line saying where one comes from."""
    with pytest.raises(ParameterError, match=r"model=auto is trained by the harness before the run") as info:
        ValueFunction().prepare(toy.online_view())
    assert "\n" not in str(info.value)


def test_a_model_of_another_network_is_refused(models):
    line = scenario_of(NET, [(0.0, 0, 3)], [1])
    with pytest.raises(ParameterError, match="vf: the value model was learned on another road network"):
        ValueFunction(model=str(models[1][2])).prepare(line.online_view())


def test_vf_is_registered_and_its_options_are_the_training_settings():
    vf = make_strategy("vf", cell_m="500", discount="0.8", method="td", epochs="3", iterations="2")
    assert isinstance(vf, ValueFunction) and vf.label == "VF"
    assert vf.options.settings() == Settings(
        cell_m=500.0, bin_s=600.0, discount=0.8, method="td", epochs=3, iterations=2, order_rule="min_feasible"
    )
    assert ValueOptions().model == "auto" and ValueOptions().train_seeds == (100,)
    with pytest.raises(ParameterError, match="option discount = 0.0 is out of range"):
        make_strategy("vf", discount="0")
    with pytest.raises(ParameterError, match="option method = 'mc' must be one of exact, td"):
        make_strategy("vf", method="mc")
