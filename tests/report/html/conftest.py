"""A toy comparison folder (simulated and offline runs) whose report.html the tests read."""

from __future__ import annotations

import pytest

from rpbench.harness.comparison import run_comparison
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


@pytest.fixture(scope="package")
def toy_run(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.3, seed=3), ["np", "mb", "fl", "bound"])
    folder = run_comparison(spec, tmp_path_factory.mktemp("html") / "toy", progress=False).folder
    return folder
