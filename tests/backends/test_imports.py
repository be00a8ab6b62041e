"""Solver libraries load lazily, and all of them load together in one process.

highspy 1.15 ships ``libhighs.so.1``, the soname of the HiGHS bundled in
OR-Tools 9.15, and importing both then fails (in either order); pyproject
pins highspy < 1.15.  These tests run in fresh interpreters so the import
order is the one under test.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import textwrap

import pytest

SOLVER_LIBS = ("highspy", "ortools", "pyomo", "cvxpy", "pymatching", "lap")
#: The optional ``blossom`` extra: cppyy's JIT and libOGDF (which bundles COIN-OR Clp) in the same process.
BLOSSOM_LIBS = ("cppyy", "ogdf_python")
HAS_BLOSSOM = all(importlib.util.find_spec(m) is not None for m in BLOSSOM_LIBS)
#: The libraries installed here: the optional extras (backends, blossom) may be missing.
LOADED = tuple(m for m in SOLVER_LIBS if importlib.util.find_spec(m) is not None) + (
    BLOSSOM_LIBS if HAS_BLOSSOM else ()
)


def run_python(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout


def test_importing_rpbench_loads_no_solver():
    out = run_python(f"""
        import sys
        import rpbench, rpbench.backends, rpbench.model, rpbench.bench.synthetic, rpbench.bench.runner
        from rpbench.backends import BACKEND_REGISTRY, backend_class
        for name in BACKEND_REGISTRY:
            backend_class(name).is_installed()       # the adapter modules import, their solvers do not
        print(sorted(m for m in {SOLVER_LIBS + BLOSSOM_LIBS!r} if m in sys.modules))
    """)
    assert out.strip() == "[]"


@pytest.mark.parametrize("order", [LOADED, tuple(reversed(LOADED))], ids=["highspy-first", "highspy-last"])
@pytest.mark.slow
def test_every_solver_library_loads_and_solves_in_one_process(order):
    imports = {
        "highspy": "import highspy",
        "ortools": "import ortools.sat.python.cp_model, ortools.graph.python.min_cost_flow, "
        "ortools.linear_solver.pywraplp",
        "pyomo": "import pyomo.environ",
        "cvxpy": "import cvxpy",
        "pymatching": "import pymatching",
        "lap": "import lap",
        "cppyy": "import cppyy",
        "ogdf_python": "from ogdf_python import ogdf",
    }
    out = run_python(
        "\n".join(imports[m] for m in order)
        + """
from rpbench.backends import get_backend
from rpbench.model import PairingModel, AssignmentModel
from rpbench.backends.presets import load_preset, preset_names
pair = PairingModel(4, [0, 1, 2], [1, 2, 3], [1, 10, 1], objective="cardinality_then_weight")
assign = AssignmentModel(2, 1, [0, 0, 1, 1], [0, -1, 0, -1], [-3, -10, -4, -5])
for name in preset_names():
    p = load_preset(name)
    if not p.is_installed():
        continue
    b = get_backend(p.backend)
    print(name, b.solve(pair, p.options).objective, b.solve(assign, p.options).objective)
"""
    )
    lines = out.strip().splitlines()
    from rpbench.backends.presets import load_preset, preset_names

    installed = [n for n in preset_names() if load_preset(n).is_installed()]
    assert [line.split()[0] for line in lines] == installed, out  # every installed preset solved
    assert all(line.split()[1:] == ["2.0", "-8.0"] for line in lines), out
