"""A simulation run's trajectories and event log: ``movement``, ``event-log``, ``assigned-once``,
``within-patience``, ``service``, ``max-pickup``, ``max-detour`` and ``capacity``.

:func:`check_events` also returns the per-order table (event times, vehicle, partner, odometers read at the
matched trajectory entries) that :mod:`.kpis` and :mod:`.certificate` read the run's figures off.
A zero-length trip (origin = destination) is never pooled (``service``), in folders whose scenario summary
counts such orders (``zero_length_orders``: written since the rule).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pandas as pd

from rpbench.check.core import EVENT_KINDS, TOL_M, TOL_S, RunCheck, show
from rpbench.check.folder import Folder
from rpbench.network import RoadNetwork
from rpbench.results.layout import ORDERS
from rpbench.scenarios.base import ZERO_LENGTH_KEY, Params

Trajectories = dict[str, np.ndarray]


# --------------------------------------------------------------------- movement
def check_movement(rc: RunCheck, traj: Trajectories, network: RoadNetwork, initial: np.ndarray, params: Params) -> bool:
    """Vehicles drive network arcs at no more than the set speed; False when the trajectories cannot even
    be split per vehicle (then nothing else of the run can be checked)."""
    off = traj["vehicle_offsets"].astype(np.int64)
    nodes, t, odo = traj["node"].astype(np.int64), traj["t_s"].astype(np.float64), traj["odo_m"].astype(np.float64)
    if len(off) - 1 != len(initial):
        rc.fail("movement", f"{len(off) - 1} trajectories for {len(initial)} vehicles")
        return False
    if off[0] != 0 or off[-1] != len(nodes) or (np.diff(off) < 1).any():
        rc.fail("movement", "the trajectory offsets do not split the entries into one non-empty trajectory per vehicle")
        return False
    bad = ~np.isfinite(t) | ~np.isfinite(odo)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        rc.fail(
            "movement",
            f"{int(bad.sum())} trajectory entries have a non-finite time or odometer (NaN or inf), "
            f"e.g. entry {k}: t = {show(t[k])}, odo = {show(odo[k])}",
        )
    outside = (nodes < 0) | (nodes >= network.n_nodes)
    if outside.any():
        rc.fail(
            "movement",
            f"{int(outside.sum())} trajectory entries name a node outside the network, e.g. "
            f"{nodes[np.flatnonzero(outside)[0]]}",
        )
    starts = off[:-1]
    bad_start = np.flatnonzero((nodes[starts] != initial) | ~(np.abs(t[starts]) <= TOL_S))
    for v in bad_start[:5]:
        rc.fail("movement", f"vehicle {v} does not start at its initial node {initial[v]} at t=0")
    step = np.ones(len(nodes), dtype=bool)
    step[off[1:] - 1] = False  # no step across vehicles (nor past the last entry)
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
    else:
        length = network.arc_length_m[arc]
        wrong = np.abs(dodo[move] - length) > TOL_M
        if wrong.any():
            k = np.flatnonzero(wrong)[0]
            rc.fail(
                "movement",
                f"{int(wrong.sum())} steps' odometer differs from the arc length, e.g. entry "
                f"{i[move][k]}: {dodo[move][k]:.3f} m on an arc of {length[k]:.3f} m",
            )
        too_fast = dt[move] < length / params.speed_mps - TOL_S
        if too_fast.any():
            rc.fail("movement", f"{int(too_fast.sum())} arcs driven faster than {params.speed_mps:.4f} m/s")
    rc.checked["trajectory_steps"] = len(i)
    return True


def _by_vehicle(vehicle: np.ndarray) -> Iterator[tuple[int, np.ndarray]]:
    """(vehicle, positions) groups of the queries with ``vehicle >= 0``: one vectorised step per vehicle."""
    q = np.flatnonzero(vehicle >= 0)
    q = q[np.argsort(vehicle[q], kind="stable")]
    cut = np.flatnonzero(np.diff(vehicle[q])) + 1
    for group in np.split(q, cut) if len(q) else []:
        yield int(vehicle[group[0]]), group


def _locate(traj: Trajectories, vehicle: np.ndarray, t: np.ndarray, node: np.ndarray) -> np.ndarray:
    """Odometer at the trajectory entry where ``vehicle`` is at ``node`` within TOL_S of time ``t`` (NaN if none)."""
    off, ts, nodes, odo = traj["vehicle_offsets"], traj["t_s"], traj["node"], traj["odo_m"]
    vehicle = np.where(np.isfinite(t), vehicle, -1)
    lo = np.zeros(len(vehicle), dtype=np.int64)
    hi = np.zeros(len(vehicle), dtype=np.int64)
    for v, group in _by_vehicle(vehicle):
        a, b = off[v], off[v + 1]
        lo[group] = a + np.searchsorted(ts[a:b], t[group] - TOL_S, side="left")
        hi[group] = a + np.searchsorted(ts[a:b], t[group] + TOL_S, side="right")
    out = np.full(len(vehicle), np.nan)
    active = np.flatnonzero(lo < hi)
    while len(active):  # entries within TOL_S of t: a handful per query
        k = lo[active]
        hit = nodes[k] == node[active]
        out[active[hit]] = odo[k[hit]]
        lo[active] += 1
        active = active[~hit & (lo[active] < hi[active])]
    return out


def _odometer_at(traj: Trajectories, vehicle: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Odometer of ``vehicle`` at time ``t``, linear between trajectory entries (NaN where vehicle < 0)."""
    off = traj["vehicle_offsets"]
    out = np.full(len(vehicle), np.nan)
    for v, group in _by_vehicle(np.where(np.isnan(t), -1, vehicle)):
        a, b = off[v], off[v + 1]
        out[group] = np.interp(t[group], traj["t_s"][a:b], traj["odo_m"][a:b])
    return out


