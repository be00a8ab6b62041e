"""The pieces the evaluation checks are built from, on hand-made records: the protocol digest (the same as the
protocols compute), the days of a protocol, which run a protocol entry is in a unit, what a unit's runs are
held to, and reading back the rendered reports."""

from __future__ import annotations

import base64
import json

import numpy as np
import pytest

from rpbench.check.core import RunCheck
from rpbench.check.protocol import MalformedRecord, protocol_days, read_protocol
from rpbench.check.rendered import decoded, latex_rows, markdown_tables
from rpbench.check.unit_runs import matched_runs, option_problems, preset_name
from rpbench.protocols import builtin_names, load_protocol
from rpbench.report.evaluation import entry_run, evaluation_runs
from rpbench.results.digest import protocol_digest


@pytest.mark.parametrize("name", builtin_names())
def test_the_checker_hashes_every_builtin_protocol_as_it_records_itself(name):
    record = json.loads(json.dumps(load_protocol(name).record()))  # as meta.json holds it
    assert protocol_digest(record) == record["digest"]
    fc = RunCheck("(folder)")
    assert read_protocol(fc, {"protocol": record}) is not None and fc.ok, fc.violations


def test_a_record_edited_anywhere_no_longer_hashes_to_its_digest():
    record = json.loads(json.dumps(load_protocol("toy-quick").record()))
    record["bootstrap"]["resamples"] += 1
    fc = RunCheck("(folder)")
    assert read_protocol(fc, {"protocol": record}) is not None
    assert "does not hash to its digest" in fc.violations["protocol"][0]


def test_the_days_of_a_protocol():
    assert protocol_days(None) == [None]
    assert protocol_days("2017-05-30..2017-06-01") == ["2017-05-30", "2017-05-31", "2017-06-01"]
    assert protocol_days("2017-05-03, 2017-05-01") == ["2017-05-03", "2017-05-01"]
    for bad in ("2017-05-03..2017-05-01", "2017-05-01,2017-05-01", "May 1", ""):
        with pytest.raises(MalformedRecord):
            protocol_days(bad)


def test_a_protocol_entry_is_found_under_the_name_its_unit_gives_it():
    records = {
        "mb": {"source": "mb"},
        "fl@tau0_s=200": {"source": "fl"},
        "greedy": {"source": "mypkg.rules:Greedy"},
    }
    assert entry_run("MB", records) == "mb"
    assert entry_run("FL@tau0_s=200", records) == "fl@tau0_s=200"
    assert entry_run("mypkg.rules:Greedy", records) == "greedy"
    assert entry_run("rtv", records) is None
    twice = {**records, "greedy2": {"source": "mypkg.rules:Greedy"}}
    assert entry_run("mypkg.rules:Greedy", twice) is None  # ambiguous: no run is taken for it
    units = [records, {**records, "extra": {"source": "extra"}}]
    assert evaluation_runs(["mypkg.rules:Greedy", "mb", "rtv"], units) == [
        "greedy", "mb", "rtv", "fl@tau0_s=200", "extra",
    ]  # fmt: skip


def test_a_units_runs_against_the_protocols_entries():
    unit = {"runs": {"mb": {"source": "mb"}, "stray": {"source": "stray"}}, "manifest": {"runs": ["mb", "stray"]}}
    matched, problems = matched_runs(["mb", "rtv"], unit)
    assert matched == {"mb": "mb"}
    assert problems == ["holds no run of the protocol's 'rtv'", "holds run 'stray', which the protocol does not list"]


def test_a_runs_options_are_its_defaults_and_its_variants_settings():
    fl = {"kind": "simulation", "source": "fl", "options": {"tau0_s": 211.6, "accel": "anderson", "rates": "auto"}}
    assert option_problems("fl", "fl", fl) == ([], None)  # τ_0 is calibrated on the unit: not compared
    assert option_problems("fl@accel=none", "fl@accel=none", fl)[0] == [
        "run 'fl@accel=none' ran with accel='anderson'; the protocol gives it 'none'"
    ]
    assert option_problems("fl", "fl", {**fl, "options": {"warp": 9}})[0] == [
        "run 'fl' records option 'warp', which its strategy does not declare"
    ]
    plugin = {"kind": "simulation", "source": "mypkg.rules:Greedy", "options": {}}
    assert option_problems("mypkg.rules:Greedy", "greedy", plugin) == (
        [],
        "run 'greedy': the options of a plug-in ('mypkg.rules:Greedy') are not compared",
    )
    oracle = {"kind": "oracle", "rules": {"allow_enroute": True, "window": "patience"}}
    assert option_problems("oracle1", "oracle1", oracle)[0] == [
        "offline run 'oracle1' ran with allow_enroute=True; the protocol gives it False"
    ]
    assert preset_name("solvers/fast.toml") == "fast" and preset_name("highs") == "highs"


def test_reading_back_markdown_latex_and_plotly_tables():
    md = "text\n\n| A | B |\n|---|---:|\n| x \\| y | 1 |\n\nmore\n| C |\n|---|\n| z |\n"
    assert markdown_tables(md) == [[["A", "B"], ["x \\| y", "1"]], [["C"], ["z"]]]
    tex = "\\toprule\nRank & Run \\& co \\\\\n\\midrule\n1 & 2.0 [1.0, 3.0] \\\\\n\\bottomrule\n"
    assert latex_rows(tex) == [["Rank", "Run \\& co"], ["1", "2.0 [1.0, 3.0]"]]
    values = np.array([[1.5, 2.5], [3.5, 4.5]])
    typed = {"dtype": "f8", "bdata": base64.b64encode(values.tobytes()).decode(), "shape": "2, 2"}
    assert decoded({"y": typed, "x": ["a", "b"]}) == {"y": values.tolist(), "x": ["a", "b"]}
