"""Independent verification of a results folder from its event logs alone.

For every simulated run the checker re-reads the orders, the network, the
event log and the vehicle trajectories stored in the folder (never the data
folder, never the simulator's state) and verifies:

* ``assigned-once`` — each order is assigned at most once, never after it
  was cancelled, and cancelled only when unassigned at request + K_p;
* ``within-patience`` — assignment happens between the request and request + K_p;
* ``service`` — every assigned passenger is picked up after assignment and
  dropped off after pick-up, by the assigned vehicle, and the vehicle passes
  the passenger's origin / destination node at exactly those times;
* ``max-pickup`` — pick-up distance <= R̄ (driven from the assignment, or
  from the partner's pick-up when the partner was collected first, A14);
* ``max-detour`` — ride distance - solo distance <= D̄ for every passenger;
* ``capacity`` — at most two passengers assigned-or-on-board at once, and
  at most two on board;
* ``movement`` — trajectories start at the vehicle's initial node, follow
  arcs of the network, with odometer steps equal to arc lengths and time
  steps equal to length / speed (never faster), times non-decreasing;
* ``kpi`` — every KPI recomputed from the log equals the reported one;
* ``bound-certificate`` — every pair the run formed is an edge of the upper
  bound's candidate graph (docs/bound.md: its requests within the window, the
  service order's detours <= D̄ with the vehicle at the first passenger's
  origin) and its realised saving, read off the odometers, is at most the edge
  weight (+ :data:`CERT_TOL_M`); with a ``bound`` run in the folder, the run's
  saving is at most the bound and its ``competitive_ratio_bound`` is that
  quotient.

Offline runs (``pairs.csv.gz``) are checked as matchings of feasible pairs
whose stored savings and KPIs are recomputed; the bound's pairs under the
bound's window and weight.

Distances are read off the trajectories at the matched event entries, not
recomputed by the simulator's code paths.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.geometry import pool
from rpbench.results import metrics
from rpbench.scenarios.base import Params

TOL_M = 1e-6
TOL_S = 1e-6
KPI_RTOL = 1e-9
#: Tolerance of the bound certificate: a realised saving may exceed its edge weight by float rounding only.
CERT_TOL_M = 1e-3


@dataclass
class RunCheck:
    run: str
    violations: dict[str, list[str]] = field(default_factory=dict)
    checked: dict[str, int] = field(default_factory=dict)

    def fail(self, check: str, message: str) -> None:
        self.violations.setdefault(check, []).append(message)

    @property
    def ok(self) -> bool:
        return not self.violations


def check_folder(folder: str | Path) -> list[RunCheck]:
    """Check every run of a results folder; return one :class:`RunCheck` per run."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ResultsError(f"results folder {str(folder)!r} does not exist")
    meta = results.read_meta(folder)
    names = results.run_names(folder)
    if not names:
        raise ResultsError(f"results folder {str(folder)!r} holds no runs (no runs/<name>/ folders)")
    params = Params(**meta["params"])
    orders = results.read_csv(folder / "orders.csv.gz")
    network = results.load_network(folder / "network.npz")
    fleet = results.read_csv(folder / "fleet.csv.gz")
    reported = results.read_csv(folder / "kpis.csv")
    distances = network.distances()
    dist = distances.dist
    solo = dist[orders["origin"].to_numpy(), orders["destination"].to_numpy()]
    bound_km = _bound_km(meta, reported)
    out = []
    for name in names:
        run_dir = folder / "runs" / name
        if (run_dir / "pairs.csv.gz").is_file():
            out.append(_check_oracle(name, run_dir, meta, orders, solo, distances, params,
                                     reported[reported["run"] == name]))
            continue
        rc = RunCheck(name)
        events = results.read_csv(run_dir / "events.csv.gz")
        traj = results.load_trajectories(run_dir / "trajectories.npz")
        _check_movement(rc, traj, network, fleet["initial_node"].to_numpy(), params)
        tab = _check_events(rc, events, orders, solo, traj, params)
        mine = reported[reported["run"] == name]
        _check_kpis(rc, events, orders, solo, traj, params, mine)
        _check_certificate(rc, tab, orders, solo, distances, params, mine, bound_km)
        rc.checked["orders"] = len(orders)
        rc.checked["served"] = int(tab["served"].sum())
        out.append(rc)
    return out


