"""Clean results folders for the checker's tests, built once per test module and tampered with in copies.

A test that needs one of the six-run toy folders (each runs the forward-looking strategy, the bound and both
oracles: seconds apiece) is marked slow, so that ``pytest -m "not slow"`` keeps a quick subset of the checker's
tests (the three-run ``clean_run`` folder and the unit tests).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from check.tamper import build, copy
from rpbench.harness.comparison import run_comparison
from rpbench.harness.evaluate import run_evaluation
from rpbench.protocols import load_protocol
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

_HERE = Path(__file__).parent
#: A protocol whose strongest run read the future.
SEERS_PROTOCOL = """
name = "seers"
version = 1
scenario = "toy"
sample = 0.1
seeds = [0, 1]
strategies = ["mb", "hindsight", "bound"]
metrics = ["total_saving_km", "competitive_ratio_bound"]
[bootstrap]
resamples = 50
"""

#: The fixtures (here and in the test modules) that build a six-run toy folder or a folder of several of them.
SLOW_FOLDERS = {"base", "enroute", "zero_pairs", "zero_served", "empty_hour", "sweep", "multiday", "seers", "ranked"}


def pytest_collection_modifyitems(config, items):
    for item in items:
        if _HERE in Path(str(item.fspath)).parents and SLOW_FOLDERS & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """The clean folder: each kind of run rpbench writes (mb, rtv, fl, bound, oracle1, oracle2)."""
    return build(tmp_path_factory.mktemp("clean") / "toy")


@pytest.fixture(scope="module")
def enroute(tmp_path_factory) -> Path:
    """Oracles with en-route pairs (the second order joins the first one's ride), both pick-up orders and
    the pick-up test: every branch of the oracle rules."""
    return build(
        tmp_path_factory.mktemp("enroute") / "toy",
        ["mb", "oracle1", "oracle2"],
        sample=0.5,
        seed=1,
        run_options={
            "oracle1": {"allow_enroute": "true", "both_pickup_orders": "true"},
            "oracle2": {"allow_enroute": "true", "pickup_check": "true"},
        },
    )


@pytest.fixture(scope="module")
def seers(tmp_path_factory) -> Path:
    """Online and clairvoyant runs beside the bound and Oracle-1: hindsight (clairvoyant by its class) and FL
    counting the day's own orders (clairvoyant under its options), whose best saving is LB."""
    return build(
        tmp_path_factory.mktemp("seers") / "toy",
        ["mb", "hindsight", "fl", "bound", "oracle1"],
        run_options={"fl": {"rates": "scenario"}},
    )


@pytest.fixture(scope="module")
def ranked(tmp_path_factory) -> Path:
    """An evaluation of two toy seeds with a clairvoyant run (hindsight), ranked apart after the online one."""
    path = tmp_path_factory.mktemp("protocol") / "seers.toml"
    path.write_text(SEERS_PROTOCOL)
    folder = run_evaluation(load_protocol(str(path)), tmp_path_factory.mktemp("ranked") / "eval", workers=1).folder
    return folder


@pytest.fixture
def folder(base, tmp_path) -> Path:
    """A copy of the clean folder, to tamper with."""
    return copy(base, tmp_path)


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory) -> Path:
    """A small clean folder (mb, rtv, oracle1: no prediction, no bound), quick to build."""
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=3), ["mb", "rtv", "oracle1"])
    folder = run_comparison(spec, tmp_path_factory.mktemp("runs") / "clean", progress=False).folder
    return folder


@pytest.fixture
def clean_copy(clean_run, tmp_path) -> Path:
    """A copy of the small clean folder, to tamper with."""
    target = tmp_path / "run"
    shutil.copytree(clean_run, target)
    return target
