"""The paper's Table 2 KPIs, computed from a run's event log and trajectories only.

Distances are read off the vehicles' odometers (trajectories) at event
times, so every figure is what the vehicles actually drove.  Definitions
(each KPI key below; "served" = assigned and delivered, "pooled" = served
and paired with another passenger in the same vehicle):

* ``response_rate`` — served / orders.
* ``pairing_ratio`` — pooled / served (share of responded passengers who
  were pooled).  The paper does not say which denominator it uses;
  ``pairing_ratio_of_orders`` = pooled / orders is the alternative (the
  oracle's 2|M|/|P| is the same number when every order is served).
* ``platform_profit_cny`` — fares minus driver pay: a served passenger pays
  5 CNY/km of solo distance, a pooled one 3.5 CNY/km of solo distance;
  drivers are paid 2 CNY/km of occupied driving.  The paper's text ("5 Yuan/km
  for solo-ride distance and 3.5 Yuan/km for shared distance") can also be
  read as 5 CNY/km of a passenger's un-shared ride and 3.5 CNY/km of its
  shared ride: ``platform_profit_alt_cny``.
* ``avg_response_time_s`` — mean assignment time minus request time (served).
* ``avg_pickup_time_s`` — mean pick-up time minus assignment time (served).
* ``avg_detour_m`` — mean ride distance minus solo distance (pooled).
* ``avg_shared_m`` — mean distance ridden with the partner on board (pooled).
* ``total_occupied_km`` — distance driven with at least one passenger on
  board (the paper's dist_total).
* ``total_saving_km`` — Σ solo distance of served passengers minus
  total_occupied_km (the paper's dist_save; = Σ over pairs of l_A + l_B - L, so exactly 0 when
  nothing was pooled).

:func:`state_spells` and :func:`count_at` / :func:`mean_count` give the run's timeline: how many
passengers wait, are served, ride pooled or have cancelled at any time, from the event log alone.
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd

from rpbench.scenarios.base import Params

KPI_ORDER = [
    "response_rate",
    "pairing_ratio",
    "platform_profit_cny",
    "avg_response_time_s",
    "avg_pickup_time_s",
    "avg_detour_m",
    "avg_shared_m",
    "total_occupied_km",
    "total_saving_km",
]
KPI_LABELS = {
    "response_rate": "Response rate",
    "pairing_ratio": "Pairing ratio",
    "platform_profit_cny": "Platform profit (CNY)",
    "avg_response_time_s": "Average response time (s)",
    "avg_pickup_time_s": "Average pick-up time (s)",
    "avg_detour_m": "Average detour distance (m)",
    "avg_shared_m": "Average shared distance (m)",
    "total_occupied_km": "Total driving distance with passenger(s) on board (km)",
    "total_saving_km": "Total distance saving due to ride-pooling (km)",
    "competitive_ratio_bound": "Competitive ratio (saving / proven upper bound)",
    "competitive_ratio_best_known": "Competitive ratio (saving / best known schedule)",
    "competitive_ratio_interval": "Competitive ratio: [saving / upper bound, saving / best known schedule]",
    "saving_over_oracle1": "Saving / Oracle-1 (paper's reference; not a bound)",
    "best_known_saving_km": "Best known schedule's saving, LB (km)",
    "bound_over_best_known": "Upper bound / best known saving (U / LB)",
    "matching_pairing_ratio": "Pairing ratio of the bound's matching (bounds nothing)",
    "matching_avg_detour_m": "Average detour in the bound's matching (m; bounds nothing)",
    "matching_avg_shared_m": "Average shared distance in the bound's matching (m; bounds nothing)",
    "decision_p50_s": "Decision time per round, median (s)",
    "decision_p95_s": "Decision time per round, 95th percentile (s)",
    "decision_max_s": "Decision time per round, maximum (s)",
    "rounds_over_dt": "Rounds slower than the batch interval",
    "rounds_over_budget": "Rounds slower than the decision budget",
}
#: The upper bound's matching described as a schedule would be: none of these bounds the runs' (only its total
#: saving bounds anything), so kpis.csv names them apart and the bound's column of a table shows "/" there.
BOUND_MATCHING_KPIS = {
    "pairing_ratio": "matching_pairing_ratio",
    "avg_detour_m": "matching_avg_detour_m",
    "avg_shared_m": "matching_avg_shared_m",
}
EXTRA_KPIS = [
    "orders",
    "served",
    "cancelled",
    "pooled_passengers",
    "pairs",
    "pairing_ratio_of_orders",
    "avg_pickup_distance_m",
    "platform_profit_alt_cny",
    "total_solo_served_km",
]


def odometer_at(traj: dict[str, np.ndarray], vehicle: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Odometer (m) of each ``vehicle`` at time ``t`` (linear between trajectory nodes)."""
    vehicle = np.asarray(vehicle, dtype=np.int64)
    t = np.asarray(t, dtype=np.float64)
    out = np.full(len(vehicle), np.nan)
    off = traj["vehicle_offsets"]
    for v in np.unique(vehicle[vehicle >= 0]):
        sel = vehicle == v
        lo, hi = off[v], off[v + 1]
        out[sel] = np.interp(t[sel], traj["t_s"][lo:hi], traj["odo_m"][lo:hi])
    return out


