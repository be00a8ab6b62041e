"""Scenario generators and their registry.

``build_scenario(name, ...)`` is the one entry point: it resolves the data
folder (``--data``, ``$RPBENCH_DATA``, ``../shared/data/haikou``), applies
parameter overrides and returns a frozen :class:`~rpbench.scenario.Scenario`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from ..exceptions import ParameterError
from ..paths import find_data_dir, require_data_dir
from ..scenario import Params, Scenario
from .day import build_day
from .peak import build_peak
from .toy import build_toy, grid_network
from .trace import build_trace


@dataclass(frozen=True)
class ScenarioSpec:
    name: str
    description: str
    needs_data: bool
    default_sample: float
    build: Callable[..., Scenario]


SCENARIOS: dict[str, ScenarioSpec] = {
    spec.name: spec for spec in [
        ScenarioSpec("haikou-peak", "a date's real 08:00-09:00 DiDi orders on the authors' network "
                     "(default 2017-05-01, 30 % sample)", True, 0.3, build_peak),
        ScenarioSpec("haikou-day", "SYNTHETIC 24-hour stand-in: a date's real hourly volumes, OD pairs "
                     "from the 21-day OD rate table", True, 1.0, build_day),
        ScenarioSpec("haikou-trace", "the real 2017-07-01 00:00-13:06 trace on the TR-B 2021 network",
                     True, 1.0, build_trace),
        ScenarioSpec("toy", "SYNTHETIC small grid city generated in code (no data needed)", False, 1.0,
                     lambda data_dir, **kw: build_toy(**kw)),
    ]
}

DEFAULT_SCENARIO = "haikou-peak"


def build_scenario(name: str, *, data_dir: str | Path | None = None, date: str | None = None,
                   sample: float | None = None, seed: int = 0, params: Params | None = None,
                   param_overrides: dict[str, Any] | None = None, **options: Any) -> Scenario:
    """Build the named scenario (see :data:`SCENARIOS`)."""
    spec = SCENARIOS.get(name)
    if spec is None:
        raise ParameterError(f"unknown scenario {name!r}; expected one of {', '.join(SCENARIOS)}")
    params = params or Params()
    if param_overrides:
        params = params.replace(**param_overrides)
    kwargs: dict[str, Any] = dict(seed=seed, params=params,
                                  sample=spec.default_sample if sample is None else sample, **options)
    if date is not None:
        kwargs["date"] = date
    folder = require_data_dir(data_dir, what=f"scenario {name!r}") if spec.needs_data else None
    return spec.build(folder, **kwargs)


def default_scenario_name(data_dir: str | Path | None = None) -> str:
    """``haikou-peak`` when a data folder exists, else the built-in ``toy`` city."""
    return DEFAULT_SCENARIO if find_data_dir(data_dir) is not None else "toy"


__all__ = ["SCENARIOS", "ScenarioSpec", "build_scenario", "default_scenario_name", "grid_network"]
