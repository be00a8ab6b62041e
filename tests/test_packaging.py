"""What a non-editable install ships: every package of the tree, the presets of solvers/ as ``rpbench.presets``.

pyproject.toml lists the packages by name, because setuptools' discovery finds packages by their folders'
names and misses ``rpbench.presets``, which package-dir maps to the top-level solvers/ folder: a wheel built
from the discovered list had no presets, and ``--solver highs`` then found none.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
import zipfile
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def _tree_packages() -> set[str]:
    """The packages of the source tree: every folder under rpbench/ with an ``__init__.py``."""
    return {".".join(init.parent.relative_to(ROOT).parts) for init in (ROOT / "rpbench").rglob("__init__.py")}


def test_listed_packages_are_the_tree_and_the_presets() -> None:
    assert set(SETUPTOOLS["packages"]) == _tree_packages() | {"rpbench.presets"}
    assert len(SETUPTOOLS["packages"]) == len(set(SETUPTOOLS["packages"]))


def test_presets_package_maps_to_the_solvers_folder() -> None:
    folder = ROOT / SETUPTOOLS["package-dir"]["rpbench.presets"]
    assert folder == ROOT / "solvers"
    assert (folder / "highs.toml").is_file()
    assert SETUPTOOLS["package-data"]["rpbench.presets"] == ["*.toml"]


def test_package_data_belongs_to_listed_packages() -> None:
    assert set(SETUPTOOLS["package-data"]) <= set(SETUPTOOLS["packages"])


def _setuptools_builds_wheels() -> bool:
    """setuptools 70.1+ builds a wheel by itself, offline; an older one in the test environment cannot
    read this pyproject.toml (tests never download a newer one)."""
    try:
        version = metadata.version("setuptools")
    except metadata.PackageNotFoundError:
        return False
    parts = tuple(int(p) for p in version.split(".")[:2] if p.isdigit())
    return parts >= (70, 1)


@pytest.mark.slow
@pytest.mark.skipif(not _setuptools_builds_wheels(), reason="needs setuptools >= 70.1 in the test environment")
def test_wheel_ships_the_presets(tmp_path: Path) -> None:
    # A copy of the sources, so that the build writes nothing into the checkout.
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    for name in ("rpbench", "solvers"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    out = tmp_path / "wheel"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-q"]
        + ["-w", str(out), str(src)],
        check=True,
        capture_output=True,
    )
    (wheel,) = out.glob("rpbench-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    presets = {f"rpbench/presets/{p.name}" for p in (ROOT / "solvers").glob("*.toml")}
    assert presets and presets <= names
    packages = {name.rsplit("/", 1)[0].replace("/", ".") for name in names if name.endswith("/__init__.py")}
    assert packages == _tree_packages()
