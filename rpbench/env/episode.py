"""One episode: a run of the ``agent`` strategy through the harness, in a thread of its own.

The thread calls the harness as ``rpbench run`` would (:func:`~rpbench.harness.comparison.run_comparison`
when the episode is graded into a results folder, :func:`~rpbench.harness.comparison.simulate_strategy`
otherwise), with an :class:`~rpbench.strategies.agent.Link` the agent strategy plays through.  The
environment's thread and this one take turns: :meth:`Episode.next` waits for the next round (or the end),
:meth:`Episode.answer` hands the round's model back.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

from rpbench.backends import Preset
from rpbench.harness.comparison import run_comparison, simulate_strategy
from rpbench.harness.outcome import Outcome
from rpbench.results.folder import StrategyRun
from rpbench.scenarios.base import Scenario
from rpbench.spec import RunSpec
from rpbench.strategies.agent import Committed, Link, Round, Stopped, linked
from rpbench.strategies.base import RoundModel

#: How long closing an episode waits for its thread to unwind.
STOP_WAIT_S = 30.0


@dataclass(frozen=True)
class Finished:
    """The episode's end: the agent's run (its KPIs) and, when graded, the comparison's outcome."""

    run: StrategyRun | None
    outcome: Outcome | None


@dataclass(frozen=True)
class _Failed:
    error: BaseException


class Episode:
    """The agent's run of ``scenario`` under ``spec`` (its run ``name``), written to ``out`` if given."""

    def __init__(self, spec: RunSpec, name: str, scenario: Scenario, preset: Preset, out: Path | None):
        self.link = Link()
        self._spec, self._name, self._scenario, self._preset, self._out = spec, name, scenario, preset, out
        self.finished: Finished | None = None
        self._thread = threading.Thread(target=self._play, name="rpbench-episode", daemon=True)
        self._thread.start()

    def _play(self) -> None:
        try:
            with linked(self.link):
                if self._out is not None:
                    outcome = run_comparison(self._spec, self._out, scenario=self._scenario, progress=False)
                    result = Finished(None, outcome)
                else:
                    entry = self._spec.entry(self._name)
                    result = Finished(simulate_strategy(self._scenario, entry, self._preset, progress=False), None)
        except Stopped:
            return
        except BaseException as exc:  # handed to the environment's thread, raised there
            self.link.rounds.put(_Failed(exc))
            return
        self.link.rounds.put(result)

    def next(self) -> Round | Finished:
        """The next round to decide, or the episode's end; an error of the run is raised here."""
        message = self.link.rounds.get()
        if isinstance(message, _Failed):
            self._thread.join(STOP_WAIT_S)
            raise message.error
        if isinstance(message, Finished):
            self.finished = message
            self._thread.join(STOP_WAIT_S)
        return message

    def answer(self, model: RoundModel) -> None:
        self.link.models.put(model)

    def take_committed(self) -> Committed:
        """What the rounds committed since the last call."""
        committed, self.link.committed = self.link.committed, Committed()
        return committed

    def stop(self) -> None:
        """Let go of an unfinished episode: its thread unwinds (the agent strategy raises
        :class:`~rpbench.strategies.agent.Stopped`) and nothing is written."""
        if self._thread.is_alive():
            self.link.models.put(Link.STOP)
            self._thread.join(STOP_WAIT_S)
