"""Training a value model on the toy city: reproducible to the byte, held out from its test scenario,
cached by the content of what it was trained on, and simulated without changing the policy's decisions."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest

from rpbench.backends import load_preset
from rpbench.exceptions import ParameterError
from rpbench.harness import training
from rpbench.harness.training import cached_model, recording, train
from rpbench.scenarios.registry import build_scenario
from rpbench.sim.simulator import Simulator
from rpbench.strategies.myopic import MyopicBatch
from rpbench.strategies.value import ValueFunction
from rpbench.valuefn.model import MODEL_JSON, load_model, save_model
from rpbench.valuefn.training import (
    CACHE_FOLDER,
    Settings,
    check_held_out,
    held_out_problem,
    training_key,
    training_record,
    training_scenarios,
)

SAMPLE = 0.3


@pytest.fixture(scope="module")
def toy():
    return build_scenario("toy", sample=SAMPLE, seed=0)


def files_of(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_the_same_training_gives_the_same_bytes_and_another_seed_another_digest(toy, tmp_path):
    """Two trainings on seed 1 write identical folders, file for file; seed 2 gives another model."""
    runs = training_scenarios(toy, "", (1,))
    digest_a = save_model(train(runs, Settings()), tmp_path / "a")
    digest_b = save_model(train(training_scenarios(toy, "", (1,)), Settings()), tmp_path / "b")
    assert digest_a == digest_b
    a, b = files_of(tmp_path / "a"), files_of(tmp_path / "b")
    assert list(a) == ["model.json", "node_cell.npy", "values.npy", "visits.npy"]
    assert a == b
    other = train(training_scenarios(toy, "", (2,)), Settings())
    assert save_model(other, tmp_path / "c") != digest_a
    assert files_of(tmp_path / "c")["values.npy"] != a["values.npy"]
    assert files_of(tmp_path / "c")["node_cell.npy"] == a["node_cell.npy"]  # same network, same cells


def test_a_trained_model_describes_its_training(toy, tmp_path):
    """model.json: the grid, the discount, the network and each training run; no machine path."""
    runs = training_scenarios(toy, "", (1, 2))
    settings = Settings(cell_m=2000.0, bin_s=900.0, discount=0.8)
    model = train(runs, settings)
    assert model.values.shape == model.visits.shape == (9, 4)  # 3 x 3 cells of 2 km; 4 bins of 900 s
    assert model.node_cell.shape == (toy.network.n_nodes,)
    assert model.network == toy.network.content_hash
    assert model.visits.sum() > 100 and np.isfinite(model.values).all()
    assert model.training == training_record(runs, settings)
    assert model.training["runs"] == [
        {"date": None, "seed": 1, "sample": SAMPLE, "orders": len(runs[0].orders)},
        {"date": None, "seed": 2, "sample": SAMPLE, "orders": len(runs[1].orders)},
    ]
    assert model.training["policy"] == "mb" and model.training["settings"] == dataclasses.asdict(settings)
    save_model(model, tmp_path / "m")
    text = (tmp_path / "m" / MODEL_JSON).read_text()
    assert str(tmp_path) not in text and json.loads(text)["training"] == model.training


def test_policy_iteration_and_td_learn_other_values(toy):
    """iterations = 2 evaluates vf's own policy (another value); method td another estimate of MB's."""
    runs = training_scenarios(toy, "", (1,))
    mb = train(runs, Settings())
    again = train(runs, Settings(iterations=2), next_policy=ValueFunction().next_policy)
    td = train(runs, Settings(method="td", learning_rate=0.1, epochs=5))
    assert again.training["policy"] == "mb, then vf (1 policy iteration)"
    assert not np.array_equal(again.values, mb.values)
    assert not np.array_equal(td.values, mb.values)
    assert np.array_equal(td.visits, mb.visits)  # the same transitions, evaluated otherwise
    # both estimate the same values: they agree in sign and size on the states visited most
    busy = mb.visits >= np.quantile(mb.visits[mb.visits > 0], 0.75)
    assert np.corrcoef(td.values[busy], mb.values[busy])[0, 1] > 0.5


def test_training_scenarios_of_an_undated_generator_are_its_seeds(toy):
    runs = training_scenarios(toy, "2017-05-01..2017-05-07", (4, 9))  # no dates: ignored
    assert [s.seed for s in runs] == [4, 9]
    assert all(s.name == "toy" and s.provenance["sample"] == SAMPLE and s.params == toy.params for s in runs)
    assert all(s.network.content_hash == toy.network.content_hash for s in runs)
    assert len(runs[0].orders) == len(toy.orders) and not np.array_equal(runs[0].orders.origin, toy.orders.origin)


def test_training_scenarios_of_a_dated_generator_are_its_days(two_day_data):
    """On the fake Haikou folder: a test day of 2017-05-02 trains on 2017-05-01, and is held out from it."""
    test_day = build_scenario("haikou-peak", data_dir=two_day_data, date="2017-05-02", sample=1.0)
    runs = training_scenarios(test_day, "2017-05-01", (0, 3))
    assert [(s.provenance["date"], s.seed) for s in runs] == [("2017-05-01", 0), ("2017-05-01", 3)]
    record = training_record(runs, Settings())
    assert held_out_problem(test_day, record) is None
    assert held_out_problem(runs[0], record) == "2017-05-01 is one of its training days"
    # a dated scenario is held out by its day: another seed of a training day is not
    other_seed = build_scenario("haikou-peak", data_dir=two_day_data, date="2017-05-01", sample=1.0, seed=99)
    assert held_out_problem(other_seed, record) == "2017-05-01 is one of its training days"


def test_held_out_rule_of_an_undated_generator(toy):
    """Trained on (seed, sample) draws: the same draw is refused, another seed, sample or generator is not."""
    record = training_record(training_scenarios(toy, "", (0, 5)), Settings())
    assert held_out_problem(toy, record) == "seed 0 is one of its training seeds"
    with pytest.raises(ParameterError) as info:
        check_held_out(toy, record)
    assert str(info.value) == (
        "vf: the value model was trained on this scenario (seed 0 is one of its training seeds); test on held-out "
        "days, seeds or hours, or train on others (--opt vf.train_dates=..., vf.train_seeds=..., vf.train_hours=...)"
    )
    assert held_out_problem(build_scenario("toy", sample=SAMPLE, seed=1), record) is None
    assert held_out_problem(build_scenario("toy", sample=0.5, seed=0), record) is None
    assert held_out_problem(toy, {**record, "scenario": "haikou-peak"}) is None
    check_held_out(build_scenario("toy", sample=SAMPLE, seed=1), record)  # no error


def test_train_refuses_no_scenarios_and_mixed_networks(toy):
    with pytest.raises(ParameterError, match="vf: no training scenarios"):
        train([], Settings())
    small = build_scenario("toy", sample=SAMPLE, size=8)
    with pytest.raises(ParameterError, match="vf: the training scenarios are on different road networks"):
        train([toy, small], Settings())


def test_cache_key_follows_the_training_inputs(toy):
    runs = training_scenarios(toy, "", (1,))
    key = training_key(runs, Settings())
    assert key == training_key(training_scenarios(toy, "", (1,)), Settings()) and len(key) == 24
    assert key != training_key(training_scenarios(toy, "", (2,)), Settings())
    assert key != training_key(runs, Settings(discount=0.95))
    assert key != training_key(runs + training_scenarios(toy, "", (2,)), Settings())
    moved = dataclasses.replace(
        runs[0], orders=dataclasses.replace(runs[0].orders, request_s=runs[0].orders.request_s + 1)
    )
    assert key != training_key([moved], Settings())


def test_cached_model_trains_once_and_retrains_a_damaged_entry(toy, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    runs = training_scenarios(toy, "", (1,))
    model, digest, folder = cached_model(runs, Settings(), progress=False)
    assert folder == tmp_path / "cache" / CACHE_FOLDER / training_key(runs, Settings())
    assert load_model(folder)[1] == digest
    entry = files_of(folder)

    def no_training(*args, **kwargs):
        raise AssertionError("trained again")

    monkeypatch.setattr(training, "train", no_training)
    again, digest_again, folder_again = cached_model(runs, Settings(), progress=False)
    assert (digest_again, folder_again) == (digest, folder) and np.array_equal(again.values, model.values)
    monkeypatch.undo()
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    np.save(folder / "values.npy", np.zeros_like(model.values))  # a damaged entry
    capsys.readouterr()
    rebuilt, digest_rebuilt, _ = cached_model(runs, Settings(), progress=False)
    assert "rebuilding the cached value model" in capsys.readouterr().err
    assert digest_rebuilt == digest and files_of(folder) == entry
    assert [p.name for p in folder.parent.iterdir()] == [folder.name]  # no staging folder left


def test_recording_logs_each_round_without_changing_decisions(toy):
    """The recorded run is MB's run, event for event; the log holds each round's vacant vehicles and nodes."""
    preset = load_preset("highs")
    plain = Simulator(toy, MyopicBatch(), preset).run()
    log: list = []
    policy = MyopicBatch()
    recorded = Simulator(toy, recording(policy, log), preset).run()
    pd.testing.assert_frame_equal(plain.events, recorded.events)
    assert type(policy) is MyopicBatch  # the strategy given is left as it was
    assert [t for t, _, _ in log] == plain.rounds["t_s"].tolist()
    assert [len(v) for _, v, _ in log] == plain.rounds["v0"].tolist()
    n_vehicles = len(toy.fleet.initial_node)
    assert len(log[0][1]) == n_vehicles  # nobody is busy before the first round
    for _, vehicles, nodes in log:
        assert len(np.unique(vehicles)) == len(vehicles) == len(nodes)
        assert vehicles.min() >= 0 and vehicles.max() < n_vehicles
        assert nodes.min() >= 0 and nodes.max() < toy.network.n_nodes
