"""A dated evaluation holds one unit per day of its protocol and seed: a whole day deleted, or a unit of another
day copied in its place, fails ``protocol-units`` even with the parent's tables recomputed."""

from __future__ import annotations

import shutil

import pytest
from helpers import write_fake_haikou

from check.tamper import assert_fails, assert_passes, copy, edit_meta
from rpbench.harness.evaluate import run_evaluation
from rpbench.protocols import load_protocol
from rpbench.report.evaluation import write_evaluation_tables

pytestmark = pytest.mark.slow
DAYS = ("2017-05-01", "2017-05-02")
PROTOCOL = f"""
name = "two-days"
version = 1
scenario = "haikou-peak"
dates = "{DAYS[0]}..{DAYS[1]}"
sample = 1.0
seeds = [0]
strategies = ["mb", "rtv", "bound"]
oracle_preset = "matching"
metrics = ["total_saving_km", "competitive_ratio_bound"]
[bootstrap]
resamples = 100
"""


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    data = write_fake_haikou(tmp_path_factory.mktemp("data") / "haikou", days=DAYS)
    path = tmp_path_factory.mktemp("protocol") / "two-days.toml"
    path.write_text(PROTOCOL)
    out = tmp_path_factory.mktemp("eval") / "two-days"
    return run_evaluation(load_protocol(str(path)), out, data_dir=str(data), workers=1).folder


@pytest.fixture
def ev(evaluated, tmp_path):
    return copy(evaluated, tmp_path, "ev")


def test_a_dated_evaluation_passes(evaluated):
    (parent, *units) = assert_passes(evaluated)
    assert parent.folder_check.checked["protocol_units"] == 2 and len(units) == 2


def test_a_whole_day_deleted_with_its_entry_fails(ev):
    shutil.rmtree(ev / "2017-05-02_seed0")
    edit_meta(ev, lambda m: m.update(children=["2017-05-01_seed0"]))
    write_evaluation_tables(ev)
    assert_fails(ev, "protocol-units", "unit 2017-05-02_seed0 (day 2017-05-02, seed 0) of protocol 'two-days'")


def test_a_unit_of_another_day_copied_in_fails(ev):
    """(Its tables cannot be recomputed: two units of one day and seed.)"""
    shutil.rmtree(ev / "2017-05-02_seed0")
    shutil.copytree(ev / "2017-05-01_seed0", ev / "2017-05-02_seed0")
    assert_fails(ev, "protocol-units", "2017-05-02_seed0 records date '2017-05-01', the protocol gives it '2017-05-02'")
