"""Bad input gets one clear error: unknown preset, malformed TOML, missing library, bad options."""

from __future__ import annotations

import importlib.util

import pytest

from rpbench.backends import BACKEND_REGISTRY, SolveOptions, backend_class, get_backend
from rpbench.backends import base as backends_base
from rpbench.backends.highs import HighsBackend
from rpbench.backends.presets import load_preset, parse_preset
from rpbench.exceptions import PresetError, RpbenchError, SolverError, SolverNotInstalledError
from rpbench.model import AssignmentModel, PairingModel

ASSIGN = AssignmentModel(1, 1, [0, 0], [0, -1], [-1, -2])
PAIR = PairingModel(3, [0, 1], [1, 2], [2, 3])


def test_unknown_preset_names_the_available_ones():
    with pytest.raises(PresetError, match="unknown solver preset 'nope'.*highs"):
        load_preset("nope")


def test_unknown_backend_is_a_preset_error():
    with pytest.raises(PresetError, match="unknown backend"):
        backend_class("gurobi")


@pytest.mark.parametrize(
    "text, match",
    [
        ("backend = ", "not valid TOML"),
        ('backend = "highs"\ncolour = 1', "unknown key"),
        ('backend = "cplex"', "is not one of"),
        ('backend = "highs"\n[options]\nthreads = "two"', "must be of type int"),
        ('backend = "highs"\n[options]\ntime_limit_s = -1', "must be > 0"),
        ('backend = "highs"\n[options]\nmip_rel_gap = -0.1', "mip_rel_gap must be >= 0"),
        ('backend = "highs"\n[options]\ngap = 0.1', "unknown option"),
    ],
)
def test_malformed_preset_toml(text, match):
    with pytest.raises(PresetError, match=match):
        parse_preset("bad", text, "bad.toml")


def test_malformed_preset_file_on_disk(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("backend = [")
    with pytest.raises(PresetError, match="not valid TOML"):
        load_preset(str(path))
    with pytest.raises(PresetError, match="does not exist"):
        load_preset(str(tmp_path / "missing.toml"))


@pytest.mark.parametrize("name", sorted(BACKEND_REGISTRY))
def test_missing_solver_library_is_reported_by_name(name, monkeypatch):
    cls = backend_class(name)
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda mod, *a: None if mod == cls.requires[0] else real(mod, *a))
    monkeypatch.setattr(backends_base, "_FOUND", set())  # as in a process where it was never found
    # [0]: with an optional extra absent (blossom), its other libraries are missing too
    assert not cls.is_installed() and cls.missing_libraries()[0] == cls.requires[0]
    with pytest.raises(SolverNotInstalledError, match=f"needs the Python package.*{cls.requires[0]}.*--solver"):
        get_backend(name)
    with pytest.raises(SolverNotInstalledError):
        cls().solve(PAIR, SolveOptions())  # solving checks too, not only get_backend


def test_missing_library_via_requires(monkeypatch):
    monkeypatch.setattr(HighsBackend, "requires", ("highspy", "no_such_solver_lib"))
    with pytest.raises(SolverNotInstalledError, match="no_such_solver_lib"):
        get_backend("highs")


def test_errors_are_rpbench_errors_for_the_cli():
    assert issubclass(SolverNotInstalledError, RpbenchError) and issubclass(SolverError, RpbenchError)


def test_unknown_method_is_a_solver_error():
    """A method the backend does not offer is one SolverError naming it."""
    with pytest.raises(SolverError, match="method 'simplex' unknown"):
        get_backend("highs").solve(ASSIGN, SolveOptions(method="simplex"))


def test_unknown_ortools_method_is_a_solver_error():
    """The same for OR-Tools (the backends extra)."""
    pytest.importorskip("ortools")
    with pytest.raises(SolverError, match="method 'lp' unknown"):
        get_backend("ortools").solve(ASSIGN, SolveOptions(method="lp"))


def test_unknown_highs_option_is_a_solver_error():
    with pytest.raises(SolverError, match="HiGHS rejected option no_such_option"):
        get_backend("highs").solve(PAIR, SolveOptions(extra={"no_such_option": 1}))


def test_unknown_cvxpy_solver_is_not_installed():
    pytest.importorskip("cvxpy")
    with pytest.raises(SolverNotInstalledError, match="CVXPY solver 'NOPE'"):
        get_backend("cvxpy").solve(PAIR, SolveOptions(solver="nope"))


def test_unknown_pyomo_solver_is_not_installed():
    pytest.importorskip("pyomo")
    with pytest.raises(SolverNotInstalledError, match="Pyomo solver 'no_such_solver'"):
        get_backend("pyomo").solve(PAIR, SolveOptions(solver="no_such_solver"))


def test_every_backend_declares_what_it_needs():
    for name in BACKEND_REGISTRY:
        cls = backend_class(name)
        assert cls.name == name and cls.requires and cls.exact and cls.description


def test_a_library_found_once_is_not_looked_for_again(monkeypatch):
    monkeypatch.setattr(backends_base, "_FOUND", set())
    looked = []
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda mod, *a: looked.append(mod) or real(mod, *a))
    for _ in range(3):
        HighsBackend.ensure_installed()
    assert looked == ["highspy"]
    monkeypatch.setattr(HighsBackend, "requires", ("highspy", "no_such_solver_lib"))
    for _ in range(2):  # a missing library is looked for at every check: it may be installed meanwhile
        assert HighsBackend.missing_libraries() == ["no_such_solver_lib"]
    assert looked == ["highspy", "no_such_solver_lib", "no_such_solver_lib"]