def passenger_table(
    events: pd.DataFrame, solo_m: np.ndarray, request_s: np.ndarray, traj: dict[str, np.ndarray]
) -> pd.DataFrame:
    """One row per order: times, vehicle, partner, and driven distances from the odometers."""
    n = len(solo_m)
    tab = pd.DataFrame({"request_s": request_s, "solo_m": solo_m})
    for name in ("assign", "pickup", "dropoff", "cancel"):
        sel = events[events["event"] == name]
        col = np.full(n, np.nan)
        col[sel["order"].to_numpy(dtype=np.int64)] = sel["t_s"].to_numpy(dtype=np.float64)
        tab[f"{name}_s"] = col
    assign = events[events["event"] == "assign"]
    vehicle = np.full(n, -1, dtype=np.int64)
    vehicle[assign["order"].to_numpy()] = assign["vehicle"].to_numpy()
    partner = np.full(n, -1, dtype=np.int64)
    has = assign["partner"].to_numpy() >= 0
    a_order, a_partner = assign["order"].to_numpy()[has], assign["partner"].to_numpy()[has]
    partner[a_order] = a_partner
    partner[a_partner] = a_order  # the first passenger of a join learns its partner too
    kind = np.full(n, "", dtype=object)
    kind[assign["order"].to_numpy()] = assign["kind"].to_numpy()
    tab["vehicle"], tab["partner"], tab["kind"] = vehicle, partner, kind
    served = ~np.isnan(tab["dropoff_s"].to_numpy())
    tab["served"] = served
    tab["pooled"] = served & (partner >= 0)
    odo_pick = odometer_at(traj, vehicle, tab["pickup_s"].to_numpy())
    odo_drop = odometer_at(traj, vehicle, tab["dropoff_s"].to_numpy())
    odo_assign = odometer_at(traj, vehicle, tab["assign_s"].to_numpy())
    tab["ride_m"] = odo_drop - odo_pick
    tab["detour_m"] = tab["ride_m"] - tab["solo_m"]
    # Pick-up distance: from the assignment, or from the partner's pick-up when the
    # partner was collected first (a join diverts at o_p', A14; the second request of a trip).
    p_idx = np.where(partner >= 0, partner, 0)
    partner_pick = np.where(partner >= 0, tab["pickup_s"].to_numpy()[p_idx], np.nan)
    partner_first = (partner >= 0) & (partner_pick <= tab["pickup_s"].to_numpy())
    start = np.where(partner_first, np.maximum(tab["assign_s"].to_numpy(), partner_pick), tab["assign_s"].to_numpy())
    odo_start = np.where(partner_first, odometer_at(traj, vehicle, start), odo_assign)
    tab["pickup_m"] = odo_pick - odo_start
    shared = np.full(n, np.nan)
    pooled = tab["pooled"].to_numpy()
    if pooled.any():
        pp = partner[pooled]
        begin = np.maximum(tab["pickup_s"].to_numpy()[pooled], tab["pickup_s"].to_numpy()[pp])
        end = np.minimum(tab["dropoff_s"].to_numpy()[pooled], tab["dropoff_s"].to_numpy()[pp])
        v = vehicle[pooled]
        shared[pooled] = np.maximum(0.0, odometer_at(traj, v, end) - odometer_at(traj, v, np.minimum(begin, end)))
    tab["shared_m"] = shared
    return tab


