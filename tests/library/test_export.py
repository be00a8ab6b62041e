"""Exported instance files: each format read back independently reaches the model's exact optimum."""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path

import networkx as nx
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import linear_sum_assignment

from rpbench.backends import load_preset, solve
from rpbench.bench import synthetic
from rpbench.exceptions import ParameterError, SolverError
from rpbench.library.export import FORMATS, export_formats, read_mps_optimum, write_model
from rpbench.model import AssignmentModel, Model, PairingModel, Status, TripPackingModel
from rpbench.model.instances import load_instance

EXAMPLES = Path(__file__).resolve().parents[2] / "instances" / "examples"
EXAMPLE_FILES = sorted(EXAMPLES.glob("*.npz"))
SYNTHETIC: dict[str, Callable[[], Model]] = {
    "synthetic-assignment": lambda: synthetic.assignment(12, 30, seed=2),
    "synthetic-assignment-no-wait": lambda: synthetic.assignment(6, 12, seed=5, density=(0.5, 1.0), wait=False),
    "synthetic-trip-packing": lambda: synthetic.trip_packing(10, 8, seed=4),
    "synthetic-pairing-weight": lambda: synthetic.pairing(60, seed=3),
    "synthetic-pairing-ctw": lambda: synthetic.pairing(60, seed=3, objective="cardinality_then_weight"),
}
KEYS = [f.stem for f in EXAMPLE_FILES] + list(SYNTHETIC)


@functools.cache
def model_of(key: str) -> Model:
    if key in SYNTHETIC:
        return SYNTHETIC[key]()
    return load_instance(EXAMPLES / f"{key}.npz")[0]


@functools.cache
def optimum_of(key: str) -> float:
    """rpbench's exact optimum (model units) by the highs preset."""
    sol = solve(model_of(key), load_preset("highs"))
    assert sol.status is Status.OPTIMAL
    return sol.objective


def keys_of(cls) -> list[str]:
    return [k for k in KEYS if isinstance(model_of(k), cls)]


def test_the_examples_cover_every_structure_and_objective():
    assert len(EXAMPLE_FILES) >= 7
    kinds = {(model_of(k).structure.value, getattr(model_of(k), "objective", "")) for k in KEYS}
    assert kinds == {
        ("assignment", ""),
        ("trip_packing", ""),
        ("pairing", "weight"),
        ("pairing", "cardinality_then_weight"),
    }


def test_export_formats_follow_the_structure():
    assignment, packing = model_of("synthetic-assignment"), model_of("synthetic-trip-packing")
    assert export_formats(assignment) == ("mps", "lp", "asn")
    assert export_formats(packing) == ("mps", "lp")
    assert export_formats(model_of("synthetic-pairing-ctw")) == ("mps", "lp", "edges")
    assert FORMATS == ("mps", "lp", "asn", "edges")


# ------------------------------------------------------------------ MPS and LP
@pytest.mark.parametrize("fmt", ["mps", "lp"])
@pytest.mark.parametrize("key", KEYS)
def test_program_file_reaches_the_exact_optimum(key, fmt, tmp_path):
    model = model_of(key)
    path = write_model(model, tmp_path / f"m.{fmt}", fmt)
    assert path == tmp_path / f"m.{fmt}"
    # Oracle-2's file encodes the lexicographic optimum directly: its value, in model units
    assert read_mps_optimum(path) == optimum_of(key)


def _read_lp(path: Path):
    import highspy

    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    assert h.readModel(str(path)).name == "kOk"
    return h


