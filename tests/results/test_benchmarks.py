"""The benchmark summaries: shifted geometric means and Dolan-Moré performance profiles, by hand-made tables."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rpbench.results.benchmarks import performance_profile, performance_ratios, preset_summary, shifted_geometric_mean


def table(rows):
    return pd.DataFrame(rows, columns=["model", "preset", "structure", "status", "agrees", "total_s"])


TABLE = table(
    [
        ("m1", "a", "pairing", "optimal", True, 1.0),
        ("m1", "b", "pairing", "optimal", True, 2.0),
        ("m2", "a", "pairing", "optimal", True, 4.0),
        ("m2", "b", "pairing", "optimal", True, 1.0),
        ("m3", "a", "pairing", "time_limit", None, 60.0),
        ("m3", "b", "pairing", "optimal", True, 3.0),
        ("m4", "a", "pairing", "optimal", False, 0.5),  # disagrees with the others' optimum: not solved
        ("m4", "b", "pairing", "optimal", True, 5.0),
    ]
)


def test_shifted_geometric_mean():
    assert shifted_geometric_mean(np.array([1.0, 4.0]), shift=0.0) == pytest.approx(2.0)
    assert shifted_geometric_mean(np.array([1.0, 4.0]), shift=1.0) == pytest.approx(math.sqrt(2 * 5) - 1)
    assert math.isnan(shifted_geometric_mean(np.array([])))


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)  # a shared machine
@given(st.lists(st.floats(1e-6, 1e3), min_size=1, max_size=20), st.floats(0.0, 10.0))
def test_the_mean_lies_between_the_extremes(times, shift):
    m = shifted_geometric_mean(np.array(times), shift)
    assert min(times) * (1 - 1e-9) - 1e-12 <= m <= max(times) * (1 + 1e-9) + 1e-12


def test_ratios_and_profile():
    ratios = performance_ratios(TABLE)
    assert ratios.loc["m1"].tolist() == [1.0, 2.0] and ratios.loc["m2"].tolist() == [4.0, 1.0]
    assert ratios.loc["m3", "a"] == np.inf and ratios.loc["m4", "a"] == np.inf  # unsolved, disagreeing
    profile = performance_profile(TABLE)
    r, share = profile["b"]
    assert r.tolist() == [1.0, 1.0, 1.0, 2.0] and share.tolist() == [0.25, 0.5, 0.75, 1.0]
    r, share = profile["a"]
    assert r.tolist() == [1.0, 4.0] and share[-1] == 0.5  # a solved half of the models


def test_preset_summary():
    summary = preset_summary(TABLE, shift=0.0)
    assert summary.loc["a", "solved"] == 2 and summary.loc["b", "solved"] == 4
    assert summary.loc["b", "fastest"] == 3 and summary.loc["a", "fastest"] == 1
    # the models both solved: m1 and m2
    assert summary.loc["a", "sgm_common_ms"] == pytest.approx(1e3 * 2.0)
    assert summary.loc["b", "sgm_common_ms"] == pytest.approx(1e3 * math.sqrt(2.0))


def test_a_killed_solve_without_a_time_leaves_the_mean_over_all_models_undefined():
    killed = pd.concat([TABLE, table([("m5", "a", "pairing", "killed", None, np.nan)])], ignore_index=True)
    summary = preset_summary(killed)
    assert math.isnan(summary.loc["a", "sgm_all_ms"]) and not math.isnan(summary.loc["b", "sgm_all_ms"])


def test_the_bench_page(tmp_path):
    from rpbench.results.html.bench import bench_tables, write_bench_folder

    TABLE.assign(cols=100, objective=1.0, gap=0.0, message="").to_csv(tmp_path / "bench.csv", index=False)
    (tmp_path / "other.csv").write_text("x,y\n1,2\n")
    assert bench_tables(tmp_path) == [tmp_path / "bench.csv"]
    page = write_bench_folder(tmp_path).read_text()
    assert 'id="bench-summary"' in page and "fig-profile" in page and "fig-times" in page