# -------------------------------------------------------------------- event log
def check_event_log(rc: RunCheck, events: pd.DataFrame, f: Folder, n_vehicles: int) -> pd.DataFrame:
    """Every event names things that exist; returns the events that do (the others fail ``event-log``)."""
    kind = events["event"].to_numpy()
    order, vehicle = events["order"].to_numpy(), events["vehicle"].to_numpy()
    node, partner, t = events["node"].to_numpy(), events["partner"].to_numpy(), events["t_s"].to_numpy()
    n = f.n
    known = np.isin(kind, EVENT_KINDS)
    of_order = known & (kind != "reposition")
    unvehicled = np.isin(kind, ("request", "cancel"))
    problems = {
        "an unknown event kind": ~known,
        "a time that is not finite": known & ~np.isfinite(t),
        f"an order outside 0..{n - 1}": of_order & ((order < 0) | (order >= n)),
        "an order (a reposition names none)": (kind == "reposition") & (order != -1),
        f"a vehicle outside 0..{n_vehicles - 1}": known & ~unvehicled & ((vehicle < 0) | (vehicle >= n_vehicles)),
        "a vehicle (a request or cancellation names none)": unvehicled & (vehicle != -1),
        "a node outside the network": known & (kind != "assign") & ((node < 0) | (node >= f.network.n_nodes)),
        "a partner that is not another order": (partner != -1)
        & ((kind != "assign") | (partner < 0) | (partner >= n) | (partner == order)),
    }
    valid = np.ones(len(events), dtype=bool)
    for what, bad in problems.items():
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            rc.fail(
                "event-log",
                f"{int(bad.sum())} events name {what}, e.g. row {k + 2}: {kind[k]} of order "
                f"{order[k]}, vehicle {vehicle[k]}, node {node[k]}, partner {partner[k]} "
                f"at t={show(t[k])}",
            )
            valid &= ~bad
    ev = events[valid]
    _check_event_places(rc, ev, f)
    return ev


