"""A scenario request: everything that names one scenario, frozen, picklable, recorded as given.

One :class:`ScenarioRequest` replaces the argument shapes that the run, the
multi-day runner, the sweep points and the commands used to rebuild:
:meth:`~ScenarioRequest.build` makes the scenario, :meth:`~ScenarioRequest.meta`
is what a results folder records (``meta.json`` ``scenario.args``), and
:meth:`~ScenarioRequest.dates` expands ``--dates`` for any dated scenario.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
from dataclasses import dataclass
from typing import Any

from rpbench.data.first_run import ensure_data_dir
from rpbench.data.orders import parse_date
from rpbench.exceptions import ParameterError
from rpbench.scenarios.base import Scenario
from rpbench.scenarios.registry import build_scenario, scenario_spec


@dataclass(frozen=True)
class ScenarioRequest:
    """Name, date, sample, seed, parameter overrides and fleet placement of one scenario; for a scenario of a
    city's day, the city (``city``) and the time window (``window``)."""

    name: str
    date: str | None = None
    sample: float | None = None
    seed: int = 0
    params: tuple[tuple[str, float], ...] = ()  # overrides, sorted (frozen and hashable)
    fleet_placement: str = "order_origins"
    data_dir: str | None = None
    city: str | None = None
    window: str | None = None

    def __post_init__(self) -> None:
        spec = scenario_spec(self.name)  # an unknown name fails here, before any work
        if self.sample is not None:  # so does a sample the scenario cannot take (above 1 for real orders)
            spec.check_sample(self.sample)
        object.__setattr__(self, "params", tuple(sorted(dict(self.params).items())))

    @property
    def overrides(self) -> dict[str, float]:
        return dict(self.params)

    def replace(self, **changes: Any) -> ScenarioRequest:
        """A copy with some fields changed; ``params`` may be given as a dict."""
        if isinstance(changes.get("params"), dict):
            changes["params"] = tuple(changes["params"].items())
        return dataclasses.replace(self, **changes)

    def with_overrides(self, overrides: dict[str, float]) -> ScenarioRequest:
        """This request with more parameter overrides (they win over the present ones)."""
        return self.replace(params={**self.overrides, **overrides})

    def resolved(self) -> ScenarioRequest:
        """This request with its data folder found now (``--data``, ``$RPBENCH_DATA``, the defaults: see
        :mod:`rpbench.files.paths`), so that every later build, in any worker process, reads the same folder; a
        scenario that needs no data is returned as it is."""
        if self.data_dir is not None or not scenario_spec(self.name).needs_data:
            return self
        spec = scenario_spec(self.name)
        return self.replace(data_dir=str(ensure_data_dir(None, what=f"scenario {self.name!r}", city=spec.city)))

    def build(self) -> Scenario:
        return build_scenario(
            self.name,
            data_dir=self.data_dir,
            date=self.date,
            sample=self.sample,
            seed=self.seed,
            param_overrides=self.overrides,
            fleet_placement=self.fleet_placement,
            city=self.city,
            window=self.window,
        )

    def meta(self) -> dict[str, Any]:
        """The request as recorded in a results folder (no machine path)."""
        city = {k: v for k, v in (("city", self.city), ("window", self.window)) if v is not None}
        return {
            "date": self.date,
            "sample": self.sample,
            "seed": self.seed,
            "params": self.overrides,
            "fleet_placement": self.fleet_placement,
            **city,  # only when given: a Haikou folder records what it recorded before cities existed
        }

    def dates(self, text: str) -> list[str]:
        """``A..B`` (the days in range the data folder has) or ``A,B,C`` (each must exist) for this scenario."""
        spec = scenario_spec(self.name)
        if spec.dates is None:
            raise ParameterError(f"--dates: scenario {self.name!r} has no dates to choose from")
        folder = ensure_data_dir(self.data_dir, what="--dates", city=spec.city)
        return parse_dates(text, spec.dates(folder))


def parse_dates(text: str, have: list[str]) -> list[str]:
    """``A..B`` (inclusive; the days in range that are in ``have``) or ``A,B,C`` (each must be in ``have``)."""
    if ".." in text:
        first, _, last = text.partition("..")
        a, b = parse_date(first.strip()), parse_date(last.strip())
        if b < a:
            raise ParameterError(f"--dates {text!r}: the range ends before it starts")
        dates = [d for d in have if a <= dt.date.fromisoformat(d) <= b]
        if not dates:
            raise ParameterError(f"--dates {text!r}: no data for a day in that range (available: {_span(have)})")
        return dates
    dates = [parse_date(d.strip()).isoformat() for d in text.split(",") if d.strip()]
    twice = sorted({d for d in dates if dates.count(d) > 1})
    if twice:
        raise ParameterError(f"--dates {text!r}: {', '.join(twice)} given twice; each day once")
    missing = [d for d in dates if d not in have]
    if missing or not dates:
        raise ParameterError(
            f"--dates {text!r}: no data for {', '.join(missing) or '(none)'} (available: {_span(have)})"
        )
    return dates


def _span(have: list[str]) -> str:
    if not have:
        return "none"
    return ", ".join(have) if len(have) <= 20 else f"{have[0]}..{have[-1]} ({len(have)} days)"