@pytest.mark.parametrize("key", KEYS)
def test_mps_file_is_the_model_with_names_to_map_solutions_back(key, tmp_path):
    import highspy

    model = model_of(key)
    h = _read_lp(write_model(model, tmp_path / "m.mps", "mps"))
    lp = h.getLp()
    assert lp.sense_ == highspy.ObjSense.kMaximize
    assert list(lp.col_names_) == [f"c{c}" for c in range(model.n_cols)]
    np.testing.assert_array_equal(lp.col_cost_, model.values)
    np.testing.assert_array_equal(lp.col_lower_, 0.0)
    np.testing.assert_array_equal(lp.col_upper_, 1.0)
    assert all(k == highspy.HighsVarType.kInteger for k in lp.integrality_)
    if isinstance(model, AssignmentModel):
        names = [f"p{i}" for i in range(model.n_passengers)] + [f"v{j}" for j in range(model.n_vehicles)]
    elif isinstance(model, TripPackingModel):
        names = [f"r{i}" for i in range(model.n_requests)] + [f"v{j}" for j in range(model.n_vehicles)]
    else:
        names = [f"o{i}" for i in range(model.n_orders)]
    card = isinstance(model, PairingModel) and model.objective == "cardinality_then_weight"
    assert list(lp.row_names_) == names + (["card"] if card else [])
    exact = model.row_exact()
    m = model.n_rows
    np.testing.assert_array_equal(np.asarray(lp.row_lower_)[:m] == 1.0, exact)
    np.testing.assert_array_equal(np.isinf(np.asarray(lp.row_lower_)[:m]), ~exact)
    np.testing.assert_array_equal(np.asarray(lp.row_upper_)[:m], 1.0)
    a = lp.a_matrix_
    got = sp.csc_matrix((a.value_, a.index_, a.start_), shape=(lp.num_row_, lp.num_col_))
    want = model.incidence()
    if card:
        want = sp.vstack([want, sp.csr_matrix(np.ones((1, model.n_cols)))], format="csc")
    assert (got != want).nnz == 0
    # a solution of the file, read back through the column names, is an optimum of the model
    h.setOptionValue("mip_rel_gap", 0.0)
    h.run()
    x = np.asarray(h.getSolution().col_value)
    chosen = [int(name[1:]) for name, value in zip(lp.col_names_, x, strict=True) if value > 0.5]
    assert model.violations(chosen) == []
    assert model.objective_of(chosen) == optimum_of(key)


def test_cardinality_row_is_the_maximum_matching_size_and_decides_the_optimum(tmp_path):
    key = "synthetic_pairing-300-cardinality_then_weight-s1"
    model = model_of(key)
    assert isinstance(model, PairingModel)
    g = nx.Graph(zip(model.col_a.tolist(), model.col_b.tolist(), strict=True))
    k = len(nx.max_weight_matching(g, maxcardinality=True))  # unit weights: the largest matching
    lp = _read_lp(write_model(model, tmp_path / "m.mps", "mps")).getLp()
    assert lp.row_names_[-1] == "card"
    assert (lp.row_lower_[-1], lp.row_upper_[-1]) == (k, np.inf)
    # without the row the same columns reach a larger weight: the file's optimum is the lexicographic one
    weight_only = PairingModel(model.n_orders, model.col_a, model.col_b, model.values, unit_m=model.unit_m)
    plain = read_mps_optimum(write_model(weight_only, tmp_path / "w.mps", "mps"))
    assert plain == solve(weight_only, load_preset("highs")).objective > optimum_of(key)
    assert read_mps_optimum(tmp_path / "m.mps") == optimum_of(key)


def test_infeasible_assignment_file_is_infeasible(tmp_path):
    # two passengers who must ride the one vehicle
    model = AssignmentModel(2, 1, [0, 1], [0, 0], [5.0, 7.0])
    with pytest.raises(SolverError, match="Infeasible"):
        read_mps_optimum(write_model(model, tmp_path / "m.mps", "mps"))
    with pytest.raises(ValueError, match="infeasible"):
        _solve_asn(_parse_asn(write_model(model, tmp_path / "m.asn", "asn").read_text()))


def test_empty_pairing_model_has_optimum_zero(tmp_path):
    model = PairingModel(3, [], [], [])
    assert read_mps_optimum(write_model(model, tmp_path / "m.mps", "mps")) == 0.0
    assert _parse_edges(write_model(model, tmp_path / "m.edges", "edges").read_text()) == (3, [])


def test_values_beyond_15_digits_are_refused_for_mps_and_lp_but_exact_in_asn(tmp_path):
    model = AssignmentModel(1, 1, [0, 0], [0, -1], [2.0**52 + 1, -3.0])
    for fmt in ("mps", "lp"):
        with pytest.raises(ParameterError, match=r"column 0 .* coarser unit_m") as err:
            write_model(model, tmp_path / f"m.{fmt}", fmt)
        assert "\n" not in str(err.value)
        assert not (tmp_path / f"m.{fmt}").exists()
    parsed = _parse_asn(write_model(model, tmp_path / "m.asn", "asn").read_text())
    assert parsed["arcs"][0] == (1, 3, -(2**52 + 1))
    assert _solve_asn(parsed)[0] == -(2**52 + 1)


