"""Training a value model by simulation: run the training policy on the training scenarios, collect its
vehicles' transitions, evaluate the policy (:mod:`rpbench.valuefn`).

The harness trains what a strategy's :attr:`~rpbench.strategies.base.Strategy.trained_by` names before the
run (:func:`supply_model`, as it calibrates FL from an MB run), so the value package needs neither the
simulator nor the strategies.  ``auto`` models are cached under ``<cache>/value-models/``
(:func:`cached_model`); ``rpbench train vf`` trains one into a folder of its own (:func:`train`).
"""

from __future__ import annotations

import shutil
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rpbench.backends import Preset, load_preset
from rpbench.exceptions import ParameterError
from rpbench.files.paths import cache_dir
from rpbench.results import metrics
from rpbench.scenarios.base import Scenario
from rpbench.sim.simulator import Simulator
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.myopic import MyopicBatch
from rpbench.strategies.value import ValueFunction
from rpbench.valuefn.cells import Grid
from rpbench.valuefn.learn import evaluate_policy
from rpbench.valuefn.model import MODEL_JSON, ValueModel, load_model, save_model_atomically
from rpbench.valuefn.training import (
    CACHE_FOLDER,
    Settings,
    check_held_out,
    training_key,
    training_record,
    training_scenarios,
)
from rpbench.valuefn.transitions import Observations, Transitions, transitions_of_run

#: Makes the policy a learned value dispatches with (policy iteration).
NextPolicy = Callable[[ValueModel], Strategy]


def supply_model(strategy: Strategy, scenario: Scenario, *, progress: bool | None = None) -> None:
    """Hand ``strategy`` the value model it dispatches with, when it is one whose
    :attr:`~rpbench.strategies.base.Strategy.trained_by` asks for one and none was given (``model=auto``):
    trained on the other days or seeds of ``scenario``'s generator (checked to be held out from it), or
    taken from the cache."""
    if type(strategy).trained_by is None or not isinstance(strategy, ValueFunction) or not strategy.needs_model:
        return
    options = strategy.options
    scenarios = training_scenarios(scenario, options.train_dates, options.train_seeds, options.train_hours)
    check_held_out(scenario, training_record(scenarios, options.settings()))
    model, digest, folder = cached_model(
        scenarios, options.settings(), next_policy=strategy.next_policy, progress=progress
    )
    model.check_network(scenario.network, "vf")
    strategy.use_model(model, digest, folder)


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


def cached_model(
    scenarios: list[Scenario],
    settings: Settings,
    *,
    next_policy: NextPolicy | None = None,
    progress: bool | None = None,
) -> tuple[ValueModel, str, Path]:
    """The model trained on ``scenarios`` with ``settings``: from the cache (its digests verified on load),
    or trained and stored there.  Returns the model, its digest and its folder."""
    folder = cache_dir() / CACHE_FOLDER / training_key(scenarios, settings)
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