def _bound_km(meta: dict, reported: pd.DataFrame) -> float | None:
    """The reported upper bound (km) when the folder has a bound run (its own check verifies it)."""
    for name, run in meta.get("runs", {}).items():
        if run.get("kind") == "oracle" and run.get("rules", {}).get("window") == "bound":
            value = reported[(reported["run"] == name) & (reported["kpi"] == "total_saving_km")]["value"]
            return float(value.iloc[0]) if len(value) else float("nan")
    return None


# ------------------------------------------------------------------- movement
def _check_movement(rc: RunCheck, traj, network, initial: np.ndarray, params: Params) -> None:
    off = traj["vehicle_offsets"]
    nodes, t, odo = traj["node"].astype(np.int64), traj["t_s"], traj["odo_m"]
    if len(off) - 1 != len(initial):
        rc.fail("movement", f"{len(off) - 1} trajectories for {len(initial)} vehicles")
        return
    starts = off[:-1]
    bad_start = np.flatnonzero((nodes[starts] != initial) | (np.abs(t[starts]) > TOL_S))
    for v in bad_start[:5]:
        rc.fail("movement", f"vehicle {v} does not start at its initial node {initial[v]} at t=0")
    step = np.ones(len(nodes), dtype=bool)
    step[off[1:-1] - 1] = False               # no step across vehicles
    step[-1] = False
    i = np.flatnonzero(step)
    u, w = nodes[i], nodes[i + 1]
    dt, dodo = t[i + 1] - t[i], odo[i + 1] - odo[i]
    if (dt < -TOL_S).any():
        k = i[np.flatnonzero(dt < -TOL_S)[0]]
        rc.fail("movement", f"time runs backwards in trajectory entry {k}")
    stay = u == w
    if (np.abs(dodo[stay]) > TOL_M).any():
        rc.fail("movement", f"{int((np.abs(dodo[stay]) > TOL_M).sum())} standing steps change the odometer")
    move = ~stay
    arc = network.arc_index(u[move], w[move])
    if (arc < 0).any():
        k = np.flatnonzero(arc < 0)[0]
        rc.fail("movement", f"{int((arc < 0).sum())} steps are not network arcs, e.g. {u[move][k]} -> {w[move][k]}")
        return
    length = network.arc_length_m[arc]
    if (np.abs(dodo[move] - length) > TOL_M).any():
        rc.fail("movement", f"{int((np.abs(dodo[move] - length) > TOL_M).sum())} steps' odometer differs from the "
                            "arc length")
    too_fast = dt[move] < length / params.speed_mps - TOL_S
    if too_fast.any():
        rc.fail("movement", f"{int(too_fast.sum())} arcs driven faster than {params.speed_mps:.4f} m/s")
    rc.checked["trajectory_steps"] = int(len(i))


# --------------------------------------------------------------------- events
def _locate(traj, vehicle: np.ndarray, t: np.ndarray, node: np.ndarray) -> np.ndarray:
    """Odometer at the trajectory entry where ``vehicle`` is at ``node`` at time ``t`` (NaN if none)."""
    off = traj["vehicle_offsets"]
    out = np.full(len(vehicle), np.nan)
    for k, (v, tk, nk) in enumerate(zip(vehicle, t, node)):
        if v < 0 or not np.isfinite(tk):
            continue
        lo, hi = off[v], off[v + 1]
        ts = traj["t_s"][lo:hi]
        a = np.searchsorted(ts, tk - TOL_S, side="left")
        b = np.searchsorted(ts, tk + TOL_S, side="right")
        match = np.flatnonzero(traj["node"][lo + a:lo + b] == nk)
        if len(match):
            out[k] = traj["odo_m"][lo + a + match[0]]
    return out


