"""Sweep expansion (the paper's Tables 3-6) and bad sweep input."""

from __future__ import annotations

import pytest

from rpbench.exceptions import ParameterError
from rpbench.harness.sweep import SWEEPS, expand, parameter_fields, parse_over


def test_patience_sweep_moves_passengers_and_planner_together():
    points = expand("K", SWEEPS["patience"].values)
    assert [p.value for p in points] == [60, 90, 120, 180, 240, 300, 400, 500, 600]
    assert points[0].overrides == {"patience_mean_s": 60.0, "planner_patience_s": 60.0}
    assert points[1].label == "K=90"


def test_paper_sweeps_have_the_paper_layout():
    assert SWEEPS["response-rate"].strategies == ("fl",)
    assert SWEEPS["interval"].values == (2, 10, 30, 60)
    assert SWEEPS["ratio"].values == (10, 25)
    assert expand("ratio", (10,))[0].overrides == {"vehicles_per_100_orders": 10.0}
    assert expand("r_w", (0.3,))[0].overrides == {"response_rate": 0.3}
    assert parameter_fields("dt_s") == ("dt_s",)


def test_over_parsing():
    assert parse_over("dt=2,10,30") == ("dt", [2.0, 10.0, 30.0])
    with pytest.raises(ParameterError, match="expected NAME=V1,V2"):
        parse_over("dt")
    with pytest.raises(ParameterError, match="must be numbers"):
        parse_over("dt=fast")


def test_unknown_sweep_parameter():
    with pytest.raises(ParameterError, match="unknown sweep parameter 'speed'"):
        expand("speed", [1.0])


def test_out_of_range_and_repeated_values():
    with pytest.raises(ParameterError, match="dt_s = 0.0 must be > 0"):
        expand("dt", [0, 10])
    with pytest.raises(ParameterError, match="must lie in \\[0, 1\\]"):
        expand("r_w", [1.5])
    with pytest.raises(ParameterError, match="repeats a value"):
        expand("dt", [10, 10])


def test_sweep_cli_rejects_unknown_parameter(capsys):
    from rpbench.cli import main

    assert main(["sweep", "--over", "colour=1,2", "--scenario", "toy"]) == 2
    assert "unknown sweep parameter 'colour'" in capsys.readouterr().err


@pytest.mark.slow
def test_sweep_runs_end_to_end_on_the_toy_city(tmp_path):
    from rpbench.harness.render import render
    from rpbench.harness.sweep import SweepSpec, run_sweep
    from rpbench.scenarios import ScenarioRequest
    from rpbench.spec import RunSpec

    spec = SweepSpec("dt", "dt", (10, 30), ("mb",), ("total_saving_km", "response_rate"))
    request = ScenarioRequest("toy", sample=0.1, seed=1)
    folder = run_sweep(
        spec,
        expand("dt", spec.values),
        RunSpec.of(request, ["mb"], command="test", formats=("svg", "pdf")),  # the vector copies asked for
        str(tmp_path / "sw"),
        workers=1,
    ).folder
    assert (folder / "dt=10").is_dir() and (folder / "dt=30").is_dir()
    assert all((folder / f"sweep{suffix}").is_file() for suffix in (".png", ".svg", ".pdf"))
    tex = (folder / "table.tex").read_text()  # the report's table in LaTeX: a header and a row per point
    assert "\\toprule" in tex and tex.count("\\\\") == 3 and "\n10 & " in tex and "\n30 & " in tex
    page = (folder / "report.html").read_text()
    assert 'href="dt=10/report.html"' in page and "fig-sweep" in page and (folder / "dt=30" / "report.html").is_file()
    text, _ = render([folder])
    assert "| dt |" in text and text.count("\n| 10 |") + text.count("\n| 30 |") == 2


def test_a_sweep_over_a_strategy_option(tmp_path, capsys):
    """``--over fl.tau0_s=...``: each point runs FL with that option (recorded in the point's meta.json),
    the other runs as given; a bad option or value is one line before anything runs."""
    from rpbench.check import check_tree
    from rpbench.cli import main
    from rpbench.results.store import read_meta

    out = tmp_path / "sw"
    argv = ["sweep", "--scenario", "toy", "--sample", "0.1", "--strategies", "mb,fl", "--workers", "1"]
    assert main([*argv, "--over", "fl.tau0_s=30,300", "--out", str(out)]) == 0
    for label, tau0 in (("fl.tau0_s=30", 30.0), ("fl.tau0_s=300", 300.0)):
        runs = read_meta(out / label)["runs"]
        assert runs["fl"]["options"]["tau0_s"] == tau0 and runs["mb"]["options"] == {"order_rule": "min_feasible"}
    assert all(r.status == "ok" for r in check_tree(out))
    assert main([*argv, "--over", "fl.nope=1,2", "--out", str(tmp_path / "bad")]) == 2
    assert "unknown option 'nope'" in capsys.readouterr().err and not (tmp_path / "bad").exists()
    assert main([*argv, "--over", "fl.tau0_s=-5,10", "--out", str(tmp_path / "bad")]) == 2


def test_an_integer_option_can_be_swept_and_a_fraction_of_it_is_refused():
    """``msa.samples=2,4``: whole numbers reach the option as ints (an int option refuses 2.0); ``2.5`` is
    refused when the point's specification is built, as any bad option value."""
    from rpbench.scenarios import ScenarioRequest
    from rpbench.spec import RunSpec

    spec = RunSpec.of(ScenarioRequest("toy", sample=0.1), ["mb", "msa"])
    points = expand("msa.samples", [2.0, 4.0], ["mb", "msa"])
    assert [p.options for p in points] == [{"msa": {"samples": 2}}, {"msa": {"samples": 4}}]
    built = [p.spec_of(spec, spec.request) for p in points]
    assert [b.entry("msa").options.samples for b in built] == [2, 4]
    (half,) = expand("msa.samples", [2.5], ["mb", "msa"])
    with pytest.raises(ParameterError, match="samples"):
        half.spec_of(spec, spec.request)
