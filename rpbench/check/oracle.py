"""Oracle runs (``pairs.csv.gz``): ``oracle-rules``, ``oracle-pairs``, ``max-detour`` and ``kpi``.

Each pair's time window, feasibility, service and pick-up order, saving, route length, detours, shared and
pick-up distances are recomputed from the orders and the folder's network (:mod:`.certificate`'s
geometry), en-route pairs included; the KPIs are recomputed from the recomputed pairs, the solver's
objective re-summed, its other claims tested for consistency.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.check.certificate import Geometry, bound_geometry, edge_weights, first_true, order_paths
from rpbench.check.core import (
    DETOUR_TOL_M,
    HOURLY_COLUMNS,
    PAIR_COLUMNS,
    RULE_FLAGS,
    RULE_NUMBERS,
    TOL_M,
    TOL_S,
    RunCheck,
    as_number,
    same,
)
from rpbench.check.folder import Folder, read_results_table
from rpbench.check.kpis import compare_kpis
from rpbench.check.matching import bound_graph, prove_maximum, unit_values
from rpbench.results.layout import META, ORDERS, PAIRS
from rpbench.results.metrics import BOUND_MATCHING_KPIS
from rpbench.results.ratios import BRACKET_KPIS
from rpbench.scenarios.base import Params


def check_oracle(f: Folder, name: str, run_dir: Path) -> tuple[RunCheck, pd.DataFrame | None]:
    """An offline run: a matching of feasible pairs (§4.2, or the bound's) whose stored figures and KPIs
    are recomputed here."""
    rc = RunCheck(name)
    rec = f.meta["runs"][name]
    rules = _oracle_rules(rc, rec["rules"], f.params)
    pairs = read_results_table(run_dir / PAIRS, PAIR_COLUMNS)
    rows = _pair_rows(rc, pairs, f)
    if rows is None:
        rc.skip("kpi", "the pairs name unknown orders (see [oracle-pairs])")
        return rc, None
    a, b = rows
    request = f.col("request_s")
    for col, which in (("first_request_s", a), ("second_request_s", b)):
        bad = np.flatnonzero(~(np.abs(pairs[col].to_numpy() - request[which]) <= TOL_S))  # NaN is wrong too
        if len(bad):
            rc.fail("oracle-pairs", f"{len(bad)} pairs' stored {col} differ from {ORDERS}'s request times")
    fofo = pairs["service_order"].to_numpy() == "FOFO"
    strange = ~np.isin(pairs["service_order"].to_numpy(), ("FOFO", "FOLO"))
    if strange.any():
        rc.fail("oracle-pairs", f"{int(strange.sum())} pairs have a service order other than FOFO/FOLO")
    if rules["window"] == "bound":
        route = _check_bound_pairs(rc, pairs, a, b, fofo, f)
    else:
        route = _check_paper_pairs(rc, rules, pairs, a, b, fofo, f)
    _check_stored_route(rc, pairs, route)
    over = np.flatnonzero(np.maximum(route["detour_x"], route["detour_y"]) > f.params.max_detour_m + TOL_M)
    if len(over):
        rc.fail(
            "max-detour",
            f"{len(over)} pairs detour a passenger by more than D̄ = {f.params.max_detour_m:g} m, "
            f"e.g. pair ({pairs['first_id'].iloc[over[0]]}, {pairs['second_id'].iloc[over[0]]})",
        )
    recomputed, claims = _oracle_kpis(rec, rules, pairs, route, f, f.reported(name))
    compare_kpis(rc, "oracle", recomputed, f.reported(name), claims)
    rc.checked.update({"pairs": len(pairs), "orders": f.n})
    if rules["window"] != "bound":
        return rc, None
    check_bound_optimal(rc, f, float(rec.get("unit_m", 0.01)), f.reported(name))
    hour = np.floor(np.minimum(request[a], request[b]) / 3600.0).astype(np.int64)
    by_hour = pd.Series(pairs["saving_m"].to_numpy() / 1000.0).groupby(hour).sum()
    table = pd.DataFrame({column: np.nan for column in HOURLY_COLUMNS}, index=by_hour.index)
    table["total_saving_km"] = by_hour  # the bound's rows of hourly.csv: only its matching's saving
    return rc, table


def check_bound_optimal(rc: RunCheck, f: Folder, unit_m: float, reported: pd.DataFrame) -> None:
    """``bound-optimal``: the reported bound U is at least the maximum-weight matching of the bound's graph
    as the checker enumerates it (:mod:`.matching`): a bound lowered below the optimum, or computed on a
    graph missing some pairs, fails here."""
    value = reported.loc[reported["kpi"] == "total_saving_km", "value"]
    bound_km = as_number(value.iloc[0]) if len(value) else None
    if bound_km is None or not np.isfinite(bound_km):
        rc.skip("bound-optimal", "the run reports no finite bound (see [kpi])")
        return
    a, b, weight = bound_graph(f)
    values = unit_values(weight, unit_m)
    keep = values > 0  # an edge worth nothing never raises a matching's weight
    target = bound_km * 1000.0 / unit_m
    proof = prove_maximum(f.n, a[keep], b[keep], values[keep], target)
    tol = 1e-9 * max(1.0, abs(target))
    if proof.best > target + tol:
        rc.fail(
            "bound-optimal",
            f"a matching of the bound's graph (enumerated here: {int(keep.sum())} pairs of positive weight) saves "
            f"{proof.best * unit_m / 1000.0:.3f} km, more than the reported bound {bound_km:.3f} km: "
            "the bound is not the maximum",
        )
    elif not proof.upper < np.floor(target + tol) + 1 - 1e-6:
        rc.fail(
            "bound-optimal",
            f"no proof that the reported bound {bound_km:.3f} km covers every matching of the bound's graph: "
            f"the best upper bound found is {proof.upper * unit_m / 1000.0:.3f} km ({proof.method})",
        )
    rc.checked["bound_graph_pairs"] = len(a)
    rc.checked["odd_sets"] = proof.odd_sets
    if proof.mip_edges is not None:
        rc.checked["mip_edges"] = proof.mip_edges  # decided by HiGHS's MIP, on its own claim


def _oracle_rules(rc: RunCheck, recorded: dict, params: Params) -> dict:
    """The rules the pairs are checked by: K̄, D̄, R̄ and v are the folder's parameters (a rule recorded
    otherwise fails ``oracle-rules`` and is not used); the flags are the run's."""
    for key in RULE_NUMBERS:
        if not same(float(recorded[key]), float(getattr(params, key)), rtol=1e-12, atol=1e-9):
            rc.fail(
                "oracle-rules", f"rule {key} = {recorded[key]!r} is not the folder's parameter {getattr(params, key)!r}"
            )
    rules: dict[str, float | bool | str] = {key: float(getattr(params, key)) for key in RULE_NUMBERS}
    rules.update({key: bool(recorded[key]) for key in RULE_FLAGS})
    rules["order_rule"] = recorded.get("order_rule", "min_feasible")
    rules["window"] = recorded.get("window", "patience")
    if rules["order_rule"] not in ("min_feasible", "min_then_check"):
        rc.fail("oracle-rules", f"unknown order rule {rules['order_rule']!r}")
        rules["order_rule"] = "min_feasible"
    if rules["window"] not in ("patience", "bound"):
        rc.fail("oracle-rules", f"unknown pair window {rules['window']!r}")
        rules["window"] = "patience"
    if rules["window"] == "bound" and (
        rules["pickup_check"]
        or rules["allow_enroute"]
        or not rules["both_pickup_orders"]
        or rules["order_rule"] != "min_feasible"
    ):
        rc.fail(
            "oracle-rules",
            "the upper bound's rules are fixed (both pick-up orders, no pick-up test, no "
            f"en-route geometry, the best feasible service order); {META} records others",
        )
    return rules


