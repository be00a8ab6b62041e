"""The per-preset summary by hand-made tables: shifted geometric means with unsolved rows at the time limit,
the ratio to the best preset, per tier with its shift, the repeat spread, the Dolan-Moré profile; and the
environment record."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rpbench.report.bench import (
    NOT_INSTALLED,
    SUMMARY_COLUMNS,
    cpu_model,
    format_summary,
    performance_profile,
    profile_steps,
    shifted_geometric_mean,
    solved,
    solver_environment,
    summarise,
    with_verdicts,
)


def table(rows, tiers=None):
    """Rows of (model, preset, verdict, total_s[, time_limit_s]); the limit defaults to 300 s."""
    out = pd.DataFrame(
        [(*r, 300.0) if len(r) == 4 else r for r in rows],
        columns=["model", "preset", "verdict", "total_s", "time_limit_s"],
    )
    out["tier"] = [tiers.get(m, "all") for m in out["model"]] if tiers else "all"
    out["repeats"] = 1
    out["total_s_min"] = out["total_s_median"] = out["total_s_max"] = out["total_s"]
    return out


def test_sgm_of_a_hand_example():
    t = table([("m1", "a", "optimal", 1.0), ("m2", "a", "optimal", 10.0), ("m3", "a", "optimal", 100.0)])
    (row,) = summarise(t, shift=1.0).to_dict(orient="records")
    # exp(mean(log(t + 1))) - 1 = (2 * 11 * 101) ** (1/3) - 1
    assert row["sgm_s"] == pytest.approx(2222 ** (1 / 3) - 1, rel=1e-12)
    assert row["sgm_ratio"] == 1.0 and row["shift_s"] == 1.0
    assert row["solved"] == row["instances"] == 3 and list(summarise(t).columns) == SUMMARY_COLUMNS


def test_unsolved_rows_count_at_their_time_limit_and_the_ratio_is_to_the_best():
    t = table(
        [
            ("m1", "a", "optimal", 1.0),
            ("m2", "a", "optimal", 4.0),
            ("m1", "b", "optimal", 2.0),
            ("m2", "b", "time_limit", 3.0, 16.0),  # gave up after 3 s of a 16 s limit: counts 16
            ("m1", "c", "wrong", 0.5, 8.0),  # a wrong answer is no solve, however fast
            ("m2", "c", "error", math.nan, 8.0),
        ]
    )
    s = summarise(t, shift=0.0).set_index("preset")
    assert s.loc["a", "sgm_s"] == pytest.approx(2.0)  # sqrt(1 * 4)
    assert s.loc["b", "sgm_s"] == pytest.approx(math.sqrt(2 * 16))
    assert s.loc["c", "sgm_s"] == pytest.approx(8.0)
    assert s.loc["a", "sgm_ratio"] == 1.0
    assert s.loc["b", "sgm_ratio"] == pytest.approx(math.sqrt(32) / 2)
    assert s.loc["c", "sgm_ratio"] == pytest.approx(4.0)
    assert s["solved"].tolist() == [2, 1, 0]
    assert (s.loc["b", "time_limit"], s.loc["c", "wrong"], s.loc["c", "error"]) == (1, 1, 1)
    text = format_summary(summarise(t, shift=0.0))
    assert "2/2" in text and "1.00" in text and "4.00" in text and "1 wrong, 1 error" in text


def test_without_a_time_limit_the_mean_of_a_preset_with_a_failure_is_undefined():
    t = table([("m1", "a", "optimal", 1.0), ("m1", "b", "killed", math.nan, math.nan)])
    s = summarise(t).set_index("preset")
    assert s.loc["a", "sgm_ratio"] == 1.0 and math.isnan(s.loc["b", "sgm_s"]) and math.isnan(s.loc["b", "sgm_ratio"])


def test_per_tier_with_its_shift_and_a_total():
    tiers = {"s1": "S", "s2": "S", "m1": "M"}
    t = table(
        [
            ("s1", "a", "optimal", 0.01),
            ("s2", "a", "optimal", 0.04),
            ("m1", "a", "optimal", 1.0),
            ("s1", "b", "optimal", 0.02),
            ("s2", "b", "optimal", 0.02),
            ("m1", "b", "optimal", 2.0),
        ],
        tiers,
    )
    s = summarise(t).set_index(["tier", "preset"])
    assert list(dict.fromkeys(s.index.get_level_values(0))) == ["S", "M", "total"]
    assert s.loc[("S", "a"), "shift_s"] == 0.01 and s.loc[("M", "a"), "shift_s"] == 0.1
    assert s.loc[("S", "a"), "sgm_s"] == pytest.approx(math.sqrt(0.02 * 0.05) - 0.01)
    assert s.loc[("S", "b"), "sgm_s"] == pytest.approx(0.02)
    assert s.loc[("S", "b"), "sgm_ratio"] == 1.0 and s.loc[("M", "a"), "sgm_ratio"] == 1.0  # best per tier
    assert s.loc[("total", "a"), "instances"] == 3 and s.loc[("total", "a"), "shift_s"] == 0.01
    assert summarise(t, shift=0.5).set_index(["tier", "preset"]).loc[("M", "a"), "shift_s"] == 0.5


def test_repeat_spread_is_the_median_relative_range_of_repeated_solves():
    t = table([("m1", "a", "optimal", 1.0), ("m2", "a", "optimal", 1.0), ("m3", "a", "optimal", 1.0)])
    t["repeats"] = [3, 3, 1]
    t["total_s_min"] = [1.0, 1.0, 1.0]
    t["total_s_median"] = [2.0, 1.0, 1.0]
    t["total_s_max"] = [3.0, 1.5, 9.0]  # m3 ran once: its range is not a spread
    assert summarise(t)["repeat_spread"].iloc[0] == pytest.approx(np.median([1.0, 0.5]))


def test_profile_fractions_of_a_hand_example():
    t = table(
        [
            ("m1", "a", "optimal", 1.0),
            ("m2", "a", "optimal", 2.0),
            ("m3", "a", "time_limit", 300.0),
            ("m1", "b", "optimal", 2.0),
            ("m2", "b", "optimal", 1.0),
            ("m3", "b", "optimal", 4.0),
        ]
    )
    profile = performance_profile(t)
    assert list(profile.columns) == ["preset", "tau", "fraction"]
    # ratios: a = [1, 2, inf], b = [2, 1, 1]
    got = {(p, tau): f for p, tau, f in profile.itertuples(index=False)}
    assert got == {("a", 1.0): 1 / 3, ("a", 2.0): 2 / 3, ("b", 1.0): 2 / 3, ("b", 2.0): 1.0}
    steps = profile_steps(profile)
    assert steps["a"][0].tolist() == [1.0, 2.0] and steps["a"][1].tolist() == [1 / 3, 2 / 3]


def test_a_zero_time_does_not_divide_by_zero():
    t = table([("m1", "a", "optimal", 0.0), ("m1", "b", "optimal", 0.0)])
    profile = performance_profile(t)
    assert profile["tau"].tolist() == [1.0, 1.0] and profile["fraction"].tolist() == [1.0, 1.0]


def test_environment_names_the_cpu_and_every_library(tmp_path):
    env = solver_environment(("highspy", "no-such-package-rpbench"))
    assert env["versions"]["no-such-package-rpbench"] == NOT_INSTALLED and env["versions"]["highspy"] != NOT_INSTALLED
    assert {"rpbench", "python", "numpy"} <= set(env["versions"])
    assert env["machine"]["logical_cores"] >= 1 and "platform" in env["machine"]
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: X\nmodel name\t: Test CPU 9000 @ 3.0GHz\n\nprocessor\t: 1\n")
    assert cpu_model(info) == "Test CPU 9000 @ 3.0GHz"


def test_shifted_geometric_mean():
    assert shifted_geometric_mean(np.array([1.0, 4.0]), shift=0.0) == pytest.approx(2.0)
    assert shifted_geometric_mean(np.array([1.0, 4.0]), shift=1.0) == pytest.approx(math.sqrt(2 * 5) - 1)
    assert math.isnan(shifted_geometric_mean(np.array([])))


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)  # a shared machine
@given(st.lists(st.floats(1e-6, 1e3), min_size=1, max_size=20), st.floats(0.0, 10.0))
def test_the_mean_lies_between_the_extremes(times, shift):
    m = shifted_geometric_mean(np.array(times), shift)
    assert min(times) * (1 - 1e-9) - 1e-12 <= m <= max(times) * (1 + 1e-9) + 1e-12


def test_a_table_without_verdicts_counts_as_solved_what_was_proven_and_agreed():
    """A table written before verdicts: solved = proven optimal and not disagreeing with the others' optimum."""
    old = pd.DataFrame(
        [
            ("m1", "a", "optimal", True, 1.0),
            ("m2", "a", "time_limit", None, 60.0),
            ("m3", "a", "optimal", False, 0.5),
            ("m4", "a", "optimal", None, 2.0),
        ],
        columns=["model", "preset", "status", "agrees", "total_s"],
    )
    assert solved(old).tolist() == [True, False, False, True]
    assert with_verdicts(old)["verdict"].tolist() == ["optimal", "time_limit", "wrong", "optimal"]
