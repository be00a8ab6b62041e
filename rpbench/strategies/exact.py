"""Exact: the proven offline optimum OPT of a lattice city, carried out by the simulator round by round.

Clairvoyant: :meth:`Exact.prepare` builds the time-expanded flow model of the whole day
(:mod:`rpbench.oracle.exact`) and solves it to proven optimality; every round then hands the simulator
exactly the plan's decisions of that round — vacant assignments, two-passenger trips and joins, as a
trip-packing model whose only columns are the planned ones (each worth one unit, so the solver takes
them all) — and moves every free vehicle to the node the plan has it at in the next round
(:meth:`Exact.reposition`, and :meth:`Exact.idle_moves` in rounds where nobody waits).

The run is checked like every run (so OPT's schedule is feasible), and its plan is copied into the
results folder (``exact-plan/plan.json``) so that ``rpbench check`` verifies that the run realised the
model's optimum, pair by pair (docs/bound.md, "Exact optima on lattice cities").  Should the simulation
ever leave the plan (a vehicle not at its planned node), the round fails with one line saying where:
the model and the simulator disagree, which the tests rule out.
"""

from __future__ import annotations

import hashlib
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import LookaheadError, ModelError, SolverError
from rpbench.model import Structure, TripPackingModel
from rpbench.options import Range, RunOptions, option
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import Kind, RoundModel, RoundState, Strategy

#: The artefact holding the plan (``runs/exact/exact-plan/plan.json``).
EXACT_PLAN = "exact-plan"
PLAN_FILE = "plan.json"
#: Planned columns take the node exactly: a vehicle this far before a node is not at it.
_AT_NODE_M = 1e-6


@dataclass(frozen=True)
class ExactOptions(RunOptions):
    """How the offline model is solved."""

    solver: str = option("highs", "the MILP solver of the flow model (both exact)", choices=("highs", "cp-sat"))
    time_limit_s: float = option(
        600.0,
        "time allowed to prove the optimum (past it the run ends with one error line)",
        range=Range(1.0, 86400.0, "s"),
    )
    threads: int = option(1, "solver threads", range=Range(1, 64))


