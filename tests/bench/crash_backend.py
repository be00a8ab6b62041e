"""A backend for the worker tests: it kills its own process (as the out-of-memory killer would) on a model named
``crash``, and answers x = 0 as optimal on any other (a pairing's empty matching is one)."""

from __future__ import annotations

import os
import signal

from rpbench.backends import Backend
from rpbench.model import Status, Structure, make_solution


class Crash(Backend):
    name, requires, exact, description = "crash", (), frozenset(Structure), "dies on a model named 'crash'"

    def solve(self, model, options):
        if model.name == "crash":
            os.kill(os.getpid(), signal.SIGKILL)
        return make_solution(model, [], Status.OPTIMAL, self.name)