def occupied_distance_m(events: pd.DataFrame, traj: dict[str, np.ndarray]) -> np.ndarray:
    """Per vehicle, the distance driven with at least one passenger on board."""
    n_vehicles = len(traj["vehicle_offsets"]) - 1
    out = np.zeros(n_vehicles)
    ev = events[events["event"].isin(["pickup", "dropoff"])]
    if ev.empty:
        return out
    ev = ev.assign(delta=np.where(ev["event"] == "pickup", 1, -1))
    # Pick-ups before drop-offs at the same instant keep the load non-negative.
    ev = ev.sort_values(["vehicle", "t_s", "delta"], ascending=[True, True, False], kind="stable")
    veh = ev["vehicle"].to_numpy()
    t = ev["t_s"].to_numpy()
    load = np.zeros(len(ev), dtype=np.int64)
    starts = np.r_[0, np.flatnonzero(np.diff(veh)) + 1, len(ev)]
    for a, b in itertools.pairwise(starts):
        load[a:b] = np.cumsum(ev["delta"].to_numpy()[a:b])
    odo = odometer_at(traj, veh, t)
    # Distance between consecutive events of a vehicle counts when the load after the first is > 0.
    same = np.r_[veh[1:] == veh[:-1], False]
    seg = np.where(same & (load > 0), np.r_[odo[1:] - odo[:-1], 0.0], 0.0)
    np.add.at(out, veh, seg)
    return out


def kpis(tab: pd.DataFrame, occupied_m: np.ndarray, params: Params) -> dict[str, float]:
    """The KPI dictionary (keys in :data:`KPI_ORDER` and :data:`EXTRA_KPIS`)."""
    served = tab["served"].to_numpy()
    pooled = tab["pooled"].to_numpy()
    n = len(tab)
    n_served, n_pooled = int(served.sum()), int(pooled.sum())
    solo = tab["solo_m"].to_numpy()
    occupied_km = float(occupied_m.sum()) / 1000
    solo_served_km = float(solo[served].sum()) / 1000
    fare = np.where(pooled, params.fare_pooled_cny_per_km, params.fare_solo_cny_per_km)
    revenue = float((fare[served] * solo[served]).sum()) / 1000
    shared = np.nan_to_num(tab["shared_m"].to_numpy())
    ride = tab["ride_m"].to_numpy()
    revenue_alt = (
        float((params.fare_solo_cny_per_km * (ride - shared) + params.fare_pooled_cny_per_km * shared)[served].sum())
        / 1000
    )
    pay = params.driver_pay_cny_per_km * occupied_km

    def mean(x, mask):
        return float(np.mean(x[mask])) if mask.any() else float("nan")

    return {
        "orders": n,
        "served": n_served,
        "cancelled": int((~np.isnan(tab["cancel_s"].to_numpy())).sum()),
        "pooled_passengers": n_pooled,
        "pairs": n_pooled // 2,
        "response_rate": n_served / n if n else float("nan"),
        "pairing_ratio": n_pooled / n_served if n_served else float("nan"),
        "pairing_ratio_of_orders": n_pooled / n if n else float("nan"),
        "platform_profit_cny": revenue - pay,
        "platform_profit_alt_cny": revenue_alt - pay,
        "avg_response_time_s": mean((tab["assign_s"] - tab["request_s"]).to_numpy(), served),
        "avg_pickup_time_s": mean((tab["pickup_s"] - tab["assign_s"]).to_numpy(), served),
        "avg_pickup_distance_m": mean(tab["pickup_m"].to_numpy(), served),
        "avg_detour_m": mean(tab["detour_m"].to_numpy(), pooled),
        "avg_shared_m": mean(tab["shared_m"].to_numpy(), pooled),
        "total_occupied_km": occupied_km,
        "total_solo_served_km": solo_served_km,
        # Σ over pairs of l_A + l_B - L: no pair, no saving (the difference of two equal sums is float noise)
        "total_saving_km": solo_served_km - occupied_km if n_pooled else 0.0,
    }


#: A round's decision time: the strategy building its model, the solver building, solving and decoding it.
DECISION_PARTS = ("strategy_build_s", "solver_build_s", "solve_s", "extract_s")
#: The decision-time KPIs of a simulation run, from its rounds (rounds.csv.gz).
DECISION_KPIS = ("decision_p50_s", "decision_p95_s", "decision_max_s", "rounds_over_dt")
#: The rounds slower than the run's decision budget (``--decision-budget``): reported only with a budget.
BUDGET_KPI = "rounds_over_budget"
#: KPIs measured on the clock: they differ from one run of the same inputs to the next (every other KPI is
#: a function of the inputs and seeds alone).
TIMING_KPIS = (
    "wall_s",
    "prepare_s",
    *DECISION_KPIS,
    BUDGET_KPI,
    # an offline run's phases
    "candidates_s",
    "model_s",
    "build_s",
    "solve_s",
    "extract_s",
    "total_s",
)


