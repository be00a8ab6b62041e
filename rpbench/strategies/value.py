"""VF: value-function dispatch (Xu et al., KDD 2018) on MB's assignment model.

Each option's MB weight (paper Eq. 7) gets the discounted value change of the vehicle it moves
(docs/value-function.md §3):

* vacant option (p, v ∈ V0): ``-pk + γ^(Δ/bin) V(d_p, t + Δ) - V(node_v, t)`` with
  ``Δ = (pk + l_p) / speed``, the time the vehicle needs to deliver p alone;
* join option (p, v ∈ V1): ``e - pk + γ^(Δ/bin) V(end, t + Δ) - V(node_v, t)``, ``end`` the pooled
  route's last drop-off (p's destination in FOFO, A's in FOLO) and ``Δ`` its remaining length / speed;
* keep waiting: ``-10⁶ m`` as MB (A13).

``V`` is the tabular value of :mod:`rpbench.valuefn`, learned by policy evaluation of MB on training
days (``model=auto``: trained on ``train_dates`` x ``train_seeds`` by the harness before the run, as it
calibrates FL, and cached: :mod:`rpbench.harness.training`) or loaded from a model folder written by
``rpbench train vf``.  With ``V ≡ 0`` the weights, and so the run, are MB's.  A model is never used on a
scenario it was trained on (:func:`rpbench.valuefn.training.check_held_out`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rpbench.exceptions import ParameterError
from rpbench.model import Structure
from rpbench.options import Range, option
from rpbench.scenarios.base import OnlineView, Scenario
from rpbench.strategies.base import RoundModel, RoundState, Strategy
from rpbench.strategies.candidates import NO_WAIT_UTILITY_M, assignment_round, join_options, vacant_options
from rpbench.strategies.myopic import PoolingOptions
from rpbench.valuefn.learn import LEARN_METHODS
from rpbench.valuefn.model import ValueModel, load_model
from rpbench.valuefn.training import Settings, check_held_out

#: The artefact name of the value model in a run's folder (``runs/vf/value-model/``).
VALUE_MODEL = "value-model"


@dataclass(frozen=True)
class ValueOptions(PoolingOptions):
    """VF's options: where its value comes from, and how an ``auto`` model is learned."""

    model: str = option("auto", "a model folder from `rpbench train vf`, or auto: train on train_dates (cached)")
    train_dates: str = option("2017-05-01..2017-05-07", "training days of an auto model (A..B or A,B,...)")
    train_seeds: tuple[int, ...] = option(
        (100,),
        "sample seeds of the training runs (an undated scenario: its seeds)",
        range=Range(0, 2**32 - 1, integer=True),
    )
    train_hours: int = option(
        3,
        "a city's one day (scenarios city, manhattan-*): the hours before the test window trained on, one run each",
        range=Range(1, 23, integer=True),
    )
    cell_m: float = option(1000.0, "side of a square cell of the value's grid", range=Range(50.0, 1e5, "m"))
    bin_s: float = option(600.0, "length of a time bin of the value", range=Range(30.0, 86400.0, "s"))
    discount: float = option(0.9, "discount γ per time bin", range=Range(0.0, 1.0, low_open=True))
    method: str = option(
        "exact", "policy evaluation: the exact batch TD(0) solution, or online TD(0)", choices=LEARN_METHODS
    )
    learning_rate: float = option(0.05, "TD(0) step size α (method td)", range=Range(0.0, 1.0, low_open=True))
    epochs: int = option(20, "TD(0) passes over the transitions (method td)", range=Range(1, 10_000, integer=True))
    iterations: int = option(
        1, "policy iterations: 1 evaluates MB; each further one evaluates vf itself", range=Range(1, 20, integer=True)
    )
    value_weight: float = option(1.0, "weight of the value change in each option's utility", range=Range(0.0, 1e3))

    def __post_init__(self) -> None:
        twice = sorted({s for s in self.train_seeds if self.train_seeds.count(s) > 1})
        if twice:
            raise ParameterError(
                f"vf: train_seeds {list(self.train_seeds)} names seed {twice[0]} twice; each training run once"
            )

    def settings(self) -> Settings:
        return Settings(
            cell_m=self.cell_m,
            bin_s=self.bin_s,
            discount=self.discount,
            method=self.method,
            learning_rate=self.learning_rate,
            epochs=self.epochs,
            iterations=self.iterations,
            order_rule=self.order_rule,
        )