def _check_events(rc: RunCheck, events: pd.DataFrame, orders: pd.DataFrame, solo: np.ndarray, traj,
                  params: Params) -> pd.DataFrame:
    n = len(orders)
    request = orders["request_s"].to_numpy()
    patience = orders["patience_s"].to_numpy()
    origin, dest = orders["origin"].to_numpy(), orders["destination"].to_numpy()
    if not np.allclose(orders["solo_m"].to_numpy(), solo, rtol=0, atol=1e-6):
        rc.fail("kpi", "stored solo distances differ from shortest paths on the stored network")

    def times(kind: str) -> tuple[np.ndarray, np.ndarray]:
        sel = events[events["event"] == kind]
        counts = np.bincount(sel["order"].to_numpy(), minlength=n)
        col = np.full(n, np.nan)
        col[sel["order"].to_numpy()] = sel["t_s"].to_numpy()
        veh = np.full(n, -1, dtype=np.int64)
        veh[sel["order"].to_numpy()] = sel["vehicle"].to_numpy()
        for o in np.flatnonzero(counts > 1)[:5]:
            rc.fail("assigned-once" if kind == "assign" else "service", f"order {o} has {counts[o]} {kind} events")
        return col, veh

    t_assign, v_assign = times("assign")
    t_pick, v_pick = times("pickup")
    t_drop, v_drop = times("dropoff")
    t_cancel, _ = times("cancel")
    assigned = ~np.isnan(t_assign)
    cancelled = ~np.isnan(t_cancel)
    for o in np.flatnonzero(assigned & cancelled)[:5]:
        rc.fail("assigned-once", f"order {o} is both assigned and cancelled")
    bad = cancelled & (np.abs(t_cancel - (request + patience)) > TOL_S)
    for o in np.flatnonzero(bad)[:5]:
        rc.fail("assigned-once", f"order {o} cancelled at {t_cancel[o]:.3f} s, not at request + patience")
    late = assigned & ((t_assign < request - TOL_S) | (t_assign - request > patience + TOL_S))
    for o in np.flatnonzero(late)[:5]:
        rc.fail("within-patience", f"order {o} assigned {t_assign[o] - request[o]:.2f} s after its request "
                                   f"(patience {patience[o]:.2f} s)")
    unresolved = ~assigned & ~cancelled
    if unresolved.any():
        rc.fail("service", f"{int(unresolved.sum())} orders are neither assigned nor cancelled")
    # service by the assigned vehicle, in order, at the right nodes
    not_served = assigned & (np.isnan(t_pick) | np.isnan(t_drop))
    for o in np.flatnonzero(not_served)[:5]:
        rc.fail("service", f"order {o} assigned but never picked up and dropped off")
    wrong = assigned & ~not_served & ((v_pick != v_assign) | (v_drop != v_assign))
    for o in np.flatnonzero(wrong)[:5]:
        rc.fail("service", f"order {o} served by another vehicle than the one assigned")
    order_bad = assigned & ~not_served & ((t_pick < t_assign - TOL_S) | (t_drop < t_pick - TOL_S))
    for o in np.flatnonzero(order_bad)[:5]:
        rc.fail("service", f"order {o}: pick-up before assignment or drop-off before pick-up")
    served = assigned & ~not_served
    odo_pick = _locate(traj, np.where(served, v_assign, -1), t_pick, origin)
    odo_drop = _locate(traj, np.where(served, v_assign, -1), t_drop, dest)
    missing = served & (np.isnan(odo_pick) | np.isnan(odo_drop))
    for o in np.flatnonzero(missing)[:5]:
        rc.fail("service", f"order {o}: vehicle {v_assign[o]} is not at the origin/destination node at the "
                           "pick-up/drop-off time")
    ok = served & ~missing
    ride = odo_drop - odo_pick
    detour = ride - solo
    over = ok & (detour > params.max_detour_m + TOL_M)
    for o in np.flatnonzero(over)[:5]:
        rc.fail("max-detour", f"order {o}: detour {detour[o]:.1f} m > D̄ = {params.max_detour_m:g} m")
    # pick-up distance (A14 rule: from the partner's pick-up when the partner came first)
    assign_ev = events[events["event"] == "assign"]
    partner = np.full(n, -1, dtype=np.int64)
    has = assign_ev["partner"].to_numpy() >= 0
    partner[assign_ev["order"].to_numpy()[has]] = assign_ev["partner"].to_numpy()[has]
    partner[assign_ev["partner"].to_numpy()[has]] = assign_ev["order"].to_numpy()[has]
    pair_bad = (partner >= 0) & (v_assign != v_assign[np.maximum(partner, 0)])
    for o in np.flatnonzero(pair_bad)[:5]:
        rc.fail("capacity", f"order {o} is paired with order {partner[o]} of another vehicle")
    p = np.maximum(partner, 0)
    partner_first = (partner >= 0) & (t_pick[p] <= t_pick + TOL_S) & ok & ok[p]
    start_t = np.where(partner_first, np.maximum(t_assign, t_pick[p]), t_assign)
    odo_start = metrics.odometer_at(traj, np.where(ok, v_assign, -1), start_t)
    pickup = odo_pick - odo_start
    far = ok & (pickup > params.max_pickup_m + TOL_M)
    for o in np.flatnonzero(far)[:5]:
        rc.fail("max-pickup", f"order {o}: pick-up distance {pickup[o]:.1f} m > R̄ = {params.max_pickup_m:g} m")
    _check_capacity(rc, v_assign, t_assign, t_pick, t_drop, served)
    rc.checked["events"] = int(len(events))
    return pd.DataFrame({"served": served, "ok": ok, "partner": partner, "t_pick": t_pick, "odo_pick": odo_pick,
                         "odo_drop": odo_drop})


