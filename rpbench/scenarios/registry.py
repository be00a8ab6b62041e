"""The scenario generators by name.

``build_scenario(name, ...)`` resolves the data folder (``--data``,
``$RPBENCH_DATA``, ``../shared/data/haikou``, the fetched folder; fetching it
first when none exists, :mod:`rpbench.data.first_run`), applies parameter
overrides and returns a frozen :class:`~rpbench.scenarios.base.Scenario`.  A generator
of real days also says which dates its data folder holds (``dates``), which
is what ``--dates`` runs over.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rpbench.data import available_peak_dates, read_hourly_counts
from rpbench.data.first_run import ensure_data_dir, obtain_data_dir, warn_synthetic
from rpbench.exceptions import ParameterError
from rpbench.scenarios.base import Params, Scenario
from rpbench.scenarios.day import build_day
from rpbench.scenarios.lattice import build_lattice
from rpbench.scenarios.paper_input import build_paper_input
from rpbench.scenarios.peak import build_peak
from rpbench.scenarios.toy import build_toy
from rpbench.scenarios.trace import build_trace


@dataclass(frozen=True)
class ScenarioSpec:
    name: str
    description: str
    needs_data: bool
    default_sample: float
    build: Callable[..., Scenario]
    #: The dates a data folder holds for this scenario (None: the scenario has no date choice).
    dates: Callable[[Path], list[str]] | None = None


def _hourly_count_dates(data_dir: Path) -> list[str]:
    return sorted(read_hourly_counts(data_dir))


SCENARIOS: dict[str, ScenarioSpec] = {
    spec.name: spec
    for spec in [
        ScenarioSpec(
            "haikou-peak",
            "a date's real 08:00-09:00 DiDi orders on the authors' network (default 2017-05-01, 30 % sample)",
            True,
            0.3,
            build_peak,
            available_peak_dates,
        ),
        ScenarioSpec(
            "haikou-paper-input",
            "the authors' exact input behind their committed outputs: arrive-time "
            "selection on 2017-05-01, pandas sample random_state=1, int(n/4) vehicles",
            True,
            0.3,
            build_paper_input,
            available_peak_dates,
        ),
        ScenarioSpec(
            "haikou-day",
            "SYNTHETIC 24-hour stand-in: a date's real hourly volumes, OD pairs from the 21-day OD rate table",
            True,
            1.0,
            build_day,
            _hourly_count_dates,
        ),
        ScenarioSpec(
            "haikou-trace", "the real 2017-07-01 00:00-13:06 trace on the TR-B 2021 network", True, 1.0, build_trace
        ),
        ScenarioSpec(
            "toy",
            "SYNTHETIC small grid city generated in code (no data needed)",
            False,
            1.0,
            lambda data_dir, **kw: build_toy(**kw),
        ),
        ScenarioSpec(
            "lattice",
            "SYNTHETIC small grid city, every block one batch interval long: rpbench proves its offline optimum",
            False,
            0.3,
            lambda data_dir, **kw: build_lattice(**kw),
        ),
    ]
}

DEFAULT_SCENARIO = "haikou-peak"


def build_scenario(
    name: str,
    *,
    data_dir: str | Path | None = None,
    date: str | None = None,
    sample: float | None = None,
    seed: int = 0,
    params: Params | None = None,
    param_overrides: dict[str, Any] | None = None,
    **options: Any,
) -> Scenario:
    """Build the named scenario (see :data:`SCENARIOS`)."""
    spec = scenario_spec(name)
    params = params or Params()
    if param_overrides:
        params = params.replace(**param_overrides)
    kwargs: dict[str, Any] = dict(
        seed=seed, params=params, sample=spec.default_sample if sample is None else sample, **options
    )
    if date is not None:
        kwargs["date"] = date
    folder = ensure_data_dir(data_dir, what=f"scenario {name!r}") if spec.needs_data else None
    return spec.build(folder, **kwargs)


def scenario_spec(name: str) -> ScenarioSpec:
    spec = SCENARIOS.get(name)
    if spec is None:
        raise ParameterError(f"unknown scenario {name!r}; expected one of {', '.join(SCENARIOS)}")
    return spec


def default_scenario_name(
    data_dir: str | Path | None = None, *, offline: bool = False, progress: bool | None = None
) -> str:
    """``haikou-peak`` when a data folder exists or can be fetched (``offline``: not tried), else the
    built-in ``toy`` city, after a banner on stderr saying that what follows is synthetic, why, and how
    to get the real data (:func:`rpbench.data.first_run.obtain_data_dir`)."""
    folder, why = obtain_data_dir(data_dir, offline=offline, progress=progress)
    if folder is not None:
        return DEFAULT_SCENARIO
    warn_synthetic(why)
    return "toy"
