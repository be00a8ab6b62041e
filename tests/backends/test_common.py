"""Status rules shared by every backend, and time limits that stop real solves."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from rpbench.backends import SolveOptions
from rpbench.backends._common import INFEASIBLE, LIMIT, OPTIMAL, Clock, Raw, classify, finish, integral_bound, program
from rpbench.backends._milp import ProgramBackend
from rpbench.backends.presets import load_preset
from rpbench.bench import synthetic
from rpbench.exceptions import SolverError
from rpbench.model import AssignmentModel, PairingModel, Status, TripPackingModel

from .conftest import make

PAIR = PairingModel(4, [0, 1, 2], [1, 2, 3], [1, 10, 1])
ASSIGN = AssignmentModel(1, 1, [0, 0], [0, -1], [-5, -2])


def test_integral_bound_rounds_down_with_a_tolerance():
    assert integral_bound(10.9) == 10.0 and integral_bound(10.0000000001) == 10.0
    assert integral_bound(9.9999999999) == 10.0 and integral_bound(None) is None
    assert integral_bound(float("inf")) is None


@pytest.mark.parametrize(
    "state, obj, bound, gap, expected",
    [
        (OPTIMAL, 10.0, 10.0, 0.0, Status.OPTIMAL),
        (OPTIMAL, 10.0, 12.0, 0.1, Status.FEASIBLE),  # stopped by a requested gap
        (LIMIT, 10.0, 12.0, 0.0, Status.TIME_LIMIT),
        (LIMIT, 10.0, 10.0, 0.0, Status.OPTIMAL),  # the bound proves the incumbent: integral values
        (LIMIT, 10.0, None, 0.0, Status.TIME_LIMIT),
    ],
)
def test_classify(state, obj, bound, gap, expected):
    assert classify(state, obj, bound, gap) is expected


def test_finish_rejects_fractional_answers_and_impossible_infeasibility():
    with pytest.raises(SolverError, match="fractional"):
        finish(PAIR, Raw(x=np.array([0.5, 0.0, 0.5]), state=OPTIMAL), "x", Clock())
    # feasibility is verified once, by rpbench.backends.solve (tests/backends/test_solve.py), not here
    assert finish(PAIR, Raw(x=np.array([1.0, 1.0, 0.0]), state=OPTIMAL), "x", Clock()).chosen.tolist() == [0, 1]
    with pytest.raises(SolverError, match="x = 0 is feasible"):
        finish(PAIR, Raw(x=None, state=INFEASIBLE), "x", Clock())


def test_time_limit_without_incumbent():
    # packing/pairing: x = 0 with status time_limit; assignment: a clear error
    sol = finish(PAIR, Raw(x=None, state=LIMIT, bound=12.7), "x", Clock())
    assert sol.status is Status.TIME_LIMIT and sol.cardinality == 0 and sol.bound == 12.0
    with pytest.raises(SolverError, match="before finding any feasible assignment"):
        finish(ASSIGN, Raw(x=None, state=LIMIT), "x", Clock())


def test_time_limit_returns_the_incumbent_with_bound_and_gap():
    sol = finish(PAIR, Raw(x=np.array([0.0, 1.0, 0.0]), state=LIMIT, bound=10.4), "x", Clock())
    assert sol.status is Status.OPTIMAL  # floor(10.4) = 10 = objective: proven
    sol = finish(PAIR, Raw(x=np.array([1.0, 0.0, 1.0]), state=LIMIT, bound=10.4), "x", Clock())
    assert sol.status is Status.TIME_LIMIT and sol.objective == 2.0 and sol.bound == 10.0
    assert sol.gap == pytest.approx(4.0)


def test_a_bound_below_the_incumbent_proves_nothing():
    # e.g. CP-SAT's bound without a solution: it must not turn a time limit into "optimal"
    sol = finish(PAIR, Raw(x=np.array([1.0, 0.0, 1.0]), state=LIMIT, bound=0.0), "x", Clock())
    assert sol.status is Status.TIME_LIMIT and sol.bound is None and sol.gap is None


def test_program_rows_and_cardinality_row():
    prog = program(ASSIGN)
    assert prog.lo.tolist() == [1.0, -np.inf] and prog.hi.tolist() == [1.0, 1.0]
    prog = program(PAIR, c=np.ones(3), min_count=2)
    assert prog.A.shape == (5, 3) and prog.lo[-1] == 2 and np.isinf(prog.hi[-1]) and prog.c.tolist() == [1, 1, 1]


@pytest.mark.parametrize("seed", range(10))
def test_program_arrays_are_the_sorted_incidence_matrix(seed):
    # The CSC arrays handed to solvers equal scipy's sorted incidence matrix, with or without the extra row.
    rng = np.random.default_rng(seed)
    n_req, n_veh, n = 6, 4, int(rng.integers(1, 15))
    r1 = rng.integers(0, n_req - 1, n)
    r2 = np.where(rng.random(n) < 0.5, -1, r1 + 1 + rng.integers(0, n_req - 1 - r1))
    keys = {(int(v), int(a), int(b)) for v, a, b in zip(rng.integers(0, n_veh, n), r1, r2, strict=True)}
    v, a, b = (np.array(x) for x in zip(*sorted(keys), strict=True))
    model = TripPackingModel(n_req, n_veh, v, a, b, rng.integers(-5, 5, len(v)).astype(float))
    for min_count in (None, 1):
        prog = program(model, min_count=min_count)
        expected = model.incidence()
        if min_count is not None:
            expected = sp.vstack([expected, sp.csr_matrix(np.ones((1, model.n_cols)))], format="csc")
        expected.sort_indices()
        assert np.array_equal(prog.indptr, expected.indptr) and np.array_equal(prog.indices, expected.indices)
        assert (expected != prog.A).nnz == 0 and prog.n_rows == expected.shape[0] and prog.n == model.n_cols


@pytest.mark.parametrize("seed", range(20))
def test_sorted_within_columns_agrees_with_scipy(seed):
    from rpbench.backends._common import _sorted_within_columns

    rng = np.random.default_rng(seed)
    counts = rng.integers(0, 4, int(rng.integers(1, 8)))
    start = np.concatenate([[0], np.cumsum(counts)])
    rows = rng.integers(0, 6, start[-1]).astype(np.int32)
    A = sp.csc_matrix((np.ones(len(rows)), rows, start), shape=(6, len(counts)))
    strictly = all((np.diff(rows[start[c] : start[c + 1]]) > 0).all() for c in range(len(counts)))
    assert _sorted_within_columns(start, rows) == strictly
    if strictly:
        assert A.has_sorted_indices


class _Scripted(ProgramBackend):
    """A fake MILP backend replaying raw answers, to test the shared drivers."""

    name, requires, description = "scripted", (), "test double"

    def __init__(self, answers):
        self.answers, self.calls = list(answers), []

    def run(self, prog, options, clock, *, relax=False, time_limit=None, hint=None):
        self.calls.append({"relax": relax, "rows": prog.A.shape[0], "hint": hint})
        answer = self.answers.pop(0)
        if isinstance(answer, Exception):
            raise answer
        return answer


def test_fractional_lp_vertex_is_resolved_as_mip():
    model = AssignmentModel(1, 2, [0, 0, 0], [0, 1, -1], [1, 1, 0])
    b = _Scripted([Raw(x=np.array([0.5, 0.5, 0.0]), state=OPTIMAL), Raw(x=np.array([1.0, 0, 0]), state=OPTIMAL)])
    sol = b.solve(model, SolveOptions())
    assert [c["relax"] for c in b.calls] == [True, False] and "re-solved as a MIP" in sol.message


def test_failed_lp_is_resolved_as_mip():
    # HiGHS's simplex ended "kUnknown" on a real full-day FL-nd round (wait values of -1e9 beside ~1e6)
    model = AssignmentModel(1, 2, [0, 0, 0], [0, 1, -1], [3, 1, -(10**9)])
    b = _Scripted([SolverError("HiGHS failed with model status kUnknown"), Raw(x=np.array([1.0, 0, 0]), state=OPTIMAL)])
    sol = b.solve(model, SolveOptions())
    assert [c["relax"] for c in b.calls] == [True, False] and sol.objective == 3
    assert "kUnknown" in sol.message and "re-solved as a MIP" in sol.message


def test_oracle2_stage1_is_combinatorial_and_warm_starts_stage2():
    # the path 0-1-2-3 has one 2-matching, {(0,1), (2,3)}: Edmonds finds it, the MIP only solves stage 2
    model = PairingModel(4, [0, 1, 2], [1, 2, 3], [1, 10, 1], objective="cardinality_then_weight")
    b = _Scripted([Raw(x=None, state=LIMIT, bound=2.0)])
    sol = b.solve(model, SolveOptions(time_limit_s=10))
    assert len(b.calls) == 1
    assert b.calls[0]["rows"] == 5 and b.calls[0]["hint"].tolist() == [1, 0, 1]  # degree rows + Σx >= 2
    assert sol.status is Status.OPTIMAL and sol.chosen.tolist() == [0, 2]  # start adopted, bound proves it


def test_oracle2_stage2_stopped_early_reports_time_limit():
    model = PairingModel(4, [0, 1, 2], [1, 2, 3], [1, 10, 1], objective="cardinality_then_weight")
    b = _Scripted([Raw(x=None, state=LIMIT, bound=5.0)])
    sol = b.solve(model, SolveOptions(time_limit_s=10))
    assert sol.status is Status.TIME_LIMIT and sol.chosen.tolist() == [0, 2] and sol.bound == 5.0


MIP_PRESETS = ["highs", "scipy", "ortools", "cvxpy-highs", "pyomo-highs"]


@pytest.mark.slow
@pytest.mark.parametrize("name", MIP_PRESETS)
def test_time_limit_stops_a_hard_pairing_and_returns_a_feasible_incumbent(name):
    backend, options = make(name)
    model = synthetic.pairing(1500, partners=30)  # several seconds to prove for every MIP
    sol = backend.solve(model, SolveOptions(**{**options.__dict__, "time_limit_s": 0.3}))
    assert sol.status is Status.TIME_LIMIT
    assert model.violations(sol.chosen) == []
    assert sol.bound is None or sol.bound >= sol.objective


def test_time_limit_in_trip_packing_keeps_feasibility():
    backend, options = make("highs")
    model = synthetic.trip_packing(400, 200)
    sol = backend.solve(model, SolveOptions(time_limit_s=0.5))
    assert sol.status in (Status.OPTIMAL, Status.TIME_LIMIT) and model.violations(sol.chosen) == []


def test_requested_gap_gives_feasible_or_optimal():
    backend, options = make("highs")
    sol = backend.solve(synthetic.pairing(300, partners=10), SolveOptions(mip_rel_gap=0.5))
    assert sol.status in (Status.FEASIBLE, Status.OPTIMAL)
    if sol.status is Status.FEASIBLE:
        assert sol.bound > sol.objective


def test_presets_ship_single_thread_deterministic_options():
    for name in ["highs", "ortools", "pyomo-highs", "cvxpy-highs", "matching"]:
        assert load_preset(name).options.threads == 1
    assert TripPackingModel  # (imported for the structures list)