def _check_capacity(rc: RunCheck, vehicle, t_assign, t_pick, t_drop, served) -> None:
    """At most 2 passengers assigned-or-on-board, and at most 2 on board, per vehicle at any time."""
    for label, start in (("assigned or on board", t_assign), ("on board", t_pick)):
        o = np.flatnonzero(served)
        if not len(o):
            return
        veh = np.concatenate([vehicle[o], vehicle[o]])
        t = np.concatenate([start[o], t_drop[o]])
        delta = np.concatenate([np.ones(len(o)), -np.ones(len(o))])
        # Drop-offs before starts at the same instant: a vehicle can hand over at a node.
        order = np.lexsort((delta, t, veh))
        veh, delta = veh[order], delta[order]
        load = np.zeros(len(veh))
        starts = np.r_[0, np.flatnonzero(np.diff(veh)) + 1, len(veh)]
        for a, b in zip(starts[:-1], starts[1:]):
            load[a:b] = np.cumsum(delta[a:b])
        if (load > 2).any():
            rc.fail("capacity", f"a vehicle has {int(load.max())} passengers {label} at once")


# ----------------------------------------------------------------------- KPIs
def _check_kpis(rc: RunCheck, events, orders, solo, traj, params: Params, reported: pd.DataFrame) -> None:
    if reported.empty:
        rc.fail("kpi", "no reported KPIs for this run in kpis.csv")
        return
    tab = metrics.passenger_table(events, solo, orders["request_s"].to_numpy(), traj)
    recomputed = metrics.kpis(tab, metrics.occupied_distance_m(events, traj), params)
    have = dict(zip(reported["kpi"], reported["value"]))
    for key, value in recomputed.items():
        if key not in have:
            rc.fail("kpi", f"KPI {key} is not reported")
            continue
        rep = float(have[key])
        if np.isnan(value) and np.isnan(rep):
            continue
        if not np.isclose(rep, value, rtol=KPI_RTOL, atol=1e-6):
            rc.fail("kpi", f"KPI {key}: reported {rep!r}, recomputed {value!r}")
    rc.checked["kpis"] = len(recomputed)


