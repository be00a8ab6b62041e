"""rpbench/Dispatch-v0: a Gymnasium environment whose episodes are ordinary runs.  MB's scores played
through it give MB's event log; the return is the episode's total saving; a graded episode is a results
folder the checker passes, with the bracket; bad actions and parameters are one clear error."""

from __future__ import annotations

import threading
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
from gymnasium.utils.env_checker import check_env

import rpbench.env
from rpbench.backends import load_preset
from rpbench.check.verify import check_folder
from rpbench.cli import main
from rpbench.env.dispatch import DispatchEnv
from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.harness.comparison import simulate_strategy
from rpbench.scenarios import ScenarioRequest
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M

TOY = {"scenario": "toy", "sample": 0.3}


def mb_scores(env: DispatchEnv) -> np.ndarray:
    """MB's utilities (Eqs. 1-4 with MB's weights) of the round's shown edges, from its exact edges."""
    r = env.round
    assert r is not None
    e = r.edges
    scores = np.where(e.kind == 2, NO_WAIT_UTILITY_M, e.saving_m - np.nan_to_num(e.pickup_m))
    return np.concatenate([scores[: r.shown], np.zeros(env.max_edges - r.shown)])


def play(env: DispatchEnv, policy, seed: int = 0) -> tuple[list[float], dict]:
    env.reset(seed=seed)
    rewards = []
    while True:
        _, reward, terminated, truncated, info = env.step(policy(env))
        rewards.append(reward)
        assert not truncated
        if terminated:
            return rewards, info


@pytest.mark.filterwarnings("ignore:.*(recommend using a symmetric|infinity).*:UserWarning")
def test_the_environment_passes_gymnasiums_checker():
    env = gym.make(rpbench.env.ENV_ID, **TOY)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_mbs_scores_through_the_environment_are_mbs_run(tmp_path):
    env = DispatchEnv(**TOY, results_dir=tmp_path)
    rewards, info = play(env, mb_scores)
    scenario = ScenarioRequest(name="toy", sample=0.3).build()
    mb = simulate_strategy(scenario, "mb", load_preset("highs"))
    mb.sim.events.to_csv(tmp_path / "mb.csv.gz", index=False)
    mb_events, agent = (pd.read_csv(f) for f in (tmp_path / "mb.csv.gz", info["folder"] + "/runs/agent/events.csv.gz"))
    pd.testing.assert_frame_equal(mb_events, agent)
    # the return is the measured total saving, and the per-round planned savings already add up to it
    assert sum(rewards) == pytest.approx(mb.kpis["total_saving_km"], abs=1e-9)
    assert abs(info["final_correction"]) < 1e-6
    # graded: the folder passes the checker and the agent sits inside the bracket
    assert info["check"] == "OK"
    assert all(c.ok for c in check_folder(info["folder"]))
    assert info["total_saving_km"] <= info["best_known_km"] + 1e-9 <= info["upper_bound_km"] + 1e-6
    assert info["competitive_ratio_bound"] == pytest.approx(info["total_saving_km"] / info["upper_bound_km"])


@pytest.mark.parametrize(("reward", "kpi"), [("profit", "platform_profit_cny"), ("response", "response_rate")])
def test_the_return_is_the_chosen_kpi_and_the_plans_already_add_up_to_it(reward, kpi):
    env = DispatchEnv(**TOY, reward=reward)
    rewards, info = play(env, mb_scores)
    assert sum(rewards) == pytest.approx(info["kpis"][kpi], rel=1e-12)
    assert abs(info["final_correction"]) < 1e-6 * max(1.0, abs(info["kpis"][kpi]))
    assert info[kpi] == info["kpis"][kpi]


def test_a_graded_episode_beside_other_strategies_under_the_agents_name(tmp_path):
    env = DispatchEnv(**TOY, results_dir=tmp_path / "graded", name="cem", label="CEM agent", beside=["np", "mb"])
    _, info = play(env, mb_scores)
    folder = Path(info["folder"])
    assert sorted(p.name for p in (folder / "runs").iterdir()) == ["bound", "cem", "hindsight", "mb", "np"]
    assert info["check"] == "OK"
    assert info["saving_km_by_run"]["cem"] == pytest.approx(info["saving_km_by_run"]["mb"])  # MB's scores
    assert "CEM agent" in (folder / "report.md").read_text()
    assert info["best_known_km"] == max(info["saving_km_by_run"][r] for r in ("cem", "np", "mb", "hindsight"))
    with pytest.raises(ParameterError, match="run name 'a/b'"):
        DispatchEnv(**TOY, results_dir=tmp_path / "x", name="a/b")
    with pytest.raises(ParameterError, match="appears twice"):
        DispatchEnv(**TOY, results_dir=tmp_path / "y", name="mb", beside=["mb"])


def test_a_decision_agent_and_a_bad_decision(tmp_path):
    env = DispatchEnv(**TOY, mode="decision")
    obs, _ = env.reset(seed=0)
    two = np.zeros(env.max_edges, np.int8)
    first = np.flatnonzero((obs["passenger"] == 0) & (obs["edges"][:, 2] == 1))  # passenger 0's wait edge
    two[[0, int(first[0])]] = 1  # its first edge and its wait edge: two edges of one passenger
    with pytest.raises(ParameterError, match="passenger .* has 2 edges chosen"):
        env.step(two)
    # the episode goes on: the rejected action decided nothing

    def greedy(env: DispatchEnv) -> np.ndarray:
        """Each passenger its cheapest vacant edge whose vehicle is still free, else it waits."""
        r = env.round
        e, taken, served = r.edges, set(), set()
        out = np.zeros(env.max_edges, np.int8)
        for i in np.argsort(np.nan_to_num(e.pickup_m[: r.shown], nan=np.inf), kind="stable"):
            if e.kind[i] == 0 and e.vehicle[i] not in taken and e.passenger[i] not in served:
                out[i] = 1
                taken.add(e.vehicle[i])
                served.add(e.passenger[i])
        return out

    rewards, info = play(env, greedy)
    assert info["kpis"]["response_rate"] > 0.5
    assert sum(rewards) == pytest.approx(info["total_saving_km"])