def decision_kpis(rounds: pd.DataFrame, dt_s: float) -> dict[str, float]:
    """The median, 95th percentile (linear interpolation) and maximum of the rounds' decision times
    (:data:`DECISION_PARTS` summed), and how many rounds decided more slowly than the batch interval
    ``dt_s`` (a dispatcher must decide within it). No round: NaN times and 0 rounds."""
    if rounds.empty:
        return {"decision_p50_s": np.nan, "decision_p95_s": np.nan, "decision_max_s": np.nan, "rounds_over_dt": 0.0}
    decision = decision_times(rounds)
    p50, p95 = np.quantile(decision, [0.5, 0.95])
    return {
        "decision_p50_s": float(p50),
        "decision_p95_s": float(p95),
        "decision_max_s": float(decision.max()),
        "rounds_over_dt": float((decision > dt_s).sum()),
    }


def decision_times(rounds: pd.DataFrame) -> np.ndarray:
    """Each round's decision time (s): :data:`DECISION_PARTS` summed."""
    return rounds[list(DECISION_PARTS)].to_numpy(dtype=float).sum(axis=1)


def over_budget(rounds: pd.DataFrame, budget_s: float) -> np.ndarray:
    """Per round, whether it decided more slowly than ``budget_s`` (strictly, as ``rounds_over_dt``
    against Δt): the ``over_budget`` column of rounds.csv.gz, summed as :data:`BUDGET_KPI`."""
    return decision_times(rounds) > budget_s