# ------------------------------------------------------------ bound certificate
def bound_weights(distances, orders: pd.DataFrame, solo: np.ndarray, params: Params, a: np.ndarray,
                  b: np.ndarray, a_first_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(weight, edge) of pairs (a, b) in the upper bound's graph (docs/bound.md), computed here pair by pair.

    With X picked up first and Y joining: ``t_Y - t_X`` in
    ``[-K_Y, K_X + (R̄ + l_X)/v]``; the vehicle turns at h*, the first node of
    X's shortest path within R̄ of o_Y, and h*'s predecessor on that path lies
    within ``v (t_Y + K_Y - t_X)`` of o_X; the service order's detours with the
    vehicle at h* (δ = its distance from o_X) are ``<= D̄``.  The weight is the
    largest such saving over the orientations (only a first: ``a_first_only``).
    ``distances`` is the folder network's DistanceOracle.
    """
    dist = distances.dist
    t = orders["request_s"].to_numpy()
    k = orders["patience_s"].to_numpy()
    o, d = orders["origin"].to_numpy(), orders["destination"].to_numpy()
    v, r_max = params.speed_mps, params.max_pickup_m
    weight = np.full(len(a), -np.inf)
    for x_all, y_all in ((a, b),) if a_first_only else ((a, b), (b, a)):
        for n, (x, y) in enumerate(zip(x_all, y_all)):
            gap = t[y] - t[x]
            if not -k[y] - TOL_S <= gap <= k[x] + (r_max + TOL_M + solo[x]) / v + TOL_S:
                continue
            path = distances.path_nodes(int(o[x]), int(d[x]))
            cum = dist[o[x], path]
            near = np.flatnonzero(dist[path, o[y]] <= r_max + TOL_M)
            if not len(near) or (near[0] > 0 and cum[near[0] - 1] > v * (t[y] + k[y] - t[x]) + TOL_M):
                continue
            h = int(near[0])
            r = pool(dist, o[x], d[x], o[y], d[y], h=path[h], delta=cum[h], pre=0.0, max_pickup_m=np.inf,
                     max_detour_m=params.max_detour_m, order_rule="min_feasible")
            if bool(r.feasible):
                weight[n] = max(weight[n], float(r.saving))
    return weight, np.isfinite(weight)


def _check_certificate(rc: RunCheck, tab: pd.DataFrame, orders: pd.DataFrame, solo: np.ndarray, distances,
                       params: Params, reported: pd.DataFrame, bound_km: float | None) -> None:
    """Every pair of the run is a bound edge whose weight covers its realised saving; saving <= bound."""
    partner, ok = tab["partner"].to_numpy(), tab["ok"].to_numpy()
    t_pick = tab["t_pick"].to_numpy()
    both = (partner >= 0) & ok & ok[np.maximum(partner, 0)]
    me = np.flatnonzero(both)
    first_me = (t_pick[me] < t_pick[partner[me]]) | ((t_pick[me] == t_pick[partner[me]]) & (me < partner[me]))
    a = me[first_me]                         # picked up first
    b = partner[a]
    odo_pick, odo_drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    occupied = np.maximum(odo_drop[a], odo_drop[b]) - odo_pick[a]
    realised = solo[a] + solo[b] - occupied
    weight, edge = bound_weights(distances, orders, solo, params, a, b)
    _, own_edge = bound_weights(distances, orders, solo, params, a, b, a_first_only=True)
    for k in np.flatnonzero(~own_edge)[:5]:
        rc.fail("bound-certificate", f"pair ({a[k]}, {b[k]}) is not an edge of the upper bound's graph with "
                                     f"order {a[k]} first (time window or detours at its origin)")
    over = edge & (realised > weight + CERT_TOL_M)
    for k in np.flatnonzero(over)[:5]:
        rc.fail("bound-certificate", f"pair ({a[k]}, {b[k]}): realised saving {realised[k]:.3f} m exceeds the "
                                     f"bound's edge weight {weight[k]:.3f} m")
    rc.checked["certified_pairs"] = int((own_edge & ~over).sum())
    if bound_km is None:
        return
    have = dict(zip(reported["kpi"], reported["value"]))
    saving = float(have.get("total_saving_km", np.nan))      # recomputed and compared by _check_kpis
    if not np.isfinite(bound_km):
        rc.fail("bound-certificate", "the folder's upper bound is not finite (its solver proved no bound)")
    elif saving > bound_km + CERT_TOL_M / 1000.0 * max(1, len(a)):
        rc.fail("bound-certificate", f"saving {saving:.3f} km exceeds the upper bound {bound_km:.3f} km")
    ratio = saving / bound_km if bound_km else float("nan")
    rep = float(have.get("competitive_ratio_bound", np.nan))
    if not (np.isnan(ratio) and np.isnan(rep)) and not np.isclose(rep, ratio, rtol=1e-6, atol=1e-9):
        rc.fail("kpi", f"KPI competitive_ratio_bound: reported {rep!r}, recomputed {ratio!r}")


# --------------------------------------------------------------------- oracle
def _check_oracle(name: str, run_dir: Path, meta: dict, orders: pd.DataFrame, solo: np.ndarray, distances,
                  params: Params, reported: pd.DataFrame) -> RunCheck:
    """An offline run: a matching of feasible pairs (§4.2, or the bound's) whose KPIs equal the reported ones."""
    rc = RunCheck(name)
    run = meta["runs"][name]
    rules = run["rules"]
    if rules.get("window") == "bound":
        return _check_bound(rc, run, run_dir, orders, solo, distances, params, reported)
    dist = distances.dist
    stored = _pairs_as_rows(rc, run_dir, orders)
    if stored is None:
        return rc
    pairs, a, b = stored
    req = orders["request_s"].to_numpy()
    direct = ~pairs["enroute"].to_numpy().astype(bool)
    gap = np.abs(req[b] - req[a])
    late = direct & (gap > rules["planner_patience_s"] + TOL_S)
    if late.any():
        rc.fail("oracle-pairs", f"{int(late.sum())} pairs of waiting orders request more than K̄ apart")
    # en-route pairs: the second order requests while the first rides (it boards at t + K̄, §4.2)
    early = ~direct & (gap <= rules["planner_patience_s"] - TOL_S)
    if early.any():
        rc.fail("oracle-pairs", f"{int(early.sum())} en-route pairs request before the first order could ride")
    if (~direct).any() and not rules["allow_enroute"]:
        rc.fail("oracle-pairs", "en-route pairs in an oracle whose rules do not allow them")
    o, d = orders["origin"].to_numpy(), orders["destination"].to_numpy()
    r = pool(dist, o[a[direct]], d[a[direct]], o[b[direct]], d[b[direct]],
             max_pickup_m=rules["max_pickup_m"] if rules["pickup_check"] else np.inf,
             max_detour_m=rules["max_detour_m"], order_rule=rules["order_rule"])
    if not r.feasible.all():
        rc.fail("oracle-pairs", f"{int((~r.feasible).sum())} pairs are not feasible under the rules")
    if not np.allclose(r.saving, pairs["saving_m"].to_numpy()[direct], rtol=0, atol=1e-6):
        rc.fail("oracle-pairs", "stored pair savings differ from the recomputed POOL savings")
    over = np.maximum(pairs["detour_first_m"], pairs["detour_second_m"]) > rules["max_detour_m"] + TOL_M
    if over.any():
        rc.fail("max-detour", f"{int(over.sum())} pairs detour a passenger by more than D̄")
    have = dict(zip(reported["kpi"], reported["value"]))
    n = len(orders)
    detours = np.concatenate([pairs["detour_first_m"], pairs["detour_second_m"]])
    recomputed = {"orders": n, "pairs": len(pairs), "pooled_passengers": 2 * len(pairs),
                  "pairing_ratio": 2 * len(pairs) / n if n else float("nan"),
                  "avg_detour_m": float(detours.mean()) if len(pairs) else float("nan"),
                  "avg_shared_m": float(pairs["shared_m"].mean()) if len(pairs) else float("nan"),
                  "total_saving_km": float(pairs["saving_m"].sum()) / 1000.0}
    for key, value in recomputed.items():
        rep = float(have.get(key, np.nan))
        if not (np.isnan(value) and np.isnan(rep)) and not np.isclose(rep, value, rtol=KPI_RTOL, atol=1e-6):
            rc.fail("kpi", f"KPI {key}: reported {rep!r}, recomputed {value!r}")
    rc.checked.update({"pairs": len(pairs), "orders": n})
    return rc


def _pairs_as_rows(rc: RunCheck, run_dir: Path, orders: pd.DataFrame):
    """(pairs, a, b): the stored pairs and their row positions, or None when they name unknown orders."""
    pairs = results.read_csv(run_dir / "pairs.csv.gz")
    index = pd.Series(np.arange(len(orders)), index=orders["order_id"].to_numpy())
    unknown = ~pairs["first_id"].isin(index.index) | ~pairs["second_id"].isin(index.index)
    if unknown.any():
        rc.fail("oracle-pairs", f"{int(unknown.sum())} pairs name unknown order ids")
        return None
    a = index[pairs["first_id"]].to_numpy()
    b = index[pairs["second_id"]].to_numpy()
    counts = np.bincount(np.concatenate([a, b]), minlength=len(orders))
    if (counts > 1).any():
        rc.fail("oracle-pairs", f"order {int(np.argmax(counts))} appears in {int(counts.max())} pairs")
    return pairs, a, b


def _check_bound(rc: RunCheck, run: dict, run_dir: Path, orders: pd.DataFrame, solo: np.ndarray, distances,
                 params: Params, reported: pd.DataFrame) -> RunCheck:
    """The upper bound: a matching of bound edges, each stored weight the largest realisable saving, and the
    reported bound the rounded-up optimum (or, when the solver stopped early, at least the matching's value)."""
    stored = _pairs_as_rows(rc, run_dir, orders)
    if stored is None:
        return rc
    pairs, a, b = stored
    weight, edge = bound_weights(distances, orders, solo, params, a, b)
    if not edge.all():
        rc.fail("oracle-pairs", f"{int((~edge).sum())} pairs are not edges of the upper bound's graph")
    if not np.allclose(weight[edge], pairs["saving_m"].to_numpy()[edge], rtol=0, atol=1e-6):
        rc.fail("oracle-pairs", "stored weights differ from the largest realisable savings recomputed here")
    unit = float(run.get("unit_m", 0.01))
    value_km = float(np.ceil(pairs["saving_m"].to_numpy() / unit).sum() * unit) / 1000.0
    have = dict(zip(reported["kpi"], reported["value"]))
    rep = float(have.get("total_saving_km", np.nan))
    if run.get("status") == "optimal":
        if not np.isclose(rep, value_km, rtol=KPI_RTOL, atol=1e-6):
            rc.fail("kpi", f"KPI total_saving_km (the bound): reported {rep!r}, recomputed {value_km!r}")
    elif not rep >= value_km - 1e-6:
        rc.fail("kpi", f"the reported bound {rep!r} km lies below its own matching's {value_km!r} km")
    n = len(orders)
    recomputed = {"orders": n, "pairs": len(pairs), "pooled_passengers": 2 * len(pairs)}
    for key, value in recomputed.items():
        if not np.isclose(float(have.get(key, np.nan)), value, rtol=KPI_RTOL, atol=1e-6):
            rc.fail("kpi", f"KPI {key}: reported {have.get(key)!r}, recomputed {value!r}")
    rc.checked.update({"pairs": len(pairs), "orders": n})
    return rc


def format_report(checks: list[RunCheck]) -> str:
    lines = []
    for rc in checks:
        if rc.ok:
            facts = ", ".join(f"{k} {v}" for k, v in rc.checked.items())
            lines.append(f"{rc.run}: OK ({facts})")
        else:
            lines.append(f"{rc.run}: FAILED")
            for check, messages in rc.violations.items():
                lines.append(f"  [{check}] {len(messages)} violation(s): {messages[0]}")
                for m in messages[1:3]:
                    lines.append(f"  [{check}]   {m}")
    return "\n".join(lines)
