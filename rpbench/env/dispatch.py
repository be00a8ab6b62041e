"""``rpbench/Dispatch-v0``: dynamic ride-pooling dispatch as a Gymnasium environment.

An episode is one run of a scenario: each step is one batch round with a choice to make (rounds where
nobody can be served pass by themselves).  The observation is the round's candidate edges
(:mod:`.observation`); the action scores or decides them; the simulator commits the round's assignment
model, exactly as for a built-in strategy, and moves on to the next round with a choice.

**Reward** (:mod:`.reward`): what the round's committed decisions are planned to add to the chosen KPI
(the total saving by default; profit or response rate).  The last step adds the difference between the
episode's measured KPI and the rewards so far, so an episode's undiscounted return *is* that KPI.

**Grading.**  With ``results_dir``, every episode is an ordinary comparison written to
``results_dir/episode-NNNN`` beside the runs of ``beside`` (``np``, ``mb``, ``fl``, ...), the Hindsight
schedule and the proven upper bound U (``hindsight``, ``bound``), and checked by ``rpbench check``'s
checker; the last step's info carries the verdict and the bracket.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym

from rpbench.backends import load_preset
from rpbench.check.verify import check_folder
from rpbench.env.episode import Episode, Finished
from rpbench.env.observation import ShownRound, action_space, observation_space, observe, round_model, shown_round
from rpbench.env.reward import REWARD_KPIS, check_reward, step_reward
from rpbench.exceptions import ParameterError
from rpbench.results.store import check_new_folder
from rpbench.scenarios import ScenarioRequest
from rpbench.scenarios.base import Scenario
from rpbench.spec import RunSpec
from rpbench.strategies.agent import Round
from rpbench.strategies.edges import ANSWER_MODES

#: The grading runs after the agent's and those ``beside`` it: LB's schedule and the proven upper bound U.
BRACKET = ("hindsight", "bound")
#: Built scenarios kept per environment, by seed (a reset with a seed already seen rebuilds nothing).
SCENARIOS_KEPT = 4


class DispatchEnv(gym.Env):
    """Ride-pooling dispatch on one of rpbench's scenarios (see the module docstring and docs/gym.md).

    ``scenario``, ``sample``, ``seed``, ``date``, ``params``, ``city``, ``window`` and ``data_dir`` name the
    scenario as ``rpbench run``'s options do.  ``mode``: ``"scores"`` or ``"decision"``; ``max_edges``: the
    observation's rows; ``reward``: ``"saving"``, ``"profit"`` or ``"response"``; ``preset``: the rounds'
    solver preset.  ``results_dir`` grades every episode, the agent's run named ``name`` (and labelled
    ``label``), beside the runs ``beside``; ``oracle_preset`` solves the bound.
    """

    metadata = {"render_modes": []}  # noqa: RUF012 (Gymnasium declares it an instance variable)

    def __init__(
        self,
        scenario: str = "toy",
        *,
        sample: float | None = None,
        seed: int = 0,
        date: str | None = None,
        params: dict[str, float] | None = None,
        city: str | None = None,
        window: str | None = None,
        data_dir: str | None = None,
        mode: str = "scores",
        max_edges: int = 1024,
        reward: str = "saving",
        preset: str = "highs",
        results_dir: str | Path | None = None,
        name: str = "agent",
        label: str | None = None,
        beside: Sequence[str] = (),
        oracle_preset: str = "matching",
    ):
        if mode not in ANSWER_MODES:
            raise ParameterError(f"mode {mode!r}: choose one of {', '.join(ANSWER_MODES)}")
        if isinstance(max_edges, bool) or not isinstance(max_edges, int) or max_edges < 1:
            raise ParameterError(f"max_edges {max_edges!r}: a whole number >= 1")
        self.mode, self.max_edges, self.reward = mode, max_edges, check_reward(reward)
        self.preset = load_preset(preset)
        request = ScenarioRequest(
            name=scenario, date=date, sample=sample, seed=seed, city=city, window=window, data_dir=data_dir
        )
        request = request.with_overrides(dict(params or {})).resolved()
        graded = results_dir is not None
        spec = RunSpec.of(
            request,
            ["agent", *(list(beside) + list(BRACKET) if graded else [])],
            preset=preset,
            oracle_preset=oracle_preset,
            command=_command(scenario, mode, request),
        )
        agent = spec.entry("agent").renamed(name, label if label is not None else name)
        self.run_spec = RunSpec(**{**spec.__dict__, "runs": (agent, *spec.runs[1:])})  # names checked again
        self.name = name
        self._scenarios: dict[int, Scenario] = {}
        self.scenario = self._scenario(seed)
        self.results_dir = Path(results_dir) if results_dir is not None else None
        if self.results_dir is not None and not self.results_dir.is_dir():
            check_new_folder(self.results_dir, what="results_dir")  # can it be made? then make it
            self.results_dir.mkdir(parents=True)
        self.observation_space = observation_space(max_edges)
        self.action_space = action_space(mode, max_edges)
        self._episode: Episode | None = None
        self._round: ShownRound | None = None
        self._pending_end: Finished | None = None  # an episode that ended before its first step
        self._return = 0.0
        self._episodes = 0

    # ------------------------------------------------------------------ Gymnasium
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start an episode; ``seed`` (kept for later resets) draws the scenario anew where it samples
        (orders, the fleet's start), so the same seed replays the same scenario."""
        super().reset(seed=seed)
        self._stop()
        if seed is not None:
            self.scenario = self._scenario(seed)
        self._episodes += 1
        out = None
        if self.results_dir is not None:
            out = _free_episode_folder(self.results_dir, self._episodes)
        spec = self.run_spec.for_request(self.run_spec.request.replace(seed=self.scenario.seed))
        self._episode = Episode(spec, self.name, self.scenario, self.preset, out)
        self._return = 0.0
        first = self._episode.next()
        if isinstance(first, Finished):  # a scenario with no choice to make: the first step ends it
            self._round, self._pending_end = None, first
        else:
            self._round, self._pending_end = self._shown(first), None
        return observe(self._round, self.max_edges, self.scenario.horizon_s), self._info()

    def step(self, action):
        episode = self._episode
        if episode is None or (self._round is None and self._pending_end is None):
            raise ParameterError("step() before reset() or after the episode ended; call reset()")
        message: Round | Finished
        if self._round is not None:
            episode.answer(round_model(self._round, self.mode, action, self.max_edges))
            message = episode.next()
        else:
            assert self._pending_end is not None
            message = self._pending_end
        orders = len(self.scenario.orders)
        reward = step_reward(self.reward, episode.take_committed(), self.scenario.params, orders)
        if isinstance(message, Finished):
            self._round = self._pending_end = None
            info = self._ending(message, reward)
            reward += info["final_correction"]
            self._return += reward
            return observe(None, self.max_edges, self.scenario.horizon_s), reward, True, False, info
        self._round = self._shown(message)
        self._return += reward
        return observe(self._round, self.max_edges, self.scenario.horizon_s), reward, False, False, self._info()

    def close(self) -> None:
        self._stop()
        super().close()

    @property
    def round(self) -> ShownRound | None:
        """The round being decided as shown: its state and exact (float64) edges, for an agent that reads more
        than the observation; ``None`` once the episode has ended."""
        return self._round

    # ------------------------------------------------------------------ helpers
    def _scenario(self, seed: int) -> Scenario:
        if seed not in self._scenarios:
            if len(self._scenarios) >= SCENARIOS_KEPT:
                self._scenarios.pop(next(iter(self._scenarios)))
            self._scenarios[seed] = self.run_spec.request.replace(seed=int(seed)).build()
        return self._scenarios[seed]

    def _shown(self, r: Round) -> ShownRound:
        return shown_round(r.state, r.edges, self.max_edges)

    def _info(self) -> dict[str, Any]:
        r = self._round
        if r is None:
            return {}
        return {"t_s": float(r.state.t_s), "waiting": r.state.n_passengers, "edges": len(r.edges), "held": r.held}

    def _ending(self, end: Finished, reward: float) -> dict[str, Any]:
        """The last step's info: the run's KPIs, the reward's final correction and, when graded, the checker's
        verdict and the bracket."""
        if end.outcome is not None:
            table = end.outcome.table
            kpis = {k: float(v) for k, v in table[self.name].items() if not _missing(v)}
        else:
            assert end.run is not None
            table = None
            kpis = dict(end.run.kpis)
        kpi = REWARD_KPIS[self.reward]
        info: dict[str, Any] = {
            "kpis": kpis,
            "total_saving_km": kpis["total_saving_km"],
            kpi: kpis[kpi],
            "final_correction": kpis[kpi] - (self._return + reward),
        }
        if end.outcome is not None and table is not None:
            checks = check_folder(end.outcome.folder)
            failed = [f"{c.run}: {check}" for c in checks for check in c.violations]
            passed = checks and all(c.ok and c.ran for c in checks)
            info["folder"] = str(end.outcome.folder)
            info["check"] = "OK" if passed else "; ".join(failed) or "nothing checked"
            info["saving_km_by_run"] = {run: float(table.loc["total_saving_km", run]) for run in table.columns}
            info["best_known_km"] = float(table.loc["best_known_saving_km", "bound"])
            info["upper_bound_km"] = float(table.loc["total_saving_km", "bound"])
            info["competitive_ratio_bound"] = kpis.get("competitive_ratio_bound", math.nan)
            info["competitive_ratio_best_known"] = kpis.get("competitive_ratio_best_known", math.nan)
        return info

    def _stop(self) -> None:
        if self._episode is not None:
            self._episode.stop()
        self._episode, self._round, self._pending_end = None, None, None


def _missing(value: Any) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def _free_episode_folder(parent: Path, n: int) -> Path:
    """``parent/episode-NNNN``, the first number from ``n`` not yet taken."""
    while (parent / f"episode-{n:04d}").exists():
        n += 1
    return parent / f"episode-{n:04d}"


def _command(scenario: str, mode: str, request: ScenarioRequest) -> str:
    """How the episode's folder records its making: the environment's construction, as Python."""
    return f"gymnasium.make('rpbench/Dispatch-v0', scenario={scenario!r}, mode={mode!r}, seed={request.seed})"