def _pair_rows(rc: RunCheck, pairs: pd.DataFrame, f: Folder) -> tuple[np.ndarray, np.ndarray] | None:
    """(a, b): the row positions of each pair's first and second order, or None when they name unknown ids."""
    index = pd.Series(np.arange(f.n), index=f.col("order_id"))
    unknown = ~pairs["first_id"].isin(index.index) | ~pairs["second_id"].isin(index.index)
    if unknown.any():
        k = int(np.flatnonzero(unknown.to_numpy())[0])
        rc.fail(
            "oracle-pairs",
            f"{int(unknown.sum())} pairs name order ids that are not in {ORDERS}, e.g. "
            f"({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]})",
        )
        return None
    a = index[pairs["first_id"]].to_numpy()
    b = index[pairs["second_id"]].to_numpy()
    if (a == b).any():
        rc.fail("oracle-pairs", f"{int((a == b).sum())} pairs pair an order with itself")
    counts = np.bincount(np.concatenate([a, b]), minlength=f.n)
    if (counts > 1).any():
        rc.fail("oracle-pairs", f"order {int(np.argmax(counts))} appears in {int(counts.max())} pairs")
    return a, b


def _check_paper_pairs(
    rc: RunCheck, rules: dict, pairs: pd.DataFrame, a: np.ndarray, b: np.ndarray, fofo: np.ndarray, f: Folder
) -> dict[str, np.ndarray]:
    """The paper's oracles (§4.2): waiting pairs request within K̄ of each other, the vehicle at the first
    order's origin; en-route pairs (allow_enroute) join the first order's ride at the next node of its path
    after ``s = v (t_b - t_a - K̄)``, ``0 < s < l_a``.  Returns the pairs recomputed in the stored order."""
    t, k_bar, v = f.col("request_s"), rules["planner_patience_s"], rules["speed_mps"]
    enroute = pairs["enroute"].to_numpy()
    gap = t[b] - t[a]
    s = v * (gap - k_bar)
    waiting = ~enroute
    ids = (pairs["first_id"].to_numpy(), pairs["second_id"].to_numpy())

    def fail(mask: np.ndarray, what: str) -> None:
        if mask.any():
            k = int(np.flatnonzero(mask)[0])
            rc.fail(
                "oracle-pairs",
                f"{int(mask.sum())} pairs {what}, e.g. ({ids[0][k]}, {ids[1][k]}) requested {gap[k]:.0f} s apart",
            )

    fail(waiting & (np.abs(gap) > k_bar + TOL_S), f"of waiting orders request more than K̄ = {k_bar:g} s apart")
    in_window = (gap > k_bar) & (s > 0) & (s < f.solo[a])
    fail(
        enroute & ~in_window,
        "are en-route pairs outside the en-route window (the second order requests after K̄, while the first one rides)",
    )
    if not rules["allow_enroute"]:
        fail(enroute, "are en-route pairs in an oracle whose rules do not allow them")
    if not rules["both_pickup_orders"]:
        later_first = (gap < 0) | ((gap == 0) & (ids[0] > ids[1]))
        fail(waiting & later_first, "pick the later order up first, which the rules do not allow")
    h, delta, pre = f.col("origin")[a].astype(np.int64), np.zeros(len(a)), np.zeros(len(a))
    en = np.flatnonzero(enroute & in_window)
    if len(en):
        off, nodes, cum = order_paths(f, a[en])
        first = first_true(cum >= np.repeat(s[en], np.diff(off)), off)  # the next node at or after s
        first = np.where(first < 0, off[1:] - 1, first)  # s < l_a: never, but no crash
        h[en], delta[en] = nodes[first], cum[first]
        pre[en] = delta[en] - s[en]
    g = Geometry.of(f, a, b, h, delta, pre, rules["max_detour_m"])
    route = g.served(fofo)
    feasible = route["ok"] & ((route["pk"] <= rules["max_pickup_m"] + DETOUR_TOL_M) | (not rules["pickup_check"]))
    fail(~feasible, "are not feasible under the rules (a detour > D̄, or a pick-up > R̄ with pickup_check)")
    chosen = g.rule_order(rules["order_rule"])
    fail(
        (chosen != fofo) & (np.abs(g.fofo_len - g.folo_len) > TOL_M),
        f"are not served in the order the rule {rules['order_rule']} picks",
    )
    if rules["both_pickup_orders"] and waiting.any():
        o_b = f.col("origin")[b].astype(np.int64)
        rev = Geometry.of(f, b, a, o_b, np.zeros(len(a)), np.zeros(len(a)), rules["max_detour_m"])
        other = rev.served(rev.rule_order(rules["order_rule"]))
        other_ok = other["ok"] & ((other["pk"] <= rules["max_pickup_m"] + DETOUR_TOL_M) | (not rules["pickup_check"]))
        fail(
            waiting & other_ok & (other["saving"] > route["saving"] + TOL_M),
            "are not in the pick-up order of the larger saving (§4.2: both orders tried, the larger wins)",
        )
    return route