class ValueFunction(Strategy[ValueOptions]):
    name = "vf"
    label = "VF"
    color = "tab:purple"
    structure = Structure.ASSIGNMENT
    Options = ValueOptions
    description = "value-function dispatch: MB's weights plus a learned V(cell, time) (Xu et al. 2018)"
    trained_by = "mb"

    def __init__(self, options: ValueOptions | None = None, **raw: Any):
        super().__init__(options, **raw)
        self.model: ValueModel | None = None
        self.model_digest = ""
        self.model_folder: Path | None = None

    @classmethod
    def with_model(cls, model: ValueModel, **raw: Any) -> ValueFunction:
        """A VF that uses ``model`` as it is (policy iteration, tests): nothing loaded or trained."""
        out = cls(**raw)
        out.model = model
        return out

    @property
    def needs_model(self) -> bool:
        """Whether the harness must train (or take from the cache) this run's value model: ``model=auto`` and
        none handed over yet (:func:`rpbench.harness.training.supply_model`)."""
        return self.model is None and self.options.model == "auto"

    def use_model(self, model: ValueModel, digest: str, folder: Path | None) -> None:
        """Dispatch with ``model`` (its digest and folder recorded as the run's artefact)."""
        self.model, self.model_digest, self.model_folder = model, digest, folder

    def prepare(self, scenario: Scenario | OnlineView) -> None:
        """The value model loaded from ``model=FOLDER`` and checked to fit the scenario's network and to be held
        out from it (an ``auto`` one is handed over, checked, by the harness)."""
        if self.model is None:
            if self.options.model == "auto":
                raise ParameterError(
                    "vf: model=auto is trained by the harness before the run (rpbench run, or "
                    "rpbench.run_comparison); elsewhere give a model folder from `rpbench train vf` (model=FOLDER)"
                )
            self.model_folder = Path(self.options.model)
            self.model, self.model_digest = load_model(self.model_folder)
            self.model.check_network(scenario.network, "vf")
            check_held_out(scenario, self.model.training)

    def next_policy(self, model: ValueModel) -> ValueFunction:
        """The policy of the next policy iteration: VF with ``model`` and this run's order rule."""
        return ValueFunction.with_model(model, order_rule=self.options.order_rule)

    def artefacts(self) -> dict[str, tuple[str, Path]]:
        if self.model_folder is None:
            return {}
        return {VALUE_MODEL: (self.model_digest, self.model_folder)}

    def build(self, state: RoundState) -> RoundModel:
        assert self.model is not None, "prepare() loads the model"
        vac = vacant_options(state)
        join = join_options(state, self.options.order_rule)
        t, speed, w = state.t_s, state.params.speed_mps, self.options.value_weight
        now_v0 = self.model.value_at(state.v0_node, t)
        now_v1 = self.model.value_at(state.v1_node, t)
        dt_vac = (vac.pickup_m + state.p_solo_m[vac.p]) / speed
        gain_vac = self._later(state.p_destination[vac.p], t, dt_vac) - now_v0[vac.v]
        end = np.where(join.fofo, state.p_destination[join.p], state.v1_destination[join.v])
        gain_join = self._later(end, t, join.remaining_m / speed) - now_v1[join.v]
        return assignment_round(
            state,
            vac,
            -vac.pickup_m + w * gain_vac,
            join,
            join.saving_m - join.pickup_m + w * gain_join,
            np.full(state.n_passengers, NO_WAIT_UTILITY_M),
            name=self.name,
        )

    def _later(self, node: np.ndarray, t_s: float, delay_s: np.ndarray) -> np.ndarray:
        """``γ^(Δ/bin) V(node, t + Δ)``: the value of being at ``node`` ``delay_s`` from now, discounted to now."""
        assert self.model is not None
        return self.model.discount ** (delay_s / self.model.bin_s) * self.model.value_at(node, t_s + delay_s)
