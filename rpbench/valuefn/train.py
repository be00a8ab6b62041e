"""Training a value model: simulate a policy on training scenarios, collect transitions, evaluate it.

The policy is MB (paper Eq. 7) first; with ``iterations`` > 1, each further iteration simulates ``vf``
with the value just learned and evaluates that policy instead (approximate policy iteration).  The
training scenarios are the test scenario's generator on other days (``train_dates``) and seeds
(``train_seeds``): :func:`training_scenarios` builds them and :func:`check_held_out` refuses to run a
model on a scenario it was trained on.  ``auto`` models are cached under ``<cache>/value-models/``,
keyed by the content of the training scenarios and the settings (:func:`cached_model`).
"""

from __future__ import annotations

import hashlib
import json
import shutil
import sys
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.backends import Preset, load_preset
from rpbench.exceptions import ParameterError
from rpbench.paths import cache_dir
from rpbench.results import metrics
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.scenarios.registry import build_scenario, scenario_spec
from rpbench.scenarios.request import parse_dates
from rpbench.sim.simulator import Simulator
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.myopic import MyopicBatch
from rpbench.valuefn.cells import Grid
from rpbench.valuefn.learn import evaluate_policy
from rpbench.valuefn.model import MODEL_JSON, ValueModel, load_model, save_model_atomically
from rpbench.valuefn.transitions import Observations, Transitions, transitions_of_run

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


def training_scenarios(like: Scenario | OnlineView, dates: str, seeds: tuple[int, ...]) -> list[Scenario]:
    """The scenarios of ``like``'s generator, sample and parameters on ``dates`` (``A..B`` or ``A,B``; a
    generator without dates ignores them) at each of ``seeds``."""
    spec = scenario_spec(like.name)
    data_dir = like.demand.data_dir
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


def held_out_problem(scenario: Scenario | OnlineView, training: dict[str, Any]) -> str | None:
    """Why ``scenario`` is one a model with this ``training`` record was trained on (None: it is not)."""
    if training.get("scenario") != scenario.name:
        return None
    date = scenario.provenance.get("date")
    runs = training.get("runs", [])
    if date is not None:
        if date in {r.get("date") for r in runs}:
            return f"{date} is one of its training days"
        return None
    if any(r.get("seed") == scenario.seed and r.get("sample") == scenario.provenance.get("sample") for r in runs):
        return f"seed {scenario.seed} is one of its training seeds"
    return None


def check_held_out(scenario: Scenario | OnlineView, training: dict[str, Any]) -> None:
    """One :class:`ParameterError` line when ``scenario`` is one a model with this ``training`` record saw."""
    problem = held_out_problem(scenario, training)
    if problem is not None:
        raise ParameterError(
            f"vf: the value model was trained on this scenario ({problem}); test on held-out days or seeds, "
            "or train on others (--opt vf.train_dates=..., vf.train_seeds=...)"
        )


#: Makes the policy a learned value dispatches with (policy iteration): the strategy layer gives it, so that
#: this package does not import the strategies that import it.
NextPolicy = Callable[[ValueModel], Strategy]