def _check_event_places(rc: RunCheck, ev: pd.DataFrame, f: Folder) -> None:
    """One request per order, at its request time; requests, pick-ups and cancellations at the origin,
    drop-offs at the destination (the node column of the log is what a reader of it sees)."""
    origin, dest, request = f.col("origin"), f.col("destination"), f.col("request_s")
    req = ev[ev["event"] == "request"]
    counts = np.bincount(req["order"].to_numpy(), minlength=f.n)
    wrong = np.flatnonzero(counts != 1)
    if len(wrong):
        rc.fail(
            "event-log",
            f"{len(wrong)} orders do not have exactly one request event, e.g. order {wrong[0]}: {counts[wrong[0]]}",
        )
    o, t = req["order"].to_numpy(), req["t_s"].to_numpy()
    late = np.flatnonzero(np.abs(t - request[o]) > TOL_S)
    if len(late):
        k = late[0]
        rc.fail(
            "event-log",
            f"{len(late)} request events are not at the order's request time, e.g. order {o[k]}: "
            f"{t[k]:.3f} s in the log, {request[o[k]]:.3f} s in {ORDERS}",
        )
    for kind, where, label in (
        ("request", origin, "origin"),
        ("pickup", origin, "origin"),
        ("cancel", origin, "origin"),
        ("dropoff", dest, "destination"),
    ):
        sel = ev[ev["event"] == kind]
        o, node = sel["order"].to_numpy(), sel["node"].to_numpy()
        bad = np.flatnonzero(node != where[o])
        if len(bad):
            k = bad[0]
            rc.fail(
                "event-log",
                f"{len(bad)} {kind} events are not at the order's {label}, e.g. order {o[k]} at "
                f"node {node[k]}, its {label} is {where[o[k]]}",
            )


# ----------------------------------------------------------------------- events
def check_events(rc: RunCheck, events: pd.DataFrame, f: Folder, traj: Trajectories) -> pd.DataFrame:
    """The service rules, and the per-order table (times, vehicle, partner, odometers) the KPIs are read off."""
    n, params = f.n, f.params
    request, patience = f.col("request_s"), f.col("patience_s")
    origin, dest = f.col("origin"), f.col("destination")

    def times(kind: str) -> tuple[np.ndarray, np.ndarray]:
        sel = events[events["event"] == kind]
        o = sel["order"].to_numpy()
        counts = np.bincount(o, minlength=n)
        col = np.full(n, np.nan)
        col[o] = sel["t_s"].to_numpy()
        veh = np.full(n, -1, dtype=np.int64)
        veh[o] = sel["vehicle"].to_numpy()
        for k in np.flatnonzero(counts > 1)[:5]:
            rc.fail("assigned-once" if kind == "assign" else "service", f"order {k} has {counts[k]} {kind} events")
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
        rc.fail(
            "within-patience",
            f"order {o} assigned {t_assign[o] - request[o]:.2f} s after its request (patience {patience[o]:.2f} s)",
        )
    unresolved = ~assigned & ~cancelled
    if unresolved.any():
        rc.fail(
            "service",
            f"{int(unresolved.sum())} orders are neither assigned nor cancelled, e.g. order "
            f"{np.flatnonzero(unresolved)[0]}",
        )
    orphan = ~assigned & (~np.isnan(t_pick) | ~np.isnan(t_drop))
    for o in np.flatnonzero(orphan)[:5]:
        rc.fail("service", f"order {o} is picked up or dropped off but never assigned")
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
        rc.fail(
            "service",
            f"order {o}: vehicle {v_assign[o]} is not at the origin/destination node at the pick-up/drop-off time",
        )
    ok = served & ~missing
    detour = odo_drop - odo_pick - f.solo
    over = ok & (detour > params.max_detour_m + TOL_M)
    for o in np.flatnonzero(over)[:5]:
        rc.fail("max-detour", f"order {o}: detour {detour[o]:.1f} m > D̄ = {params.max_detour_m:g} m")
    partner = _partners(rc, events, n, assigned)
    p = np.maximum(partner, 0)
    pair_bad = (partner >= 0) & (v_assign != v_assign[p])
    for o in np.flatnonzero(pair_bad)[:5]:
        rc.fail("capacity", f"order {o} is paired with order {partner[o]} of another vehicle")
    if ZERO_LENGTH_KEY in (f.meta.get("scenario", {}).get("summary") or {}):  # written under the rule
        zero = (partner >= 0) & (np.minimum(f.solo, f.solo[p]) <= TOL_M)
        for o in np.flatnonzero(zero & (partner > np.arange(n)))[:5]:
            rc.fail("service", f"orders {o} and {partner[o]} are pooled, but one is a zero-length trip (origin = "
                    "destination), which is served solo only")  # fmt: skip
    # pick-up distance (A14 rule: from the partner's pick-up when the partner came first)
    partner_first = (partner >= 0) & (t_pick[p] <= t_pick + TOL_S) & ok & ok[p]
    start_t = np.where(partner_first, np.maximum(t_assign, t_pick[p]), t_assign)
    odo_start = _odometer_at(traj, np.where(ok, v_assign, -1), start_t)
    pickup = odo_pick - odo_start
    far = ok & (pickup > params.max_pickup_m + TOL_M)
    for o in np.flatnonzero(far)[:5]:
        rc.fail("max-pickup", f"order {o}: pick-up distance {pickup[o]:.1f} m > R̄ = {params.max_pickup_m:g} m")
    _check_capacity(rc, v_assign, t_assign, t_pick, t_drop, served)
    rc.checked["events"] = len(events)
    return pd.DataFrame(
        {
            "request_s": request,
            "vehicle": v_assign,
            "assign_s": t_assign,
            "pickup_s": t_pick,
            "dropoff_s": t_drop,
            "cancelled": cancelled,
            "served": served,
            "ok": ok,
            "partner": partner,
            "odo_pick": odo_pick,
            "odo_drop": odo_drop,
            "odo_start": odo_start,
        }
    )


