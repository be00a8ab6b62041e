"""``external``: a dispatcher in any language, driven round by round through JSON lines on its stdin and stdout.

``--strategies mb,external --opt external.command="perl my-dispatcher.pl"`` starts the program once (its
arguments split as a shell would, but not run by one), and sends it one JSON object a line
(docs/protocol.md, protocol version :data:`PROTOCOL_VERSION`):

* ``{"type": "start", ...}`` once: the protocol version, the mode, the scenario's name, horizon, fleet
  size and parameters; no answer;
* ``{"type": "round", ...}`` each batch round with a waiting passenger: the time, the waiting passengers,
  the vehicles and the round's candidate ``edges`` (:mod:`.edges`), each with an ``"id"``; the answer is
  one line, ``{"scores": [...]}`` (mode ``scores``: one number per edge, in the order sent) or
  ``{"decision": [...]}`` (mode ``decision``: 0 or 1 per edge);
* ``{"type": "end"}`` when the run is over; the program should then exit.

An answer must come within ``time_limit_s`` of the round being sent (past it is an error, not a wait).
A program that cannot start, exits, hangs past its limit, prints something that is not the JSON
answer, or answers a decision the round cannot take is one :class:`~rpbench.exceptions.DispatcherError`
line naming the program and the round; the run stops and nothing is written.  What the program prints on
its stderr goes to rpbench's.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import select
import shlex
import subprocess
import time
from dataclasses import dataclass
from typing import Any

from rpbench.exceptions import DispatcherError, ParameterError, one_line
from rpbench.model import Structure
from rpbench.options import Range, option
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.edges import (
    ANSWER_MODES,
    EDGE_KINDS,
    RoundEdges,
    model_from_decision,
    model_from_scores,
    round_edges,
)
from rpbench.strategies.myopic import PoolingOptions

PROTOCOL_VERSION = 1
#: How long the program may take to exit once told the run is over.
EXIT_GRACE_S = 5.0
#: The longest answer line read (a round of the full Haikou day has tens of thousands of edges).
MAX_LINE_BYTES = 64 << 20


@dataclass(frozen=True)
class ExternalOptions(PoolingOptions):
    """Which program, how it answers, and how long it may think."""

    command: str = option("", "the dispatcher program and its arguments, e.g. 'perl my-dispatcher.pl'")
    mode: str = option("scores", "what it answers: a score per edge, or a 0/1 decision per edge", choices=ANSWER_MODES)
    time_limit_s: float = option(10.0, "a round's answer must come within this time", range=Range(0.001, 3600.0, "s"))


class External(Strategy[ExternalOptions]):
    name = "external"
    label = "External"
    color = "tab:olive"
    structure = Structure.ASSIGNMENT
    Options = ExternalOptions
    description = "a dispatcher program in any language, round by round through JSON lines (docs/protocol.md)"

    def __init__(self, options: ExternalOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.process: subprocess.Popen[bytes] | None = None
        self._buffer = b""

    # ----------------------------------------------------------------- the program
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        argv = shlex.split(self.options.command)
        if not argv:
            raise ParameterError("external: give the dispatcher program with --opt external.command='PROGRAM ARGS'")
        try:
            self.process = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        except OSError as exc:
            raise DispatcherError(f"external: cannot start {self.options.command!r}: {one_line(exc)}") from None
        self._send(
            {
                "type": "start",
                "protocol": PROTOCOL_VERSION,
                "mode": self.options.mode,
                "scenario": scenario.name,
                "horizon_s": scenario.horizon_s,
                "vehicles": len(scenario.fleet),
                "params": scenario.params.as_dict(),
            },
            "the start",
        )

    def build(self, state: RoundState) -> RoundModel:
        edges = round_edges(state, self.options.order_rule)
        where = f"round t={state.t_s:g} s"
        self._send(round_message(state, edges), where)
        answer = self._receive(where)
        key = "scores" if self.options.mode == "scores" else "decision"
        if not isinstance(answer, dict) or key not in answer:
            raise self._failed(f'answered {_shown(answer)} in {where}; expected an object {{"{key}": [...]}}')
        try:
            if key == "scores":
                return model_from_scores(state, edges, answer[key], name=self.name)
            return model_from_decision(state, edges, answer[key], name=self.name)
        except ParameterError as exc:
            raise self._failed(f"{where}: {exc}") from None

    def finish(self) -> None:
        """Say the run is over and let the program exit (killed if it does not within a few seconds)."""
        process, self.process = self.process, None
        if process is None:
            return
        try:
            if process.poll() is None and process.stdin is not None:
                process.stdin.write(b'{"type": "end"}\n')
                process.stdin.close()
            process.wait(EXIT_GRACE_S)
        except (OSError, subprocess.TimeoutExpired):
            process.kill()
            process.wait()

    # ----------------------------------------------------------------- the lines
    def _send(self, message: dict[str, Any], where: str) -> None:
        assert self.process is not None and self.process.stdin is not None  # prepare() started it
        try:
            self.process.stdin.write(json.dumps(message, allow_nan=False).encode() + b"\n")
            self.process.stdin.flush()
        except OSError:
            raise self._failed(f"stopped reading before {where} ({self._exit_text()})") from None

    def _receive(self, where: str) -> Any:
        """One answer line, within the time limit."""
        assert self.process is not None and self.process.stdout is not None
        fd = self.process.stdout.fileno()
        deadline = time.monotonic() + self.options.time_limit_s
        while b"\n" not in self._buffer:
            left = deadline - time.monotonic()
            ready = select.select([fd], [], [], max(0.0, left))[0] if left > 0 else []
            if not ready:
                raise self._failed(f"gave no answer to {where} within its {self.options.time_limit_s:g} s")
            chunk = os.read(fd, 1 << 16)
            if not chunk:  # its output closed: it has exited or is exiting; its status says which way
                with contextlib.suppress(subprocess.TimeoutExpired):
                    self.process.wait(EXIT_GRACE_S)
                raise self._failed(f"closed its output before answering {where} ({self._exit_text()})")
            self._buffer += chunk
            if len(self._buffer) > MAX_LINE_BYTES:
                raise self._failed(f"answered {where} with a line of more than {MAX_LINE_BYTES:,} bytes")
        line, _, self._buffer = self._buffer.partition(b"\n")
        try:
            return json.loads(line)
        except (UnicodeDecodeError, json.JSONDecodeError):
            raise self._failed(f"answered {where} with {_shown(line[:80])}, which is not a JSON line") from None

    def _exit_text(self) -> str:
        assert self.process is not None
        code = self.process.poll()
        return "it is still running" if code is None else f"it exited with status {code}"

    def _failed(self, what: str) -> DispatcherError:
        """The error naming the program; the program is stopped first, so nothing waits on it."""
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        return DispatcherError(f"external dispatcher {self.options.command!r} {what}")


def round_message(state: RoundState, edges: RoundEdges) -> dict[str, Any]:
    """The ``round`` line: the waiting passengers, the vehicles the edges name and the edges (ids = positions)."""
    passengers = [
        {
            "id": int(state.p_order[i]),
            "origin": int(state.p_origin[i]),
            "destination": int(state.p_destination[i]),
            "solo_m": float(state.p_solo_m[i]),
            "request_s": float(state.p_request_s[i]),
            "rounds_waited": int(state.p_rounds_waited[i]),
        }
        for i in range(state.n_passengers)
    ]
    vacant = [
        {"id": int(v), "state": "vacant", "node": int(n), "pre_m": float(pre)}
        for v, n, pre in zip(state.v0_vehicle, state.v0_node, state.v0_pre_m, strict=True)
    ]
    one_aboard = [
        {
            "id": int(state.v1_vehicle[j]),
            "state": "one passenger" if state.v1_onboard[j] else "on the way to one passenger",
            "node": int(state.v1_node[j]),
            "pre_m": float(state.v1_pre_m[j]),
            "passenger": int(state.v1_order[j]),
        }
        for j in range(state.n_v1)
    ]
    return {
        "type": "round",
        "t_s": float(state.t_s),
        "passengers": passengers,
        "vehicles": vacant + one_aboard,
        "edges": [
            {
                "id": i,
                "kind": EDGE_KINDS[edges.kind[i]],
                "passenger": int(state.p_order[edges.passenger[i]]),
                "vehicle": None if edges.vehicle[i] < 0 else int(edges.vehicle[i]),
                "pickup_m": _number(edges.pickup_m[i]),
                "saving_m": float(edges.saving_m[i]),
                "first_dropped": bool(edges.first_dropped[i]),
                "remaining_m": _number(edges.remaining_m[i]),
            }
            for i in range(len(edges))
        ],
    }


def _number(value: float) -> float | None:
    return None if math.isnan(value) else float(value)


def _shown(value: Any) -> str:
    text = value.decode(errors="replace") if isinstance(value, bytes) else json.dumps(value, default=str)
    return repr(text[:80] + ("..." if len(text) > 80 else ""))
