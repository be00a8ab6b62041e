"""Instance files for command-line solvers: MPS, LP, DIMACS assignment and a weighted edge list.

:func:`write_model` writes one model; the output is a pure function of the model (same model, same
bytes).  Every file opens with comment lines giving its provenance (model name, structure, ``unit_m``)
and what its optimum means.  All numbers in the files are the model's integer ``values`` (units of
``unit_m`` metres), written exactly.

* ``mps``, ``lp`` (every structure): the 0/1 program rpbench's HiGHS backend solves, built by the
  backends' own :func:`rpbench.backends._common.program` and written by HiGHS (``Highs.passModel``,
  ``writeModel``).  Sense MAX, objective ``Σ values[c] · x[c]``, every column binary.  Columns
  ``c0..c{n-1}`` are the model's columns in order; the rows are the model's, in order: ``p{i}``
  (passenger, ``= 1``) and ``v{j}`` (vehicle, ``<= 1``) for the assignment, ``r{i}`` (request, ``<= 1``)
  and ``v{j}`` for trip packing, ``o{i}`` (order, ``<= 1``) for pairing.  The file's optimum equals the
  model's optimum in model units.  Oracle-2 (``cardinality_then_weight``) is written as the backend's second stage (see
  :mod:`rpbench.backends._milp`): one more row ``card``, ``Σ x >= k*``, where ``k*`` is the maximum
  number of pairs, found by Edmonds' algorithm and certified by a Tutte-Berge set
  (:mod:`rpbench.backends.cardinality`).  *Proof*: no matching has more than ``k*`` pairs, so the
  feasible solutions of the file are exactly the maximum-cardinality matchings, and its optimum is the
  largest value among them — the lexicographic (cardinality, then weight) optimum, in model units.  No
  combined weight ``M · |x| + value`` is used: with ``M > Σ|values|`` it leaves float64's exact integers
  (and the 15 digits HiGHS writes) on full-day models.  HiGHS prints 15 significant digits, so
  values beyond ``10**15`` in magnitude are refused rather than rounded.
* ``asn`` (assignment models): the DIMACS assignment format (first DIMACS implementation challenge):
  ``p asn NODES ARCS``, ``n ID`` for each node of the source side, ``a SRC DST COST`` per arc, node ids
  from 1.  The DIMACS problem is a minimum-cost *perfect* assignment: every node, on either side,
  matched exactly once.  See :func:`asn_text` for the construction and its proof; its optimum is
  ``-(model optimum)``, and no perfect assignment exists exactly when the model is infeasible.
* ``edges`` (pairing models): ``p edge N M`` (N orders, M candidate pairs, as DIMACS graph files),
  then ``e A B W`` per column in column order — orders ``A < B`` numbered from 1, ``W`` the pair's
  integer value.  The problem (stated in the comments) is a maximum-weight matching for ``weight``
  and a maximum-cardinality matching of maximum weight for ``cardinality_then_weight`` (the comments
  also give ``k*``); its optimum is the model's optimum, not negated.

An unknown format, or one the model's structure cannot be written in, is a :class:`ParameterError`.
Files are written with :meth:`pathlib.Path.write_bytes`: an unwritable path raises its ``OSError``
(``PermissionError``, ``FileNotFoundError`` for a missing folder...) for the caller to handle.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import numpy as np

from rpbench.backends._common import Program, program
from rpbench.backends.cardinality import maximum_cardinality_matching
from rpbench.exceptions import ParameterError, SolverError
from rpbench.model import AssignmentModel, Model, PairingModel, TripPackingModel

FORMATS = ("mps", "lp", "asn", "edges")
#: Largest |value| HiGHS's MPS and LP writers print exactly (they print 15 significant digits).
MAX_WRITTEN_VALUE = 1e15
#: Comment prefix of each format.
_COMMENT = {"mps": "* ", "lp": "\\ ", "asn": "c ", "edges": "c "}


def export_formats(model: Model) -> tuple[str, ...]:
    """The formats ``model`` can be written in, in :data:`FORMATS` order."""
    if isinstance(model, AssignmentModel):
        return ("mps", "lp", "asn")
    if isinstance(model, PairingModel):
        return ("mps", "lp", "edges")
    if isinstance(model, TripPackingModel):
        return ("mps", "lp")
    raise ParameterError(f"cannot export a {type(model).__name__}: expected an rpbench model (rpbench.model)")


def write_model(model: Model, path: str | os.PathLike[str], fmt: str) -> Path:
    """Write ``model`` to ``path`` in format ``fmt`` (one of :data:`FORMATS`); returns the path.

    The suffix of ``path`` is not checked.  OSError from writing is the caller's to handle.
    """
    if not isinstance(fmt, str) or fmt not in FORMATS:
        raise ParameterError(f"export format {fmt!r} unknown; expected one of {', '.join(FORMATS)}")
    allowed = export_formats(model)
    if fmt not in allowed:
        raise ParameterError(
            f"model {model.name!r} ({model.structure.value}) cannot be written as {fmt}; "
            f"its formats are {', '.join(allowed)}"
        )
    if fmt in ("mps", "lp"):
        data = program_text(model, fmt)
    elif isinstance(model, AssignmentModel):  # fmt is asn
        data = asn_text(model)
    else:  # edges, for a pairing model
        assert isinstance(model, PairingModel)
        data = edges_text(model)
    out = Path(path)
    out.write_bytes(data.encode("ascii"))
    return out


# ------------------------------------------------------------------ provenance
def _header(model: Model, fmt: str, lines: list[str]) -> str:
    """Comment lines: provenance, then ``lines`` (what the file's numbers and optimum mean)."""
    size = model.size
    first = [
        f"rpbench decision model, format {fmt} (written by rpbench.library.export)",
        f"model {model.name!a}, structure {model.structure.value}"
        + (f", objective {model.objective}" if isinstance(model, PairingModel) else ""),
        f"unit_m {model.unit_m!r}: every number is an integer model value in units of unit_m metres",
        f"model size: {size['rows']} rows, {size['cols']} columns, {size['nonzeros']} nonzeros",
    ]
    prefix = _COMMENT[fmt]
    return "".join(f"{prefix}{line}\n" for line in first + lines)


def _int_values(model: Model) -> list[int]:
    """The values as Python ints (exact: the model holds whole numbers with Σ|values| <= 2**53)."""
    return model.values.astype(np.int64).tolist()


# ------------------------------------------------------------------ MPS and LP
def _max_pairs(model: PairingModel) -> int:
    """``k*``, the largest number of pairs of any matching (Edmonds' algorithm, Tutte-Berge certified)."""
    a, b = model.col_a.astype(np.int64), model.col_b.astype(np.int64)
    return maximum_cardinality_matching(model.n_orders, a, b).size


def _model_program(model: Model) -> tuple[Program, list[str]]:
    """The 0/1 program the HiGHS backend solves for ``model`` and its row names.

    Oracle-2 is the backend's second stage: the extra row ``card`` (``Σ x >= k*``) comes last.
    """
    if isinstance(model, AssignmentModel):
        names = [f"p{i}" for i in range(model.n_passengers)] + [f"v{j}" for j in range(model.n_vehicles)]
    elif isinstance(model, TripPackingModel):
        names = [f"r{i}" for i in range(model.n_requests)] + [f"v{j}" for j in range(model.n_vehicles)]
    else:
        names = [f"o{i}" for i in range(model.n_orders)]
        if model.objective == "cardinality_then_weight":
            return program(model, min_count=_max_pairs(model)), [*names, "card"]
    return program(model), names


def _program_lines(model: Model, prog: Program) -> list[str]:
    rows = {
        AssignmentModel: "rows p{i} passengers (= 1), then v{j} vehicles (<= 1)",
        TripPackingModel: "rows r{i} requests (<= 1), then v{j} vehicles (<= 1)",
        PairingModel: "rows o{i} orders (<= 1)",
    }[type(model)]
    lines = [
        f"columns c0..c{model.n_cols - 1}: the model's columns in order, all binary",
        rows,
        "objective: maximise the total value of the chosen columns",
        "the file's optimum equals the model's optimum, in model units",
    ]
    if isinstance(model, PairingModel) and model.objective == "cardinality_then_weight":
        lines += [
            f"row card: sum of all x >= {int(prog.lo[-1])}, the largest number of pairs of any matching",
            "(Edmonds' algorithm, Tutte-Berge certified): every feasible solution is a maximum matching,",
            "so the optimum is the largest value of a maximum matching (cardinality first, then weight)",
        ]
    return lines


def _mps_name(name: str) -> str:
    """The model name as one MPS token (readers split the NAME line on blanks)."""
    return re.sub(r"[^A-Za-z0-9_.\-]", "_", name) or "rpbench"


def program_text(model: Model, fmt: str) -> str:
    """``model`` as MPS (``fmt="mps"``) or CPLEX LP (``"lp"``) text, written by HiGHS."""
    import highspy

    big = np.abs(model.values) > MAX_WRITTEN_VALUE
    if big.any():
        c = int(np.flatnonzero(big)[0])
        raise ParameterError(
            f"model {model.name!r}: value {float(model.values[c]):.17g} of column {c} has more digits than "
            f"HiGHS writes to {fmt} files (|value| <= 1e15); export a coarser unit_m"
        )
    prog, row_names = _model_program(model)
    n, m = prog.n, prog.n_rows
    lp = highspy.HighsLp()
    lp.model_name_ = _mps_name(model.name)
    lp.num_col_, lp.num_row_ = n, m
    lp.sense_ = highspy.ObjSense.kMaximize
    lp.offset_ = 0.0
    lp.col_cost_ = prog.c
    lp.col_lower_, lp.col_upper_ = np.zeros(n), np.ones(n)
    lp.row_lower_ = np.where(np.isfinite(prog.lo), prog.lo, -highspy.kHighsInf)
    lp.row_upper_ = np.where(np.isfinite(prog.hi), prog.hi, highspy.kHighsInf)
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.num_col_, lp.a_matrix_.num_row_ = n, m
    lp.a_matrix_.start_ = prog.indptr.astype(np.int32)
    lp.a_matrix_.index_ = prog.indices.astype(np.int32)
    lp.a_matrix_.value_ = np.ones(len(prog.indices))
    lp.integrality_ = [highspy.HighsVarType.kInteger] * n
    lp.col_names_ = [f"c{c}" for c in range(n)]
    lp.row_names_ = row_names
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    if h.passModel(lp).name == "kError":
        raise SolverError(f"HiGHS rejected the program of {model.name!r} (passModel returned kError)")
    # HiGHS picks its writer from the suffix, and would report an unwritable path only as kError: it
    # writes to a private folder, and the caller's path is written by Python (OSError as documented).
    with tempfile.TemporaryDirectory(prefix="rpbench-export-") as tmp:
        file = Path(tmp) / f"model.{fmt}"
        if h.writeModel(str(file)).name == "kError":  # kWarning: an empty model
            raise SolverError(f"HiGHS could not write the program of {model.name!r} as {fmt}")
        body = file.read_text(encoding="ascii")
    return _header(model, fmt, _program_lines(model, prog)) + body


def read_mps_optimum(path: str | os.PathLike[str]) -> float:
    """Read an MPS (or, by its suffix, LP) file with HiGHS, solve it to optimality, return the objective.

    The objective is recomputed from the file's costs at the rounded optimal solution, so integral
    costs give the exact optimum; an empty model gives 0.  A file HiGHS cannot read, or a solve that
    ends other than optimal (infeasible, say), is a :class:`SolverError`.
    """
    import highspy

    h = highspy.Highs()
    for key, value in (("output_flag", False), ("random_seed", 0), ("mip_rel_gap", 0.0), ("threads", 1)):
        h.setOptionValue(key, value)
    if h.readModel(str(path)).name == "kError":
        raise SolverError(f"HiGHS could not read {os.fspath(path)!r} as a model file")
    h.run()
    status = h.getModelStatus()
    lp = h.getLp()
    if status == highspy.HighsModelStatus.kModelEmpty:
        return float(lp.offset_)
    if status != highspy.HighsModelStatus.kOptimal:
        raise SolverError(f"HiGHS ended {os.fspath(path)!r} with status {status.name}, not optimal")
    x = np.asarray(h.getSolution().col_value, dtype=np.float64)
    kinds = list(lp.integrality_)  # empty for a file without integer columns
    if kinds:
        integral = np.array([k == highspy.HighsVarType.kInteger for k in kinds], dtype=bool)
        x[integral] = np.round(x[integral])
    return float(np.dot(np.asarray(lp.col_cost_, dtype=np.float64), x) + lp.offset_)


# ------------------------------------------------------------------ DIMACS assignment
def asn_text(model: AssignmentModel) -> str:
    """The assignment model as a DIMACS minimum-cost perfect assignment (``p asn``) file.

    With ``P`` passengers and ``V`` vehicles there are ``2(P + V)`` nodes, numbered

    * sources (``n`` lines): passengers ``1..P``, then one *idle* node ``u_v`` per vehicle ``P+1..P+V``;
    * sinks: vehicles ``P+V+1..P+2V``, then one *keep-waiting* node ``w_p`` per passenger
      ``P+2V+1..2P+2V``;

    and the arcs, in this order:

    1. one arc per model column, in column order (arc ``k`` is column ``k - 1``): ``(p, v)`` for a
       ride, ``(p, w_p)`` for keep waiting, of cost ``-value``;
    2. ``(u_v, v)`` of cost 0 per vehicle (the vehicle stays unassigned);
    3. ``(u_v, w_p)`` of cost 0 per ride column ``(p, v)``, in column order (``u_v`` takes the
       keep-waiting node of ``p``, left free when ``p`` rides ``v``).

    No arc is repeated (the model's columns are distinct).  Costs are exact integers of any size;
    codes that read 32-bit costs need ``|value| < 2**31`` (millimetre models reach 10^9).

    *Claim*: the minimum cost of a perfect assignment is ``-(model optimum)``, and there is none
    exactly when the model is infeasible.  *Proof*.  (a) A feasible model solution gives a perfect
    assignment of cost ``-(its value)``: take its columns' arcs; for each vehicle ``v`` ridden by ``p``
    add ``(u_v, w_p)``, for each idle vehicle ``(u_v, v)``.  Every passenger has one arc (its column);
    ``u_v`` one (``v`` is ridden or idle); a vehicle is covered by its rider or by ``u_v``; ``w_p`` by
    ``p`` if ``p`` waits, else by ``u_v`` of the vehicle ``p`` rides — each exactly once; the added
    arcs cost 0.  (b) A perfect assignment gives a feasible model solution of value ``-(its cost)``:
    each passenger node has exactly one arc, an arc of part 1, i.e. one model column; each vehicle
    node is covered once, so at most one passenger rides it; the arcs of parts 2 and 3 cost 0.  So
    the two optima are each other's negatives, and one problem is feasible exactly when the other is.
    """
    P, V = model.n_passengers, model.n_vehicles
    p = model.col_passenger.astype(np.int64) + 1
    v = model.col_vehicle.astype(np.int64)
    ride = v >= 0
    sink = np.where(ride, P + V + 1 + v, P + 2 * V + p)
    src = np.concatenate([p, P + 1 + np.arange(V), P + 1 + v[ride]])
    dst = np.concatenate([sink, P + V + 1 + np.arange(V), P + 2 * V + p[ride]])
    cost = [-value for value in _int_values(model)] + [0] * (V + int(ride.sum()))
    lines = [
        f"sources (n lines): 1..{P} passengers, {P + 1}..{P + V} vehicle-idle nodes",
        f"sinks: {P + V + 1}..{P + 2 * V} vehicles, {P + 2 * V + 1}..{2 * (P + V)} keep-waiting node of each passenger",
        f"arcs 1..{model.n_cols}: the model's columns in order, cost = -value",
        "then, cost 0: vehicle-idle node -> its vehicle, one per vehicle;",
        "and vehicle-idle node of v -> keep-waiting node of p, one per ride column (p, v)",
        "problem: minimum-cost perfect assignment (every node matched exactly once)",
        "its optimum equals -(model optimum): the costs are negated values",
    ]
    body = [
        _header(model, "asn", lines),
        f"p asn {2 * (P + V)} {len(src)}\n",
        "".join(f"n {i}\n" for i in range(1, P + V + 1)),
        "".join(f"a {s} {d} {c}\n" for s, d, c in zip(src.tolist(), dst.tolist(), cost, strict=True)),
    ]
    return "".join(body)


# ------------------------------------------------------------------ weighted edge list
def edges_text(model: PairingModel) -> str:
    """The pairing model as a weighted edge list: ``p edge N M``, then ``e A B W`` per column."""
    lines = [
        f"nodes 1..{model.n_orders}: orders 0..{model.n_orders - 1}",
        f"edge k = 1..{model.n_cols}: model column k-1, as e A B W with A < B and W its integer value",
    ]
    if model.objective == "cardinality_then_weight":
        lines += [
            "problem: maximum-cardinality matching of maximum weight (most pairs, then largest total W)",
            f"the largest number of pairs of any matching is {_max_pairs(model)}",
        ]
    else:
        lines.append("problem: maximum-weight matching (any number of pairs)")
    lines.append("its optimum (total W) equals the model's optimum, in model units")
    a = (model.col_a.astype(np.int64) + 1).tolist()
    b = (model.col_b.astype(np.int64) + 1).tolist()
    edges = "".join(f"e {x} {y} {w}\n" for x, y, w in zip(a, b, _int_values(model), strict=True))
    return _header(model, "edges", lines) + f"p edge {model.n_orders} {model.n_cols}\n" + edges
