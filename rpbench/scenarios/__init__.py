"""Scenarios: the objects (:mod:`.base`), the generators by name (:mod:`.registry`: Haikou peak
hours, the synthetic full day, the 2017-07-01 trace, the toy city) and the frozen request that
names one (:mod:`.request`)."""

from rpbench.scenarios.registry import (
    DEFAULT_SCENARIO,
    SCENARIOS,
    ScenarioSpec,
    build_scenario,
    default_scenario_name,
    scenario_spec,
)
from rpbench.scenarios.request import ScenarioRequest

__all__ = [
    "DEFAULT_SCENARIO",
    "SCENARIOS",
    "ScenarioRequest",
    "ScenarioSpec",
    "build_scenario",
    "default_scenario_name",
    "scenario_spec",
]