def _partners(rc: RunCheck, events: pd.DataFrame, n: int, assigned: np.ndarray) -> np.ndarray:
    """Each order's partner (-1: none).  The joining passenger's assignment names the first one (who may
    name it back): every named pair is two assigned orders, and no order is in two pairs."""
    a = events[events["event"] == "assign"]
    order, named = a["order"].to_numpy(), a["partner"].to_numpy()
    has = named >= 0
    lo, hi = np.minimum(order[has], named[has]), np.maximum(order[has], named[has])
    _, first = np.unique(lo * max(n, 1) + hi, return_index=True)  # a pair named from both sides counts once
    lo, hi = lo[first], hi[first]
    count = np.bincount(np.concatenate([lo, hi]), minlength=n)
    clash = (count[lo] > 1) | (count[hi] > 1) | ~assigned[lo] | ~assigned[hi]
    for k in np.flatnonzero(clash)[:5]:
        rc.fail(
            "event-log",
            f"orders {lo[k]} and {hi[k]} are named partners, but one of them is unassigned or "
            "named in another pair too",
        )
    partner = np.full(n, -1, dtype=np.int64)
    partner[lo[~clash]] = hi[~clash]
    partner[hi[~clash]] = lo[~clash]
    return partner


def _check_capacity(
    rc: RunCheck,
    vehicle: np.ndarray,
    t_assign: np.ndarray,
    t_pick: np.ndarray,
    t_drop: np.ndarray,
    served: np.ndarray,
) -> None:
    """At most 2 passengers assigned-or-on-board, and at most 2 on board, per vehicle at any time."""
    o = np.flatnonzero(served)
    if not len(o):
        return
    for label, start in (("assigned or on board", t_assign), ("on board", t_pick)):
        veh = np.concatenate([vehicle[o], vehicle[o]])
        # A drop-off up to TOL_S after a start is at the same instant (float noise in summed arc times): the
        # simulator processes the stops due by a round before deciding it.
        t = np.concatenate([start[o], t_drop[o] - TOL_S])
        delta = np.concatenate([np.ones(len(o)), -np.ones(len(o))])
        # Drop-offs before starts at the same instant: a vehicle can hand over at a node.
        srt = np.lexsort((delta, t, veh))
        load = pd.Series(delta[srt]).groupby(veh[srt]).cumsum().to_numpy()
        if (load > 2).any():
            rc.fail("capacity", f"a vehicle has {int(load.max())} passengers {label} at once")
