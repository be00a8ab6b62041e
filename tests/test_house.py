"""The house holds its shape: the floors of pyproject.toml's import contracts (an upward or circular import
fails them), one definition per public name, a light public face, and a package map in the docs that
lists every room in the contracts' order."""

from __future__ import annotations

import ast
import importlib
import re
import shutil
import subprocess
import sys
import tomllib
from collections import defaultdict
from pathlib import Path

import pytest

import rpbench

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "rpbench"
#: Module-level protocols, one name in every module of a family: each command module registers its subcommand
#: with ``register``; each solver backend maps its solver's statuses to rpbench's with ``STATUS`` (as CVXPY's
#: solver layer does).
PROTOCOLS = {"register": "rpbench/commands/", "STATUS": "rpbench/backends/"}


def lint_imports(tree: Path) -> subprocess.CompletedProcess[str]:
    """import-linter's verdict on the ``rpbench`` package under ``tree``, against pyproject.toml's contracts."""
    return subprocess.run(
        [sys.executable, "-c", "from importlinter.cli import lint_imports_command; lint_imports_command()"]
        + ["--config", str(ROOT / "pyproject.toml"), "--no-cache"],
        cwd=tree,
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=300,
    )


def copy_of_package(tmp_path: Path) -> Path:
    shutil.copytree(PACKAGE, tmp_path / "rpbench", ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path


def test_every_import_runs_down_the_floors():
    result = lint_imports(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Contracts: 2 kept, 0 broken." in result.stdout


def test_an_upward_import_breaks_the_floors(tmp_path):
    tree = copy_of_package(tmp_path)
    with (tree / "rpbench" / "results" / "metrics.py").open("a") as fh:
        fh.write("\n\ndef _up():\n    import rpbench.harness.comparison  # a function-level import counts too\n")
    result = lint_imports(tree)
    assert result.returncode == 1
    assert "rpbench.results is not allowed to import rpbench.harness" in result.stdout
    assert "rpbench.results.metrics -> rpbench.harness.comparison" in result.stdout


def test_a_circle_inside_a_package_breaks_the_contracts(tmp_path):
    tree = copy_of_package(tmp_path)
    with (tree / "rpbench" / "check" / "core.py").open("a") as fh:
        fh.write("\nimport rpbench.check.kpis\n")
    result = lint_imports(tree)
    assert result.returncode == 1
    assert "No cycles are allowed in rpbench.check" in result.stdout


def public_definitions() -> dict[str, list[str]]:
    """Every public top-level name defined (not imported) in a module of the package, with its modules."""
    found: dict[str, list[str]] = defaultdict(list)
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names = [node.name]
            elif isinstance(node, ast.Assign):
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                names = [node.target.id]
            else:
                continue
            for name in names:
                if not name.startswith("_"):
                    found[name].append(path.relative_to(ROOT).as_posix())
    return found


def test_no_public_name_is_defined_in_two_modules():
    twice = {
        name: where
        for name, where in public_definitions().items()
        if len(where) > 1 and not (name in PROTOCOLS and all(w.startswith(PROTOCOLS[name]) for w in where))
    }
    assert twice == {}


def test_the_face_names_each_name_once_and_every_name_resolves():
    tree = ast.parse((PACKAGE / "__init__.py").read_text())
    typed = {
        alias.asname: node.module
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.module != "rpbench.version" and node.module != "__future__"
        for alias in node.names
        if alias.asname
    }
    assert typed == rpbench._FACE  # the TYPE_CHECKING block and the table list the same names
    for name, module in rpbench._FACE.items():
        assert getattr(rpbench, name) is getattr(importlib.import_module(module), name)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        _ = rpbench.no_such_name


def test_importing_the_package_loads_none_of_it():
    code = "import sys, rpbench; print(sorted(m for m in sys.modules if m.startswith('rpbench')))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert loaded.strip() == "['rpbench', 'rpbench.version']"


def rooms() -> list[str]:
    """The package's rooms: its subpackages and the modules directly in it."""
    return sorted(
        p.name if p.is_dir() else p.stem
        for p in PACKAGE.iterdir()
        if (p.is_dir() and (p / "__init__.py").is_file()) or (p.suffix == ".py" and p.stem != "__init__")
    )


def test_the_floors_hold_every_room_and_the_docs_map_lists_them_in_order():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]
    (layers,) = [c["layers"] for c in config if c["type"] == "layers"]
    floors = [[r.strip() for r in re.split(r"[|:]", floor)] for floor in layers]
    assert sorted(r for floor in floors for r in floor) == rooms()
    text = (ROOT / "docs" / "extending.md").read_text()
    section = text[text.index("## Where things live") :]
    listed = re.findall(r"^  ([a-z_]+)(?:/|\.py)", section, flags=re.M)
    assert listed == [r for floor in floors for r in floor]