def hourly(tab: pd.DataFrame, start_hour: int = 0) -> pd.DataFrame:
    """Per request hour: orders, response rate, pairing ratio, mean detour and shared distance,
    distance saving (each pair's l_A + l_B - L counted in the hour of its earlier request), and
    mean pick-up distance and time (the FL calibration inputs)."""
    hour = (tab["request_s"] // 3600).astype(int) + start_hour
    served = tab["served"]
    pooled = tab["pooled"]
    pair_saving = _lead_savings(tab)
    frame = pd.DataFrame(
        {
            "hour": hour,
            "served": served,
            "pooled": pooled,
            "detour_m": tab["detour_m"].where(pooled),
            "shared_m": tab["shared_m"].where(pooled),
            "saving_km": pair_saving / 1000,
            "pickup_m": tab["pickup_m"].where(served),
            "pickup_time_s": (tab["pickup_s"] - tab["assign_s"]).where(served),
        }
    )
    g = frame.groupby("hour")
    out = pd.DataFrame(
        {
            "orders": g.size(),
            "response_rate": g["served"].mean(),
            "pairing_ratio": g["pooled"].sum() / g["served"].sum().where(g["served"].sum() > 0),
            "avg_detour_m": g["detour_m"].mean(),
            "avg_shared_m": g["shared_m"].mean(),
            "total_saving_km": g["saving_km"].sum(),
            "avg_pickup_m": g["pickup_m"].mean(),
            "avg_pickup_time_s": g["pickup_time_s"].mean(),
        }
    )
    return out.reset_index()


def _pair_leads(tab: pd.DataFrame) -> np.ndarray:
    """Per order: whether it is its served pair's lower order index (each pair counted once)."""
    partner = tab["partner"].to_numpy()
    return tab["pooled"].to_numpy() & (partner > np.arange(len(tab)))


def _lead_savings(tab: pd.DataFrame) -> np.ndarray:
    """Per order: its pair's l_A + l_B - L on the pair's lower order index (0 on every other row)."""
    p = np.maximum(tab["partner"].to_numpy(), 0)
    return np.where(
        _pair_leads(tab), tab["solo_m"].to_numpy() + tab["solo_m"].to_numpy()[p] - _pair_length(tab, p), 0.0
    )


def pair_savings(tab: pd.DataFrame) -> pd.DataFrame:
    """One row per served pair: its vehicle, the time its last passenger was dropped off and its
    realised saving l_A + l_B - L (Eq. 5, read off the odometers), in order of the lower order index."""
    lead = np.flatnonzero(_pair_leads(tab))
    partner = tab["partner"].to_numpy()[lead]
    drop = tab["dropoff_s"].to_numpy()
    return pd.DataFrame(
        {
            "vehicle": tab["vehicle"].to_numpy()[lead],
            "done_s": np.maximum(drop[lead], drop[partner]),
            "saving_m": _lead_savings(tab)[lead],
        }
    )


def _pair_length(tab: pd.DataFrame, partner: np.ndarray) -> np.ndarray:
    """Vehicle distance from the pair's first pick-up to its last drop-off (= ride_a + ride_b - shared)."""
    ride = tab["ride_m"].to_numpy()
    shared = np.nan_to_num(tab["shared_m"].to_numpy())
    return ride + ride[partner] - shared


#: The passenger states of a run's timeline, each a set of spells (:func:`state_spells`).
TIMELINE_STATES = ("waiting", "serving", "pooled", "cancelled")


def state_spells(events: pd.DataFrame) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per state of :data:`TIMELINE_STATES`, the sorted start times and the sorted end times of the
    passengers' spells in it (an end of inf: the spell lasts past the log), from the event log alone:

    * ``waiting`` — from the request to the assignment or the cancellation;
    * ``serving`` — from the assignment to the drop-off;
    * ``pooled`` — on board with the partner on board too (from the later pick-up of the pair to the
      earlier drop-off; assign events name the partners, and the first passenger of a join learns its
      partner from the second's event, as in :func:`passenger_table`);
    * ``cancelled`` — from the cancellation on.

    An event at time t has happened at t: a spell is [start, end).
    """
    ev = events[events["event"].isin(["request", "assign", "pickup", "dropoff", "cancel"])]
    order = ev["order"].to_numpy(dtype=np.int64)
    n = int(order.max()) + 1 if len(order) else 0
    times: dict[str, np.ndarray] = {}
    for name in ("request", "assign", "pickup", "dropoff", "cancel"):
        sel = (ev["event"] == name).to_numpy()
        col = np.full(n, np.nan)
        col[order[sel]] = ev["t_s"].to_numpy(dtype=np.float64)[sel]
        times[name] = col
    assign = ev[ev["event"] == "assign"]
    partner = np.full(n, -1, dtype=np.int64)
    a_order = assign["order"].to_numpy(dtype=np.int64)
    a_partner = assign["partner"].to_numpy(dtype=np.int64)
    has = a_partner >= 0
    partner[a_order[has]] = a_partner[has]
    partner[a_partner[has]] = a_order[has]

    def ended(t: np.ndarray) -> np.ndarray:
        return np.where(np.isnan(t), np.inf, t)

    request, assigned, cancel = times["request"], times["assign"], times["cancel"]
    spells = {
        "waiting": (request, np.fmin(ended(assigned), ended(cancel))),
        "serving": (assigned, ended(times["dropoff"])),
        "cancelled": (cancel, np.full(n, np.inf)),
    }
    mate = np.flatnonzero(partner >= 0)
    pick, drop = times["pickup"], ended(times["dropoff"])
    begin = np.maximum(pick[mate], pick[partner[mate]])  # NaN (either never picked up): no spell
    end = np.minimum(drop[mate], drop[partner[mate]])
    spells["pooled"] = (begin, end)
    out = {}
    for state in TIMELINE_STATES:
        start, stop = spells[state]
        keep = ~np.isnan(start) & (stop > start)
        out[state] = (np.sort(start[keep]), np.sort(stop[keep]))
    return out


def count_at(spells: tuple[np.ndarray, np.ndarray], t: np.ndarray) -> np.ndarray:
    """How many of the spells (sorted starts, sorted ends) are under way at each time ``t``."""
    start, end = spells
    t = np.asarray(t, dtype=np.float64)
    return np.searchsorted(start, t, side="right") - np.searchsorted(end, t, side="right")


def mean_count(spells: tuple[np.ndarray, np.ndarray], edges: np.ndarray) -> np.ndarray:
    """The time average of :func:`count_at` over each bin [edges[i], edges[i + 1]) (exact, not sampled)."""
    start, end = spells
    edges = np.asarray(edges, dtype=np.float64)
    area = _time_since(start, edges) - _time_since(end, edges)
    return np.diff(area) / np.diff(edges)


def _time_since(sorted_t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Σ_i max(0, x - t_i) for each x: the integral up to x of the number of times t_i already passed."""
    k = np.searchsorted(sorted_t, x, side="right")
    finite = sorted_t[np.isfinite(sorted_t)]  # an inf time never passes (and would poison the sums)
    head = np.concatenate([[0.0], np.cumsum(finite)])
    return k * x - head[k]