class Exact(Strategy[ExactOptions]):
    name = "exact"
    label = "Exact optimum"
    color = "black"
    structure = Structure.TRIP_PACKING
    Options = ExactOptions
    description = (
        "clairvoyant: the proven offline optimum of a lattice city (a time-expanded flow model of the whole "
        "day), carried out by the simulator"
    )
    clairvoyant = True

    def __init__(self, options: ExactOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self._decisions: dict[int, list[dict[str, Any]]] = {}
        self._walk: dict[int, dict[int, int]] = {}
        self._record: dict[str, Any] = {}
        self._artefact: tuple[str, Path] | None = None

    # ---------------------------------------------------------------- prepare
    def prepare(self, scenario: Scenario | OnlineView) -> None:
        from rpbench.oracle.exact import build_exact_model, extract_plan, lattice_view, solve_exact_model

        if not isinstance(scenario, Scenario):
            raise LookaheadError(f"strategy {self.name!r} plans the whole day: its prepare needs the whole scenario")
        self.dt = scenario.params.dt_s
        view = lattice_view(scenario)
        model = build_exact_model(view, scenario)
        opts = self.options
        sol = solve_exact_model(model, solver=opts.solver, time_limit_s=opts.time_limit_s, threads=opts.threads)
        if not sol.proven:
            raise SolverError(
                f"exact: the {opts.solver} solve of the day's model ({model.n_arcs:,} arcs) ran out of time after "
                f"{sol.solve_s:.0f} s without proving its optimum (best {sol.objective} blocks, bound "
                f"{sol.bound:.1f}); raise --opt exact.time_limit_s"
            )
        plan = extract_plan(model, sol)
        self._decisions = plan.by_round()
        self._walk = {vp.vehicle: vp.walk for vp in plan.vehicles}
        pairs = sorted(
            (job["order_a"], job["order_b"], job["saving_blocks"] * view.block_m)
            for vp in plan.vehicles
            for job in vp.jobs
        )
        self._record = {
            "status": sol.status,
            "solver": sol.solver,
            "objective_m": plan.objective_m,
            "objective_blocks": plan.objective_blocks,
            "bound_blocks": sol.bound,
            "block_m": view.block_m,
            "model": model.size(),
            "build_s": model.build_s,
            "solve_s": sol.solve_s,
            "pairs": [[int(a), int(b), float(e)] for a, b, e in pairs],
        }
        self._artefact = None

    @property
    def record(self) -> dict[str, Any]:
        """What the plan says: status, objective (m and blocks), the solver's bound, model size, times, pairs."""
        return self._record

    def artefacts(self) -> dict[str, tuple[str, Path]]:
        """The plan as ``exact-plan/plan.json``, named by its SHA-256."""
        if not self._record:
            return {}
        if self._artefact is None:
            folder = Path(tempfile.mkdtemp(prefix="rpbench-exact-plan-"))
            text = json.dumps(self._record, indent=1, sort_keys=True)
            (folder / PLAN_FILE).write_text(text, encoding="utf-8")
            self._artefact = (hashlib.sha256(text.encode("utf-8")).hexdigest(), folder)
        return {EXACT_PLAN: self._artefact}

    # ------------------------------------------------------------------ rounds
    def _round_of(self, state: RoundState) -> int:
        return round(state.t_s / self.dt)

    def build(self, state: RoundState) -> RoundModel:
        k = self._round_of(state)
        self._check_walks(state, k)
        row_of = {int(o): i for i, o in enumerate(state.p_order.tolist())}
        v0_row = {int(v): i for i, v in enumerate(state.v0_vehicle.tolist())}
        v1_row = {int(v): state.n_v0 + i for i, v in enumerate(state.v1_vehicle.tolist())}
        cols: list[tuple] = []  # vehicle row, request rows, kind, vehicle, first, second, fofo, pick-up
        for d in self._decisions.get(k, []):
            a, b, v = d["order_a"], d.get("order_b", -1), d["vehicle"]
            if d["kind"] == "join":
                cols.append(self._column(state, k, v1_row, v, row_of, b, -1, Kind.JOIN, b, -1, d["fofo"]))
            elif d["kind"] == "vacant":
                cols.append(self._column(state, k, v0_row, v, row_of, a, -1, Kind.VACANT, a, -1, False))
            else:
                cols.append(self._column(state, k, v0_row, v, row_of, a, b, Kind.TRIP2, a, b, d["fofo"]))
        cols.sort()
        arr = np.array([c[:7] for c in cols], np.int64).reshape(-1, 7)
        model = TripPackingModel(
            state.n_passengers,
            state.n_v0 + state.n_v1,
            arr[:, 0],
            arr[:, 1],
            arr[:, 2],
            np.ones(len(cols)),
            unit_m=1.0,
            name="exact",
        )
        return RoundModel(
            model=model,
            kind=arr[:, 3].astype(np.int8),
            vehicle=arr[:, 4],
            first=arr[:, 5],
            second=arr[:, 6],
            fofo=np.array([c[7] for c in cols], bool),
            utility_m=np.ones(len(cols)),
            pickup_m=np.array([c[8] for c in cols], np.float64),
        )

    def _column(self, state, k, rows, v, row_of, a, b, kind, first, second, fofo):
        """One planned column: (vehicle row, request rows, kind, vehicle, first, second, fofo, pick-up)."""
        if v not in rows or a not in row_of or (b >= 0 and b not in row_of):
            raise ModelError(
                f"the exact plan left the simulation in round {k}: {kind.name} of order {a}"
                + (f" and {b}" if b >= 0 else "")
                + f" with vehicle {v}, which the round does not offer"
            )
        r1, r2 = row_of[a], (row_of[b] if b >= 0 else -1)
        lo, hi = (r1, r2) if r2 < 0 or r1 < r2 else (r2, r1)
        row = rows[v]
        if kind == Kind.JOIN:
            i = row - state.n_v0
            h = state.v1_node[i]
            pickup = float(state.v1_pre_m[i] + state.dist[h, state.p_origin[r1]])
        else:
            pickup = float(state.v0_pre_m[row] + state.dist[state.v0_node[row], state.p_origin[r1]])
        return (row, lo, hi, int(kind), v, first, second, bool(fofo), pickup)

    def _check_walks(self, state: RoundState, k: int) -> None:
        """Every free vehicle stands at the node the plan gives it for round ``k``."""
        for v, node, pre in zip(
            state.v0_vehicle.tolist(), state.v0_node.tolist(), state.v0_pre_m.tolist(), strict=True
        ):
            planned = self._walk.get(v, {}).get(k)
            if planned is not None and (planned != node or pre > _AT_NODE_M):
                raise ModelError(
                    f"the exact plan left the simulation in round {k}: vehicle {v} is {pre:.3g} m before node "
                    f"{node}, planned at node {planned}"
                )

    def _moves(self, state: RoundState, busy: set[int]) -> tuple[np.ndarray, np.ndarray]:
        k = self._round_of(state)
        vehicles, targets = [], []
        for v in state.v0_vehicle.tolist():
            if v in busy:
                continue
            nxt = self._walk.get(v, {}).get(k + 1)
            if nxt is not None:
                vehicles.append(v)
                targets.append(nxt)
        return np.array(vehicles, np.int64), np.array(targets, np.int64)

    def reposition(self, state: RoundState, rm: RoundModel, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every free vehicle to its planned node of the next round."""
        return self._moves(state, set(rm.vehicle[chosen].tolist()))

    def idle_moves(self, state: RoundState) -> tuple[np.ndarray, np.ndarray]:
        """In a round where nobody waits, the same: every free vehicle to its planned next node."""
        self._check_walks(state, self._round_of(state))
        return self._moves(state, set())
