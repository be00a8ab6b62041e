"""``agent``: the strategy a learning agent plays through rpbench's Gymnasium environment (:mod:`rpbench.env`).

The simulator runs in a thread of its own; each round with a choice to make, :meth:`Agent.build` hands
the round (its state and candidate edges, :mod:`.edges`) over a :class:`Link` to the environment and
waits for the round's model back, built there from the agent's action.  So the simulator, the solver and
the harness run exactly as for any strategy: the episode is an ordinary run, with an ordinary results
folder the checker reads.

A round whose passengers have no vacant or join edge (nothing to decide: everyone waits) is not handed
over.  Outside an environment (``rpbench run --strategies agent``) there is nobody to ask: one
:class:`~rpbench.exceptions.ParameterError` line says so.
"""

from __future__ import annotations

import contextlib
import queue
import threading
from collections.abc import Iterator
from dataclasses import astuple, dataclass, field
from typing import Any

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy
from rpbench.strategies.edges import RoundEdges, model_from_decision, round_edges
from rpbench.strategies.myopic import PoolingOptions


@dataclass(frozen=True)
class Committed:
    """What rounds committed, as their plans say: passengers assigned, the solo distances of those who took a
    vacant vehicle, of those who joined one and of the partners they joined, and the joins' planned saving e
    (Eq. 5), in metres.  The environment's rewards are read off these (docs/gym.md)."""

    assigned: int = 0
    vacant_solo_m: float = 0.0
    joined_solo_m: float = 0.0
    partner_solo_m: float = 0.0
    saving_m: float = 0.0

    def __add__(self, other: Committed) -> Committed:
        return Committed(*(a + b for a, b in zip(astuple(self), astuple(other), strict=True)))


@dataclass(frozen=True)
class Round:
    """One round handed to the environment: its state and candidate edges."""

    state: RoundState
    edges: RoundEdges


class Stopped(Exception):
    """The environment let go of the episode (closed, or reset) before it ended: the simulator's thread
    unwinds with this."""


@dataclass
class Link:
    """The hand-over between the simulator's thread and the environment's: a round out, a model back.

    Each side waits on its queue; only one of them works at a time, so nothing here is read and written
    at once.
    """

    rounds: queue.Queue[Any] = field(default_factory=lambda: queue.Queue(maxsize=1))
    models: queue.Queue[Any] = field(default_factory=lambda: queue.Queue(maxsize=1))
    #: what the rounds committed since the environment last looked
    committed: Committed = field(default_factory=lambda: Committed())
    #: what the model answers :meth:`Agent.build` with when the environment lets go
    STOP = object()


_current = threading.local()


@contextlib.contextmanager
def linked(link: Link) -> Iterator[None]:
    """Within this block, an :class:`Agent` created on this thread plays through ``link``."""
    _current.link = link
    try:
        yield
    finally:
        del _current.link


class Agent(Strategy[PoolingOptions]):
    name = "agent"
    label = "Agent"
    color = "tab:brown"
    structure = Structure.ASSIGNMENT
    Options = PoolingOptions
    description = "a learning agent's decisions, round by round, through rpbench's Gymnasium environment (docs/gym.md)"

    def __init__(self, options: PoolingOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.link: Link | None = None
        self._edges: RoundEdges | None = None

    def prepare(self, scenario: Scenario | OnlineView) -> None:
        self.link = getattr(_current, "link", None)
        if self.link is None:
            raise ParameterError(
                "strategy 'agent' is played by an agent through rpbench.env's Gymnasium environment "
                "(docs/gym.md); a program in another language plays through 'external' (docs/protocol.md)"
            )

    def build(self, state: RoundState) -> RoundModel:
        assert self.link is not None  # prepare() found it
        edges = self._edges = round_edges(state, self.options.order_rule)
        if not (edges.kind != 2).any():  # nobody can be served in the current round: no choice to hand over
            return model_from_decision(state, edges, np.zeros(len(edges)), name=self.name)
        self.link.rounds.put(Round(state, edges))
        answer = self.link.models.get()
        if answer is Link.STOP:
            raise Stopped
        return answer

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """No moves; what the round committed is added up for the environment's reward."""
        assert self.link is not None and self._edges is not None
        self.link.committed = self.link.committed + round_commit(state, self._edges, rm, chosen)
        return super().reposition(state, rm, chosen)


def round_commit(state: RoundState, edges: RoundEdges, rm: RoundModel, chosen: np.ndarray) -> Committed:
    """What a round's ``chosen`` columns commit: each vacant column's passenger, each join column's passenger
    and the passenger already in its vehicle, and the join's planned saving e (Eq. 5) as its edge gives it
    (a join edge is named once by its passenger and vehicle)."""
    chosen = np.asarray(chosen, np.int64)
    kind = rm.kind[chosen]
    vacant, joins = chosen[kind == Kind.VACANT], chosen[kind == Kind.JOIN]
    solo_of = dict(zip(state.p_order.tolist(), state.p_solo_m.tolist(), strict=True))
    out = Committed(
        assigned=len(vacant) + len(joins), vacant_solo_m=float(sum(solo_of[o] for o in rm.first[vacant].tolist()))
    )
    if not len(joins):
        return out
    is_join = np.flatnonzero(edges.kind == 1)
    edge_of = dict(
        zip(
            zip(state.p_order[edges.passenger[is_join]].tolist(), edges.vehicle[is_join].tolist(), strict=True),
            is_join.tolist(),
            strict=True,
        )
    )
    picked = np.array([edge_of[key] for key in zip(rm.first[joins].tolist(), rm.vehicle[joins].tolist(), strict=True)])
    v1_solo = dict(zip(state.v1_vehicle.tolist(), state.v1_solo_m.tolist(), strict=True))
    return Committed(
        assigned=out.assigned,
        vacant_solo_m=out.vacant_solo_m,
        joined_solo_m=float(state.p_solo_m[edges.passenger[picked]].sum()),
        partner_solo_m=float(sum(v1_solo[v] for v in edges.vehicle[picked].tolist())),
        saving_m=float(edges.saving_m[picked].sum()),
    )
