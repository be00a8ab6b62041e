"""How a value model's training is described, kept apart and cached: the settings, the training scenarios,
the record ``model.json`` keeps of them, the held-out rule and the cache key.

The policy is MB (paper Eq. 7) first; with ``iterations`` > 1, each further iteration simulates ``vf``
with the value just learned and evaluates that policy instead (approximate policy iteration).  The
training scenarios are the test scenario's generator on other days (``train_dates``) and seeds
(``train_seeds``): :func:`training_scenarios` builds them and :func:`check_held_out` refuses to run a
model on a scenario it was trained on.  The runs themselves are simulated by the harness
(:mod:`rpbench.harness.training`), which caches ``auto`` models under ``<cache>/value-models/``, keyed by
:func:`training_key`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import NoOrdersError, ParameterError
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.scenarios.city import parse_window, window_text
from rpbench.scenarios.registry import build_scenario, scenario_spec
from rpbench.scenarios.request import parse_dates
from rpbench.units import HOUR_S

CACHE_FOLDER = "value-models"
#: Bumped when training would give other values for the same inputs (the cache key holds it).
TRAINING_VERSION = 1


@dataclass(frozen=True)
class Settings:
    """How a value is learned (the ``vf`` options of the same names)."""

    cell_m: float = 1000.0
    bin_s: float = 600.0
    discount: float = 0.9
    method: str = "exact"
    learning_rate: float = 0.05
    epochs: int = 20
    iterations: int = 1
    order_rule: str = "min_feasible"
    solver: str = "highs"


def training_scenarios(
    like: Scenario | OnlineView, dates: str, seeds: tuple[int, ...], hours: int = 3
) -> list[Scenario]:
    """The scenarios of ``like``'s generator, sample and parameters on ``dates`` (``A..B`` or ``A,B``; a
    generator without dates ignores them) at each of ``seeds``; for a scenario of a city's one day, the
    ``hours`` hours before its window instead of other days (each a run of one hour)."""
    spec = scenario_spec(like.name)
    data_dir = like.demand.data_dir
    if "window" in like.provenance:
        return _earlier_hours(like, seeds, hours)
    days: list[str | None] = [None]
    if spec.dates is not None:
        if data_dir is None:
            raise ParameterError(f"vf: scenario {like.name!r} names no data folder to find its training days in")
        days = list(parse_dates(dates, spec.dates(Path(data_dir))))
    extra = {k: like.provenance[k] for k in ("fleet_placement", "size") if k in like.provenance}
    sample = like.provenance.get("sample")
    return [
        build_scenario(like.name, data_dir=data_dir, date=day, sample=sample, seed=seed, params=like.params, **extra)
        for day in days
        for seed in seeds
    ]


def _earlier_hours(like: Scenario | OnlineView, seeds: tuple[int, ...], hours: int) -> list[Scenario]:
    """One-hour scenarios of the ``hours`` hours before ``like``'s window on the same day of its city."""
    start, _ = parse_window(like.provenance["window"])
    first = max(0.0, start - hours * HOUR_S)
    windows = [window_text(s, s + HOUR_S) for s in np.arange(first, start, HOUR_S)]
    city = {"city": like.provenance["city_source"]} if like.provenance.get("city_source") else {}
    runs = []
    for w in windows:
        for seed in seeds:
            try:
                runs.append(
                    build_scenario(
                        like.name,
                        data_dir=like.demand.data_dir,
                        window=w,
                        sample=like.provenance.get("sample"),
                        seed=seed,
                        params=like.params,
                        fleet_placement=like.provenance.get("fleet_placement"),
                        **city,
                    )
                )
            except NoOrdersError:  # an hour without trips teaches nothing
                continue
    if not runs:
        raise ParameterError(
            f"vf: the {hours} hour(s) before the window {like.provenance['window']} hold no trips of the city's day "
            "to train on; test a later window, train on more hours (--opt vf.train_hours=N) or give a trained "
            "model (--opt vf.model=FOLDER)"
        )
    return runs


def held_out_problem(scenario: Scenario | OnlineView, training: dict[str, Any]) -> str | None:
    """Why ``scenario`` is one a model with this ``training`` record was trained on (None: it is not)."""
    if training.get("scenario") != scenario.name:
        return None
    date = scenario.provenance.get("date")
    runs = training.get("runs", [])
    window = scenario.provenance.get("window")
    if window is not None:  # a city's day: no training hour may overlap the tested window
        start, end = parse_window(window)
        for r in runs:
            if r.get("window") and _overlap(parse_window(r["window"]), (start, end)):
                return f"its training hour {r['window']} overlaps the window {window}"
        return None
    if date is not None:
        if date in {r.get("date") for r in runs}:
            return f"{date} is one of its training days"
        return None
    if any(r.get("seed") == scenario.seed and r.get("sample") == scenario.provenance.get("sample") for r in runs):
        return f"seed {scenario.seed} is one of its training seeds"
    return None


def _overlap(a: tuple[float, float], b: tuple[float, float]) -> bool:
    return a[0] < b[1] and b[0] < a[1]


def check_held_out(scenario: Scenario | OnlineView, training: dict[str, Any]) -> None:
    """One :class:`ParameterError` line when ``scenario`` is one a model with this ``training`` record saw."""
    problem = held_out_problem(scenario, training)
    if problem is not None:
        raise ParameterError(
            f"vf: the value model was trained on this scenario ({problem}); test on held-out days, seeds or "
            "hours, or train on others (--opt vf.train_dates=..., vf.train_seeds=..., vf.train_hours=...)"
        )


def training_record(scenarios: list[Scenario], settings: Settings) -> dict[str, Any]:
    """What model.json says of the training (no machine path, no clock)."""
    return {
        "scenario": scenarios[0].name,
        "runs": [
            {
                "date": s.provenance.get("date"),
                "seed": s.seed,
                "sample": s.provenance.get("sample"),
                "orders": len(s.orders),
                **({"window": s.provenance["window"]} if "window" in s.provenance else {}),
            }
            for s in scenarios
        ],
        "policy": _policy_text(settings.iterations),
        "settings": asdict(settings),
    }


def _policy_text(iterations: int) -> str:
    more = iterations - 1
    return "mb" if more == 0 else f"mb, then vf ({more} policy iteration{'s' if more > 1 else ''})"


def training_key(scenarios: list[Scenario], settings: Settings) -> str:
    """A digest of what determines the trained model: the training scenarios' content and the settings."""
    h = hashlib.sha256()
    h.update(json.dumps({"version": TRAINING_VERSION, "settings": asdict(settings)}, sort_keys=True).encode())
    for s in scenarios:
        h.update(
            json.dumps(
                [s.name, s.seed, s.horizon_s, s.network.content_hash, s.params.as_dict()], sort_keys=True
            ).encode()
        )
        o = s.orders
        for arr in (o.request_s, o.origin, o.destination, o.patience_s, s.fleet.initial_node):
            h.update(np.ascontiguousarray(arr).tobytes())
        for schedule in (s.fleet.online_times_s, s.fleet.online_count):
            if schedule is not None:
                h.update(np.ascontiguousarray(schedule).tobytes())
    return h.hexdigest()[:24]