def _check_bound_pairs(
    rc: RunCheck, pairs: pd.DataFrame, a: np.ndarray, b: np.ndarray, fofo: np.ndarray, f: Folder
) -> dict[str, np.ndarray]:
    """The upper bound's pairs: edges of its graph in the stored orientation, of the largest weight."""
    allowed, g = bound_geometry(f, f.params, a, b)
    route = g.served(fofo)
    not_edge = ~(allowed & route["ok"])
    if not_edge.any():
        k = int(np.flatnonzero(not_edge)[0])
        rc.fail(
            "oracle-pairs",
            f"{int(not_edge.sum())} pairs are not edges of the upper bound's graph with the "
            f"stored first order, e.g. ({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]})",
        )
    weight, _ = edge_weights(f, a, b)
    stored = pairs["saving_m"].to_numpy()
    if not np.allclose(weight[~not_edge], stored[~not_edge], rtol=0, atol=TOL_M):
        rc.fail("oracle-pairs", "stored weights differ from the largest realisable savings recomputed here")
    off = ~not_edge & (
        (g.rule_order("min_feasible") != fofo) & (np.abs(g.fofo_len - g.folo_len) > TOL_M)
        | (route["saving"] < weight - TOL_M)
    )
    if off.any():
        rc.fail(
            "oracle-pairs", f"{int(off.sum())} pairs are not in the orientation and service order of the largest weight"
        )
    return route