def test_the_same_seed_replays_the_same_episode_and_another_seed_another():
    env = DispatchEnv(scenario="toy", sample=0.3)
    a, _ = env.reset(seed=1)
    b, _ = env.reset(seed=1)
    c, _ = env.reset(seed=2)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not all(np.array_equal(a[k], c[k]) for k in a)
    env.close()


def test_reset_and_close_let_go_of_an_unfinished_episode(tmp_path):
    env = DispatchEnv(**TOY, results_dir=tmp_path)
    before = threading.active_count()
    env.reset(seed=0)
    env.step(mb_scores(env))
    env.reset(seed=0)  # the first episode is dropped: its thread unwinds
    env.close()
    assert threading.active_count() == before
    assert not any(tmp_path.iterdir())  # an episode that did not end writes nothing
    with pytest.raises(ParameterError, match="call reset"):
        env.step(np.zeros(env.max_edges))


def test_a_round_wider_than_max_edges_is_shown_passenger_by_passenger():
    env = DispatchEnv(scenario="toy", sample=1.0, max_edges=40)
    env.reset(seed=0)
    held = []
    while True:
        r = env.round
        whole = r.shown == len(r.edges) or r.edges.passenger[r.shown] != r.edges.passenger[r.shown - 1]
        assert r.shown <= 40 and whole  # whole passengers only
        held.append(r.held)
        _, _, terminated, _, _ = env.step(mb_scores(env))
        if terminated:
            break
    assert max(held) > 0  # some rounds held passengers back, and the episode still ran to its end
    narrow = DispatchEnv(scenario="toy", sample=1.0, max_edges=1)
    with pytest.raises(ParameterError, match="raise max_edges"):
        narrow.reset(seed=0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"mode": "votes"}, "mode 'votes'"),
        ({"max_edges": 0}, "max_edges 0"),
        ({"preset": "nope"}, "nope"),
        ({"scenario": "atlantis"}, "atlantis"),
        ({"params": {"dt_s": -3}}, "dt_s"),
        ({"reward": "smiles"}, "reward 'smiles'"),
        ({"beside": ["nosuch"], "results_dir": "unused"}, "unknown strategy 'nosuch'"),
    ],
)
def test_bad_parameters_are_one_line(kwargs, message):
    with pytest.raises(RpbenchError, match=message):
        DispatchEnv(**{**TOY, **kwargs})


def test_an_action_of_the_wrong_size_is_refused():
    env = DispatchEnv(**TOY)
    env.reset(seed=0)
    with pytest.raises(ParameterError, match="one per edge row"):
        env.step(np.zeros(3))
    env.close()


def test_vector_environments_step_episodes_side_by_side():
    envs = gym.vector.SyncVectorEnv([lambda: DispatchEnv(**TOY) for _ in range(2)])
    obs, _ = envs.reset(seed=[0, 1])
    assert obs["edges"].shape == (2, 1024, 10)
    for _ in range(5):
        obs, reward, terminated, truncated, _ = envs.step(np.zeros((2, 1024)))
    assert reward.shape == (2,)
    envs.close()


def test_the_agent_strategy_outside_an_environment_is_one_line(tmp_path, capsys):
    code = main(["run", "--scenario", "toy", "--sample", "0.2", "--strategies", "agent", "--out", str(tmp_path / "x")])
    assert code == 2
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("rpbench: error")]
    assert len(errors) == 1 and "Gymnasium" in errors[0]
    assert not (tmp_path / "x").exists()


def test_a_scenario_without_a_choice_is_an_episode_of_one_step():
    env = DispatchEnv(scenario="toy", sample=0.2, params={"max_pickup_m": 1})  # no vehicle reaches anyone
    obs, info = env.reset(seed=0)
    assert obs["mask"].sum() == 0 and info == {}
    _, reward, terminated, _, info = env.step(np.zeros(env.max_edges))
    assert terminated and reward == 0.0 and info["kpis"]["response_rate"] == 0.0


def test_asynchronous_vector_environments_run_in_worker_processes():
    envs = gym.make_vec(rpbench.env.ENV_ID, num_envs=2, vectorization_mode="async", scenario="toy", sample=0.3)
    obs, _ = envs.reset(seed=0)
    for _ in range(3):
        obs, reward, *_ = envs.step(np.zeros((2, 1024)))
    assert obs["mask"].shape == (2, 1024) and reward.shape == (2,)
    envs.close()


@pytest.mark.haikou
@pytest.mark.filterwarnings("ignore:.*(recommend using a symmetric|infinity).*:UserWarning")
def test_on_a_haikou_peak_hour_the_checker_passes_and_mbs_scores_give_mbs_saving(data_dir, tmp_path):
    env = DispatchEnv(scenario="haikou-peak", sample=0.3, data_dir=str(data_dir), results_dir=tmp_path, beside=["mb"])
    check_env(env, skip_render_check=True)
    rewards, info = play(env, mb_scores)
    assert info["check"] == "OK"
    assert sum(rewards) == pytest.approx(info["saving_km_by_run"]["agent"], abs=1e-9)
    assert info["saving_km_by_run"]["agent"] == pytest.approx(info["saving_km_by_run"]["mb"], abs=1e-9)
