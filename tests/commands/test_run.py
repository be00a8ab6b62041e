"""``rpbench run``: the printed table's ratio rows and bracket line, and ``--json``'s ratios for every run."""

from __future__ import annotations

import contextlib
import io
import json

import pytest

from rpbench.cli import main

RUN = ["run", "--scenario", "toy", "--sample", "0.1", "--seed", "2", "--no-progress", "--oracle-solver", "matching"]
RUN += ["--strategies", "mb,hindsight,bound,oracle1"]


@pytest.fixture(scope="module")
def printed(tmp_path_factory) -> dict[str, str]:
    """stdout of one toy comparison with a clairvoyant run, the bound and Oracle-1: as JSON and as a table."""
    root = tmp_path_factory.mktemp("run")
    out = {}
    for name, extra in (("json", ["--json"]), ("table", [])):
        buffer = io.StringIO()
        with contextlib.redirect_stdout(buffer):
            assert main([*RUN, *extra, "--out", str(root / name)]) == 0
        out[name] = buffer.getvalue()
    return out


def test_json_carries_every_ratio_of_every_run_and_the_bracket(printed):
    found = json.loads(printed["json"])
    kpis = found["kpis"]
    for run in ("mb", "hindsight"):
        assert {"competitive_ratio_bound", "competitive_ratio_best_known", "saving_over_oracle1"} <= set(kpis[run])
    assert kpis["bound"]["competitive_ratio_bound"] is None  # an offline run has no ratio
    best = found["best_known"]
    assert best["saving_km"] == max(kpis[r]["total_saving_km"] for r in ("mb", "hindsight"))
    assert kpis[best["run"]]["competitive_ratio_best_known"] == 1.0
    assert found["upper_bound_km"] == kpis["bound"]["total_saving_km"]
    assert found["bound_over_best_known"] == pytest.approx(found["upper_bound_km"] / best["saving_km"])
    assert kpis["bound"]["bound_over_best_known"] == pytest.approx(found["bound_over_best_known"])


def test_the_table_prints_the_three_ratio_rows_and_where_opt_lies(printed):
    lines = printed["table"].splitlines()
    labels = [line.split("  ")[0] for line in lines]
    assert "Competitive ratio (saving / proven upper bound)" in labels
    assert "Competitive ratio (saving / best known schedule)" in labels
    assert "Saving / Oracle-1 (paper's reference; not a bound)" in labels
    (bracket,) = [line for line in lines if line.startswith("OPT lies in [LB, U] = [")]
    assert "best known schedule: " in bracket and "U / LB = " in bracket
