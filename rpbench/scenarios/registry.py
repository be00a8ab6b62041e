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

from rpbench.cities.places import load_city
from rpbench.data import available_peak_dates, read_hourly_counts
from rpbench.data.first_run import ensure_data_dir, obtain_data_dir, warn_synthetic
from rpbench.exceptions import ParameterError
from rpbench.scenarios.base import Params, Scenario
from rpbench.scenarios.city import build_city, parse_window
from rpbench.scenarios.common import MAX_DEMAND_MULTIPLIER, check_sample
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
    #: The city whose data folder it reads (``--data DIR`` names that folder).
    city: str = "haikou"
    #: Parameters that differ from the paper's for this scenario, from its data folder and options (a city's
    #: speed); ``--param`` overrides them.
    default_params: Callable[..., dict[str, float]] | None = None
    #: The time window a scenario of a city's day covers by default (None: the scenario takes no --window).
    window: str | None = None
    #: Whether its orders are real (a sample of them cannot exceed them) or generated in code.
    real_orders: bool = True
    #: The largest ``--sample``: 1 (every order), or above 1 for a generator that takes a demand multiplier
    #: (k times the volume drawn anew from the same rates; :data:`~.common.MAX_DEMAND_MULTIPLIER`).
    max_sample: float = 1.0

    def check_sample(self, sample: float) -> float:
        """``sample`` as a float when this scenario takes it, else one line naming the scenario and why."""
        takes = ", ".join(name for name, spec in SCENARIOS.items() if spec.max_sample > 1)
        return check_sample(sample, scenario=self.name, most=self.max_sample, real=self.real_orders, multipliers=takes)


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
            "SYNTHETIC 24-hour stand-in: a date's real hourly volumes, OD pairs from the 21-day OD rate table "
            "(--sample k > 1: k times the volume, a stress test)",
            True,
            1.0,
            build_day,
            _hourly_count_dates,
            real_orders=False,
            max_sample=MAX_DEMAND_MULTIPLIER,
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
            real_orders=False,
        ),
        ScenarioSpec(
            "lattice",
            "SYNTHETIC small grid city, every block one batch interval long: rpbench proves its offline optimum",
            False,
            0.3,
            lambda data_dir, **kw: build_lattice(**kw),
            real_orders=False,
        ),
    ]
}


def _city_scenario(name: str | None, city_name: str | None = None) -> Callable[..., Scenario]:
    """The builder of a scenario over a city's day: a built-in city's own (``city_name``), or ``--city``'s."""

    def build(data_dir: Path | None, *, city: str | None = None, **kw: Any) -> Scenario:
        folder = None if data_dir is None else str(data_dir)
        loaded = load_city(_city_of(city, city_name), data_dir)
        return build_city(loaded, name=name or "city", source=city, data_dir=folder, **kw)

    return build


def _city_speed(city_name: str | None) -> Callable[..., dict[str, float]]:
    """The speed of a city's vehicles over the scenario's window, when the city records one."""

    def defaults(data_dir: Path | None, *, city: str | None = None, window: str, **_: Any) -> dict[str, float]:
        speed = load_city(_city_of(city, city_name), data_dir).speed_mps(*parse_window(window))
        return {} if speed is None else {"speed_mps": speed}

    return defaults


def _city_of(given: str | None, builtin: str | None) -> str:
    if builtin is not None:
        if given is not None and given != builtin:
            raise ParameterError(
                f"--city {given!r}: this scenario is {builtin}'s; for another city use --scenario city"
            )
        return builtin
    if given is None:
        raise ParameterError("scenario 'city' needs --city NAME (a city imported with `rpbench city import`)")
    return given


SCENARIOS.update(
    {
        spec.name: spec
        for spec in [
            ScenarioSpec(
                "city",
                "a window of a city's real trips: --city NAME (imported with `rpbench city import`) "
                "--window HH:MM-HH:MM",
                False,
                1.0,
                _city_scenario(None),
                default_params=_city_speed(None),
                window="08:00-09:00",
            ),
            ScenarioSpec(
                "manhattan-peak",
                "Manhattan's real 08:00-09:00 yellow-cab trips of one weekday on the OSMnx network (30 % sample)",
                True,
                0.3,
                _city_scenario("manhattan-peak", "manhattan"),
                city="manhattan",
                default_params=_city_speed("manhattan"),
                window="08:00-09:00",
            ),
            ScenarioSpec(
                "manhattan-day",
                "Manhattan's real day of 98,235 yellow-cab trips on the OSMnx network",
                True,
                1.0,
                _city_scenario("manhattan-day", "manhattan"),
                city="manhattan",
                default_params=_city_speed("manhattan"),
                window="00:00-24:00",
            ),
        ]
    }
)

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
    sample = spec.default_sample if sample is None else spec.check_sample(sample)
    options = {k: v for k, v in options.items() if v is not None}
    if spec.window is not None:
        options.setdefault("window", spec.window)
    elif "window" in options or "city" in options:
        flag = "--window" if "window" in options else "--city"
        raise ParameterError(f"{flag}: scenario {name!r} is not a city's day; it applies to city, manhattan-peak, ...")
    folder = ensure_data_dir(data_dir, what=f"scenario {name!r}", city=spec.city) if spec.needs_data else None
    if params is None:
        base = spec.default_params(folder, **options) if spec.default_params is not None else {}
        params = Params().replace(**base)
    if param_overrides:
        params = params.replace(**param_overrides)
    kwargs: dict[str, Any] = dict(seed=seed, params=params, sample=sample, **options)
    if date is not None:
        if spec.window is not None:
            raise ParameterError(f"--date: scenario {name!r} is a city's one day of trips; it has no date to choose")
        kwargs["date"] = date
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