def train(
    scenarios: list[Scenario],
    settings: Settings,
    *,
    next_policy: NextPolicy | None = None,
    progress: bool | None = None,
) -> ValueModel:
    """Learn V from simulations of the training ``scenarios`` (all on one network); ``next_policy`` (needed when
    ``settings.iterations`` > 1) turns a learned value into the policy of the next iteration."""
    if settings.iterations > 1 and next_policy is None:
        raise ParameterError("vf: policy iteration needs the policy a value dispatches with (next_policy)")
    if not scenarios:
        raise ParameterError("vf: no training scenarios")
    network = scenarios[0].network
    if any(s.network.content_hash != network.content_hash for s in scenarios):
        raise ParameterError("vf: the training scenarios are on different road networks")
    horizon = max(s.horizon_s for s in scenarios)
    grid = Grid.of(network, settings.cell_m, settings.bin_s, horizon)
    preset = load_preset(settings.solver)
    model: ValueModel | None = None
    for iteration in range(settings.iterations):
        parts = []
        for k, scenario in enumerate(scenarios):
            _note(
                progress, f"vf training: iteration {iteration + 1}/{settings.iterations}, run {k + 1}/{len(scenarios)}"
            )
            policy: Strategy = MyopicBatch(order_rule=settings.order_rule)
            if model is not None and next_policy is not None:  # checked above: iterations > 1 has one
                policy = next_policy(model)
            parts.append(simulate_transitions(scenario, policy, preset, grid, settings.discount))
        values, visits = evaluate_policy(
            Transitions.concat(parts),
            grid,
            method=settings.method,
            learning_rate=settings.learning_rate,
            epochs=settings.epochs,
        )
        model = ValueModel(
            values=values,
            visits=visits,
            node_cell=grid.node_cell,
            cell_m=grid.cell_m,
            bin_s=grid.bin_s,
            discount=settings.discount,
            network=network.content_hash,
            training=training_record(scenarios, settings),
        )
    assert model is not None  # iterations >= 1
    return model


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
            }
            for s in scenarios
        ],
        "policy": _policy_text(settings.iterations),
        "settings": asdict(settings),
    }


def _policy_text(iterations: int) -> str:
    more = iterations - 1
    return "mb" if more == 0 else f"mb, then vf ({more} policy iteration{'s' if more > 1 else ''})"


def simulate_transitions(
    scenario: Scenario, policy: Strategy, preset: Preset, grid: Grid, discount: float
) -> Transitions:
    """Simulate ``policy`` on ``scenario`` and return its vehicles' transitions."""
    log: list[tuple[float, np.ndarray, np.ndarray]] = []
    sim = Simulator(scenario, recording(policy, log), preset).run()
    o = scenario.orders
    solo = scenario.network.distances()(o.origin, o.destination)
    tab = metrics.passenger_table(sim.events, solo, o.request_s, sim.trajectories)
    return transitions_of_run(Observations.of_rounds(log), metrics.pair_savings(tab), grid, discount)


def recording(strategy: Strategy, log: list[tuple[float, np.ndarray, np.ndarray]]) -> Strategy:
    """``strategy`` with every round's vacant vehicles and their nodes appended to ``log`` (its decisions
    unchanged: the same class, options and state, one method wrapped)."""
    base = type(strategy)

    def build(self: Strategy, state: RoundState) -> RoundModel:
        log.append((state.t_s, state.v0_vehicle.copy(), state.v0_node.copy()))
        return base.build(self, state)

    recorder = type(f"Recording{base.__name__}", (base,), {"build": build})
    out: Strategy = object.__new__(recorder)
    out.__dict__.update(strategy.__dict__)
    return out


def cache_key(scenarios: list[Scenario], settings: Settings) -> str:
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


def cached_model(
    scenarios: list[Scenario],
    settings: Settings,
    *,
    next_policy: NextPolicy | None = None,
    progress: bool | None = None,
) -> tuple[ValueModel, str, Path]:
    """The model trained on ``scenarios`` with ``settings``: from the cache (its digests verified on load),
    or trained and stored there.  Returns the model, its digest and its folder."""
    folder = cache_dir() / CACHE_FOLDER / cache_key(scenarios, settings)
    if (folder / MODEL_JSON).is_file():
        try:
            model, digest = load_model(folder)
            return model, digest, folder
        except ParameterError as exc:  # a damaged cache entry is retrained, saying so
            _note(True, f"rebuilding the cached value model: {exc}")
            shutil.rmtree(folder, ignore_errors=True)
    if folder.exists():  # a leftover without model.json (a full disk, say): not a model
        shutil.rmtree(folder, ignore_errors=True)
    model = train(scenarios, settings, next_policy=next_policy, progress=progress)
    digest = save_model_atomically(model, folder)
    return model, digest, folder


def _note(enabled: bool | None, text: str) -> None:
    if enabled is None:
        enabled = sys.stderr.isatty()
    if enabled:
        print(text, file=sys.stderr, flush=True)
