"""The seeker/taker pairing-probability and expected-saving prediction model.

This is the TR-B 2021 model as used by the seed paper's forward-looking (FL)
dispatcher (paper §3.1-3.3 and Appendix A; docs/algorithms.md §2 with the typos
corrected and resolutions A1-A12).

Public API (what the FL / FL-no_delay strategies call)::

    from rpbench.predict import OdRates, PredictConfig, predict, month_rates

    rates = load_rates("month", network, data_dir)          # or "day" (+date), "day-table", a CSV path;
                                                            # or scenario_rates(scenario) / OdRates.from_arrays
    prediction = predict(network, rates, params, PredictConfig(tau0_s=120.0))   # cached on disk

    look = prediction.lookup(origin_nodes, destination_nodes)
    look.e_vacant      # ē(p): expected saving if matched with a vacant vehicle (Eq. 9)
    look.p_seeker      # p_s(w)
    look.e_seeker      # ē(s(w)) (Eq. 11)
    look.pairing_prob  # P_w
    look.known         # OD present in the rate table (else every value is 0, §2.1)

    prediction.e_wait(origin_nodes, destination_nodes, k_p, params)
        # ē(0,p) of Eq. (10): [1 - (1 - r_w)^n_rem] [p_s ē(s) + (1 - p_s) ē(p)],
        # n_rem = max(0, floor(K̄/Δt) - k_p), K̄ = params.planner_patience_s, r_w = params.response_rate

    prediction.per_od_table()   # pandas DataFrame, one row per OD (P_w, p_s, ē values, distances)
    prediction.summary()        # dict: ODs, states, candidate pairs, iterations, residual, converged, ...

Node arguments are the network's *internal* node indices (as in
:class:`rpbench.scenarios.base.Orders`).  Savings are the pair's total distance
saving in metres (A12: not doubled).

Modules, one concept each: :mod:`.rates` (λ_w), :mod:`.config`,
:mod:`.states` (seeker/taker states, taker classes), :mod:`.match_sets`
(T_s, E, priority), :mod:`.blocks` (the lists' class blocks),
:mod:`.list_cache` (states and lists, cached once per machine),
:mod:`.fixed_point` ((A1)-(A6) and the damped solver), :mod:`.kernels` (its
compiled sweeps), :mod:`.savings` (ē and expected distances),
:mod:`.prediction` (the entry point), :mod:`.hourly` (one prediction per
scenario hour: what FL calls), :mod:`.cache` (solved predictions),
:mod:`.fcfs` (validation simulator), :mod:`.compare` (vs the
authors' published predictions).
"""

from rpbench.predict.config import ACCELERATIONS, PRIORITIES, RHO_MODES, PredictConfig
from rpbench.predict.hourly import RATE_SOURCES, scenario_predictions
from rpbench.predict.prediction import (
    Lookup,
    Prediction,
    PredictionModel,
    build_prediction_model,
    cached_prediction,
    predict,
    solve_prediction_model,
)
from rpbench.predict.rates import (
    RATE_KINDS,
    OdRates,
    day_table_rates,
    load_rates,
    month_rates,
    order_rates,
    peak_order_rates,
    scenario_rates,
    table_rates,
)

__all__ = [
    "ACCELERATIONS",
    "PRIORITIES",
    "RATE_KINDS",
    "RATE_SOURCES",
    "RHO_MODES",
    "Lookup",
    "OdRates",
    "PredictConfig",
    "Prediction",
    "PredictionModel",
    "build_prediction_model",
    "cached_prediction",
    "day_table_rates",
    "load_rates",
    "month_rates",
    "order_rates",
    "peak_order_rates",
    "predict",
    "scenario_predictions",
    "scenario_rates",
    "solve_prediction_model",
    "table_rates",
]
