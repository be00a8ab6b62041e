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


@pytest.fixture(scope="package")
def toy_bracket(tmp_path_factory):
    """A run with the whole bracket (a clairvoyant run, the upper bound, Oracle-1): long labels, the ratio panel."""
    strategies = ["mb", "fl", "hindsight", "bound", "oracle1"]
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.3, seed=3), strategies)
    return run_comparison(spec, tmp_path_factory.mktemp("bracket") / "toy", progress=False).folder


#: Two toy seeds, an online and a clairvoyant run beside the bound: an evaluation built in seconds.
EVALUATION_PROTOCOL = """
name = "page"
version = 1
scenario = "toy"
sample = 0.1
seeds = [0, 1]
strategies = ["mb", "hindsight", "bound"]
metrics = ["total_saving_km", "competitive_ratio_bound", "response_rate"]
[bootstrap]
resamples = 50
"""


@pytest.fixture(scope="package")
def toy_evaluation(tmp_path_factory):
    from rpbench.harness.evaluate import run_evaluation
    from rpbench.protocols import load_protocol

    path = tmp_path_factory.mktemp("protocol") / "page.toml"
    path.write_text(EVALUATION_PROTOCOL)
    return run_evaluation(load_protocol(str(path)), tmp_path_factory.mktemp("evaluation") / "eval", workers=1).folder
