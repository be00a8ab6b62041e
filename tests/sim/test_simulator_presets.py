"""Every exact solver preset drives the simulator to the same decisions (tie rule of rpbench.sim.ties)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rpbench.backends.presets import load_preset, preset_names
from rpbench.harness.comparison import simulate_strategy
from rpbench.results.metrics import TIMING_KPIS
from rpbench.scenarios import build_scenario
from rpbench.strategies import strategy_class

pytestmark = pytest.mark.slow  # every installed preset simulates three strategies

STRATEGIES = ("np", "mb", "rtv")


def installed_presets() -> list[str]:
    return [n for n in preset_names() if load_preset(n).is_installed()]


@pytest.fixture(scope="module")
def runs():
    scenario = build_scenario("toy", sample=0.25, seed=11)
    out = {}
    for preset in installed_presets():
        p = load_preset(preset)
        for name in STRATEGIES:
            if strategy_class(name).structure not in p.adapter().exact:
                continue
            out[preset, name] = simulate_strategy(scenario, name, p, progress=False)
    return out


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_identical_kpis_events_and_round_objectives(runs, strategy):
    by_preset = {preset: run for (preset, name), run in runs.items() if name == strategy}
    assert len(by_preset) >= 2, "need at least two presets to compare"
    ref_name, ref = next(iter(by_preset.items()))
    ref_kpis = {k: v for k, v in ref.kpis.items() if k not in TIMING_KPIS}
    for preset, run in by_preset.items():
        kpis = {k: v for k, v in run.kpis.items() if k not in TIMING_KPIS}
        assert pd.Series(kpis).equals(pd.Series(ref_kpis)), f"{preset} differs from {ref_name}"
        pd.testing.assert_frame_equal(run.sim.events, ref.sim.events)
        assert np.array_equal(run.sim.rounds["objective_m"].to_numpy(), ref.sim.rounds["objective_m"].to_numpy())
        assert (run.sim.rounds["status"] == "optimal").all()