# ------------------------------------------------------------------ DIMACS assignment
def _parse_asn(text: str) -> dict:
    """An independent reader of the DIMACS assignment format."""
    problem = None
    sources: list[int] = []
    arcs: list[tuple[int, int, int]] = []
    for line in text.splitlines():
        kind, *fields = line.split()
        if kind == "c":
            continue
        if kind == "p":
            assert problem is None and fields[0] == "asn" and not sources and not arcs
            problem = (int(fields[1]), int(fields[2]))
        elif kind == "n":
            sources.append(int(fields[0]))
        elif kind == "a":
            src, dst, cost = map(int, fields)
            arcs.append((src, dst, cost))
        else:
            raise AssertionError(f"unexpected line {line!r}")
    assert problem is not None and problem[1] == len(arcs)
    return {"nodes": problem[0], "sources": sources, "arcs": arcs}


def _solve_asn(parsed: dict) -> tuple[int, list[int]]:
    """Minimum cost of a perfect assignment of the dense cost matrix the file defines, and the arcs used."""
    sources = parsed["sources"]
    sinks = sorted(set(range(1, parsed["nodes"] + 1)) - set(sources))
    assert len(sources) == len(sinks) == len(set(sources))  # balanced: a perfect assignment is possible
    row = {s: i for i, s in enumerate(sources)}
    col = {t: j for j, t in enumerate(sinks)}
    cost = np.full((len(sources), len(sinks)), np.inf)
    arc_of = {}
    for k, (src, dst, c) in enumerate(parsed["arcs"]):
        assert (src, dst) not in arc_of, "parallel arcs"
        arc_of[src, dst] = k
        cost[row[src], col[dst]] = c
    r, c = linear_sum_assignment(cost)  # ValueError "infeasible" when there is no perfect assignment
    total = sum(int(parsed["arcs"][arc_of[sources[i], sinks[j]]][2]) for i, j in zip(r, c, strict=True))
    return total, sorted(arc_of[sources[i], sinks[j]] for i, j in zip(r, c, strict=True))


@pytest.mark.parametrize("key", keys_of(AssignmentModel))
def test_asn_optimum_is_minus_the_model_optimum(key, tmp_path):
    model = model_of(key)
    assert isinstance(model, AssignmentModel)
    parsed = _parse_asn(write_model(model, tmp_path / "m.asn", "asn").read_text())
    P, V = model.n_passengers, model.n_vehicles
    assert parsed["nodes"] == 2 * (P + V)
    assert parsed["sources"] == list(range(1, P + V + 1))
    rides = int((model.col_vehicle >= 0).sum())
    assert len(parsed["arcs"]) == model.n_cols + V + rides
    total, used = _solve_asn(parsed)
    assert total == -optimum_of(key)
    # the arcs of model columns come first, in column order: the assignment maps back to an optimum
    chosen = [k for k in used if k < model.n_cols]
    assert len(chosen) == P
    assert model.violations(chosen) == []
    assert model.objective_of(chosen) == optimum_of(key)


def test_asn_of_a_tiny_model_is_exactly_as_documented(tmp_path):
    # passenger 0: vehicle 0 (9) or wait (-4); passenger 1: vehicle 0 (6) or vehicle 1 (2), no wait
    model = AssignmentModel(2, 2, [0, 0, 1, 1], [0, -1, 0, 1], [9.0, -4.0, 6.0, 2.0], name="tiny")
    text = write_model(model, tmp_path / "m.asn", "asn").read_text()
    assert text.startswith("c ")
    assert "c model 'tiny', structure assignment\n" in text
    assert "c unit_m 0.001" in text
    body = [line for line in text.splitlines() if not line.startswith("c ")]
    # passengers 1-2, idle nodes 3-4; vehicles 5-6, keep-waiting nodes 7-8
    assert body == [
        "p asn 8 9",
        *[f"n {i}" for i in (1, 2, 3, 4)],
        "a 1 5 -9",
        "a 1 7 4",
        "a 2 5 -6",
        "a 2 6 -2",
        "a 3 5 0",
        "a 4 6 0",
        "a 3 7 0",
        "a 3 8 0",
        "a 4 8 0",
    ]
    assert _solve_asn(_parse_asn(text))[0] == -11 == -solve(model, load_preset("highs")).objective