STORED_ROUTE = (
    ("saving_m", "saving"),
    ("length_m", "length"),
    ("detour_first_m", "detour_x"),
    ("detour_second_m", "detour_y"),
    ("shared_m", "shared"),
    ("pickup_m", "pk"),
)


def _check_stored_route(rc: RunCheck, pairs: pd.DataFrame, route: dict[str, np.ndarray]) -> None:
    """The figures pairs.csv.gz stores are the recomputed ones."""
    for column, key in STORED_ROUTE:
        stored = pairs[column].to_numpy()
        bad = ~np.isclose(stored, route[key], rtol=0, atol=TOL_M)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            rc.fail(
                "oracle-pairs",
                f"{int(bad.sum())} pairs' stored {column} differ from the recomputed ones, e.g. "
                f"({pairs['first_id'].iloc[k]}, {pairs['second_id'].iloc[k]}): stored "
                f"{stored[k]:.3f} m, recomputed {route[key][k]:.3f} m",
            )


def _oracle_kpis(
    rec: dict, rules: dict, pairs: pd.DataFrame, route: dict[str, np.ndarray], f: Folder, reported: pd.DataFrame
) -> tuple[dict[str, float], dict[str, str | None]]:
    """(recomputed KPIs, solver claims -> failure message or None).  The objective is the matching's value
    in model units (savings rounded to ``unit_m``; the bound's rounded up, docs/bound.md)."""
    n, count = f.n, len(pairs)
    unit = float(rec.get("unit_m", 0.01))
    stored = pairs["saving_m"].to_numpy()
    bound = rules["window"] == "bound"
    objective = float((np.ceil(stored / unit) if bound else np.round(stored / unit)).sum() * unit)
    detours = np.concatenate([route["detour_x"], route["detour_y"]])
    out: dict[str, float] = {
        "orders": n,
        "pairs": count,
        "pooled_passengers": 2 * count,
        "pairing_ratio": 2 * count / n if n else float("nan"),
        "avg_detour_m": float(detours.mean()) if count else float("nan"),
        "avg_shared_m": float(route["shared"].mean()) if count else float("nan"),
        "objective_m": objective,
    }
    if bound:  # the bound's matching statistics bound nothing: named apart (rpbench.results.metrics)
        out = {BOUND_MATCHING_KPIS.get(k, k): v for k, v in out.items()}
    have = {k: as_number(v) for k, v in zip(reported["kpi"], reported["value"], strict=True)}
    optimal = rec.get("status", "optimal") == "optimal"
    # the bound's bracket rows (LB, U / LB) are derived from the strategy runs: ``competitive-ratio`` checks them
    claims: dict[str, str | None] = dict.fromkeys(BRACKET_KPIS) if bound else {}
    if not bound:
        out["total_saving_km"] = float(route["saving"].sum()) / 1000.0
    elif optimal:
        out["total_saving_km"] = objective / 1000.0  # the rounded-up optimum is the bound
    else:
        rep = have.get("total_saving_km")
        claims["total_saving_km"] = (
            None
            if rep is None or rep >= objective / 1000.0 - 1e-6
            else (
                f"KPI total_saving_km: the reported bound {rep!r} km lies below its own matching's "
                f"{objective / 1000.0!r} km"
            )
        )
    bound_m, gap = have.get("bound_m"), have.get("gap")
    claims["bound_m"] = None
    if bound_m is not None and not np.isnan(bound_m):
        if bound_m < objective - max(unit, 1e-9 * abs(objective)):
            claims["bound_m"] = f"KPI bound_m: the solver's bound {bound_m!r} lies below its solution's {objective!r}"
        elif gap == 0 and not same(bound_m, objective):
            claims["bound_m"] = f"KPI bound_m: reported {bound_m!r} with a gap of 0, recomputed objective {objective!r}"
    pairs_bound = have.get("pairs_bound")
    claims["pairs_bound"] = None
    if rec.get("variant", 1) == 2 and pairs_bound is not None:
        if not pairs_bound >= count or (optimal and pairs_bound != count):
            claims["pairs_bound"] = (
                f"KPI pairs_bound: the proven maximum number of pairs {pairs_bound!r} does not "
                f"{'equal' if optimal else 'cover'} the {count} pairs of the "
                f"{'optimal ' if optimal else ''}matching"
            )
    elif pairs_bound is not None and not np.isnan(pairs_bound):
        claims["pairs_bound"] = f"KPI pairs_bound: reported {pairs_bound!r} for an oracle that proves none"
    return out, claims