# ------------------------------------------------------------------ edge list
def _parse_edges(text: str) -> tuple[int, list[tuple[int, int, int]]]:
    n = m = None
    edges: list[tuple[int, int, int]] = []
    for line in text.splitlines():
        kind, *fields = line.split()
        if kind == "c":
            continue
        if kind == "p":
            assert fields[0] == "edge" and n is None
            n, m = int(fields[1]), int(fields[2])
        else:
            assert kind == "e" and n is not None
            a, b, w = map(int, fields)
            assert 1 <= a < b <= n
            edges.append((a, b, w))
    assert n is not None and m == len(edges)
    return n, edges


@pytest.mark.parametrize("key", keys_of(PairingModel))
def test_edges_are_the_model_columns(key, tmp_path):
    model = model_of(key)
    assert isinstance(model, PairingModel)
    text = write_model(model, tmp_path / "m.edges", "edges").read_text()
    assert f"objective {model.objective}" in text
    n, edges = _parse_edges(text)
    assert n == model.n_orders
    a, b = (model.col_a + 1).tolist(), (model.col_b + 1).tolist()
    assert edges == list(zip(a, b, model.values.astype(np.int64).tolist(), strict=True))


@pytest.mark.parametrize("key", ["synthetic-pairing-weight", "synthetic-pairing-ctw"])
def test_edges_matching_optimum_is_the_model_optimum(key, tmp_path):
    model = model_of(key)
    assert isinstance(model, PairingModel)
    text = write_model(model, tmp_path / "m.edges", "edges").read_text()
    _, edges = _parse_edges(text)
    g = nx.Graph()
    g.add_weighted_edges_from(edges)
    ctw = model.objective == "cardinality_then_weight"
    matching = nx.max_weight_matching(g, maxcardinality=ctw)
    assert sum(g[a][b]["weight"] for a, b in matching) == optimum_of(key)
    if ctw:
        assert f"c the largest number of pairs of any matching is {len(matching)}\n" in text


# ------------------------------------------------------------------ determinism and errors
@pytest.mark.parametrize("key", KEYS)
def test_same_model_same_bytes(key, tmp_path):
    model = model_of(key)
    twin = load_instance(EXAMPLES / f"{key}.npz")[0] if key not in SYNTHETIC else SYNTHETIC[key]()
    for fmt in export_formats(model):
        first = write_model(model, tmp_path / f"a.{fmt}", fmt).read_bytes()
        assert write_model(model, tmp_path / f"b.{fmt}", fmt).read_bytes() == first
        assert write_model(twin, tmp_path / f"c.{fmt}", fmt).read_bytes() == first
        assert first.startswith(b"* " if fmt == "mps" else b"\\ " if fmt == "lp" else b"c ")


@pytest.mark.parametrize(
    ("key", "fmt", "message"),
    [
        ("synthetic-assignment", "xyz", "export format 'xyz' unknown; expected one of mps, lp, asn, edges"),
        ("synthetic-assignment", "MPS", "export format 'MPS' unknown"),
        ("synthetic-assignment", None, "export format None unknown"),
        ("synthetic-assignment", "edges", "(assignment) cannot be written as edges; its formats are mps, lp, asn"),
        ("synthetic-trip-packing", "asn", "(trip_packing) cannot be written as asn; its formats are mps, lp"),
        ("synthetic-pairing-ctw", "asn", "(pairing) cannot be written as asn; its formats are mps, lp, edges"),
    ],
)
def test_bad_format_is_one_line_parameter_error(key, fmt, message, tmp_path):
    with pytest.raises(ParameterError) as err:
        write_model(model_of(key), tmp_path / "m.out", fmt)
    assert message in str(err.value)
    assert "\n" not in str(err.value)
    assert not (tmp_path / "m.out").exists()


def test_not_a_model_is_a_parameter_error():
    with pytest.raises(ParameterError, match="cannot export a dict"):
        export_formats({})  # type: ignore[arg-type]


def test_unwritable_path_raises_oserror(tmp_path):
    with pytest.raises(FileNotFoundError):
        write_model(model_of("synthetic-assignment"), tmp_path / "missing" / "m.mps", "mps")
