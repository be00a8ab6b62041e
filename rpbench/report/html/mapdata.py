"""The map of a comparison folder: the road network from its own coordinates, and every simulated run's
pooled pairs, solo trips and cancelled requests, read off the event logs.

No tile server: the roads are drawn from ``network.npz``'s node coordinates.  Stops are node indices into
one coordinate table, so a run's layers cost a few numbers per passenger; the page's script filters them by
time window and draws at most :data:`MAX_DRAWN` items of a layer at once (one in k, said on the page),
while the density layer counts them all.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.exceptions import ResultsError
from rpbench.report.html.figures import FONT, css_colors
from rpbench.results import layout
from rpbench.results.ranking import run_groups
from rpbench.results.read import load_kpis
from rpbench.results.runs import run_label, run_styles

#: At most this many items of one layer are drawn at once (a window with more draws one in k).
MAX_DRAWN = 2500
#: The time window of the slider: 10 minutes for scenarios of up to two hours, an hour beyond.
SHORT_WINDOW_S, LONG_WINDOW_S, LONG_SCENARIO_S = 600.0, 3600.0, 2 * 3600.0
LAYER_NAMES = {"pooled": "pooled pairs", "solo": "solo trips", "cancelled": "cancelled requests"}


def map_payload(folder: Path) -> dict[str, Any] | str:
    """What the page's map draws (see the module docstring), or the sentence saying why there is no map."""
    meta = results.read_meta(folder)
    net_path, orders_path = folder / layout.NETWORK, folder / layout.ORDERS
    if not net_path.is_file() or not orders_path.is_file():
        return (
            "No map: it is drawn from the folder's road network, orders and event logs, which this published "
            "light copy leaves out; rerun the command above for the full folder, whose report.html has the map."
        )
    order = list(dict.fromkeys([*meta.get("strategies", []), *results.run_names(folder)]))
    simulated = [r for r in order if (folder / layout.RUNS / r / layout.EVENTS).is_file()]
    if not simulated:
        return "No map: every run of this folder is offline (no event log to draw)."
    try:
        network = results.load_network(net_path)
        orders = results.read_csv(orders_path)
        origin = _origins(orders)
        styles = run_styles(meta)
        colors = css_colors(simulated, styles)
        runs, end = [], 0.0
        for r in simulated:
            events = results.read_csv(folder / layout.RUNS / r / layout.EVENTS)
            end = max(end, float(events["t_s"].max()) if len(events) else 0.0)
            runs.append({"name": r, "label": run_label(r, styles), "color": colors[r], **layers(events, origin)})
    except (ResultsError, KeyError, ValueError, IndexError) as exc:  # `rpbench check` says what is damaged
        return f"No map: a file it is drawn from cannot be read ({exc})."
    sc = meta["scenario"]
    horizon = float(sc.get("horizon_s") or end)
    window = LONG_WINDOW_S if horizon > LONG_SCENARIO_S else SHORT_WINDOW_S
    start = sc.get("start_time")
    clock = pd.Timestamp(start) if start else None
    lon, lat = np.asarray(network.lon, dtype=float), np.asarray(network.lat, dtype=float)
    tail, head = np.asarray(network.arc_tail), np.asarray(network.arc_head)
    edges = np.unique(np.stack([np.minimum(tail, head), np.maximum(tail, head)], axis=1), axis=0)
    edges = edges[edges[:, 0] != edges[:, 1]]
    first = opening_run(folder, meta, runs)
    end_s = max(horizon, window)
    return {
        "nodes": {"lon": np.round(lon, 5).tolist(), "lat": np.round(lat, 5).tolist()},
        "edges": edges.ravel().tolist(),
        "runs": runs,
        "first_run": first,
        "first_window": opening_window(runs[first], end_s, window),
        "offline": [run_label(r, run_styles(meta)) for r in order if r not in simulated],
        "period": {
            "begin_s": 0.0,
            "end_s": end_s,
            "window_s": window,
            "start_clock_s": (clock - clock.normalize()).total_seconds() if clock is not None else 0.0,
            "seconds": horizon <= LONG_SCENARIO_S,
        },
        "max_drawn": MAX_DRAWN,
        "layer_names": LAYER_NAMES,
        "layout": _layout(lat, _extent(lon, lat, orders)),
    }


def opening_run(folder: Path, meta: dict[str, Any], runs: list[dict[str, Any]]) -> int:
    """The run the map opens on: of the online runs (simulated, not clairvoyant: what a platform could
    deploy), the one saving the most distance; without a saving to compare, the run with the most pooled
    pairs.  A clairvoyant run (Hindsight) pools nearly everyone and would open on a web of lines."""
    names = [r["name"] for r in runs]
    groups = run_groups([meta.get("runs") or {}], names)
    online = [i for i, n in enumerate(names) if groups[n] == "online"] or list(range(len(runs)))
    try:
        saving = load_kpis(folder).loc["total_saving_km"]
    except (ResultsError, KeyError, ValueError, OSError):
        saving = pd.Series(dtype=float)

    def key(i: int) -> tuple[float, int]:
        value = float(saving.get(names[i], np.nan))
        return (-np.inf if np.isnan(value) else value), len(runs[i]["pooled"]["t"])

    return max(online, key=key)


def opening_window(run: dict[str, Any], end_s: float, window_s: float) -> int:
    """The time window the map opens on (1 is the first; 0 would be the whole period): the one holding the
    median first pick-up of ``run``'s pooled pairs, a typical busy window, few enough lines to follow."""
    times = run["pooled"]["t"] or run["solo"]["t"] or run["cancelled"]["t"]
    count = max(1, math.ceil(end_s / window_s))
    if not times:
        return 1
    middle = float(np.median(times))
    return int(min(max(middle // window_s + 1, 1), count))


def _origins(orders: pd.DataFrame) -> np.ndarray:
    """Each order's origin node, by the order's position (the event logs' ``order``)."""
    return orders["origin"].to_numpy(dtype=np.int64)


def layers(events: pd.DataFrame, origin: np.ndarray) -> dict[str, dict[str, Any]]:
    """A run's three layers from its event log (``stops`` node indices per item, in the order served):

    * ``pooled`` — one item per pair whose two passengers were both delivered: first pick-up, the join
      (second pick-up), then the two drop-offs in time order; ``t`` is the first pick-up;
    * ``solo`` — a passenger delivered without a partner: pick-up, drop-off; ``t`` is the pick-up;
    * ``cancelled`` — a request cancelled before assignment: its origin; ``t`` is the cancellation.
    """
    n = len(origin)
    when: dict[str, np.ndarray] = {}
    where: dict[str, np.ndarray] = {}
    for name in ("pickup", "dropoff", "cancel"):
        sel = events[events["event"] == name]
        idx = sel["order"].to_numpy(dtype=np.int64)
        when[name] = np.full(n, np.nan)
        when[name][idx] = sel["t_s"].to_numpy(dtype=float)
        where[name] = np.full(n, -1, dtype=np.int64)
        where[name][idx] = sel["node"].to_numpy(dtype=np.int64)
    assign = events[events["event"] == "assign"]
    second = assign["order"].to_numpy(dtype=np.int64)
    first = assign["partner"].to_numpy(dtype=np.int64)
    joined = first >= 0
    first, second = first[joined], second[joined]
    delivered = ~np.isnan(when["dropoff"])
    both = delivered[first] & delivered[second]
    first, second = first[both], second[both]
    pick_t = np.stack([when["pickup"][first], when["pickup"][second]], axis=1)
    drop_t = np.stack([when["dropoff"][first], when["dropoff"][second]], axis=1)
    pick_n = np.stack([where["pickup"][first], where["pickup"][second]], axis=1)
    drop_n = np.stack([where["dropoff"][first], where["dropoff"][second]], axis=1)
    rows = np.arange(len(first))
    p_order = np.argsort(pick_t, axis=1, kind="stable")
    d_order = np.argsort(drop_t, axis=1, kind="stable")
    pair_orders = np.stack([first, second], axis=1)[rows[:, None], p_order]
    stops = np.concatenate([pick_n[rows[:, None], p_order], drop_n[rows[:, None], d_order]], axis=1)
    pooled_t = pick_t[rows, p_order[:, 0]]

    solo = np.flatnonzero(delivered & ~_any_partner(assign, n))
    cancelled = np.flatnonzero(~np.isnan(when["cancel"]))
    return {
        "pooled": _items(pooled_t, stops, pair_orders, 4),
        "solo": _items(
            when["pickup"][solo], np.stack([where["pickup"][solo], where["dropoff"][solo]], axis=1), solo[:, None], 2
        ),
        "cancelled": _items(when["cancel"][cancelled], origin[cancelled][:, None], cancelled[:, None], 1),
    }


def _any_partner(assign: pd.DataFrame, n: int) -> np.ndarray:
    """Orders assigned with a partner (either side of a join), delivered or not: never drawn as solo."""
    out = np.zeros(n, dtype=bool)
    a_order, a_partner = assign["order"].to_numpy(dtype=np.int64), assign["partner"].to_numpy(dtype=np.int64)
    has = a_partner >= 0
    out[a_order[has]] = out[a_partner[has]] = True
    return out


def _items(t: np.ndarray, stops: np.ndarray, orders: np.ndarray, k: int) -> dict[str, Any]:
    """One layer's items sorted by time: times (whole seconds: a window is minutes wide), ``k`` stops each
    (flat), their order ids (flat)."""
    by_time = np.argsort(t, kind="stable")
    return {
        "t": np.floor(t[by_time]).astype(int).tolist(),
        "nodes": stops[by_time].reshape(-1).astype(int).tolist(),
        "orders": orders[by_time].reshape(-1).astype(int).tolist(),
        "stops": k,
    }


def _extent(lon: np.ndarray, lat: np.ndarray, orders: pd.DataFrame) -> tuple[list[float], list[float]]:
    """The initial view: where the orders start and end (1st to 99th percentile, with a margin), not the
    whole network, whose outskirts carry few trips; the reader zooms out with a double click."""
    stops = np.concatenate([orders["origin"].to_numpy(dtype=np.int64), orders["destination"].to_numpy(dtype=np.int64)])
    if not len(stops):
        stops = np.arange(len(lon))
    box = []
    for axis in (lon[stops], lat[stops]):
        low, high = np.percentile(axis, [1, 99])
        pad = max(0.08 * (high - low), 1e-3)
        box.append([round(float(low - pad), 5), round(float(high + pad), 5)])
    return box[0], box[1]


def _layout(lat: np.ndarray, extent: tuple[list[float], list[float]]) -> dict[str, Any]:
    """Longitude and latitude axes at the true ground aspect (a degree of longitude is cos(latitude) of
    one of latitude), opening on ``extent``; the zoom survives run and window changes (``uirevision``)."""
    mid = float(np.nanmean(lat)) if len(lat) else 0.0
    return {
        "height": 680,
        "font": FONT,
        "paper_bgcolor": "#ffffff",
        "plot_bgcolor": "#ffffff",
        "margin": {"l": 60, "r": 10, "t": 20, "b": 60},
        "xaxis": {"title": {"text": "longitude (° E)"}, "showgrid": False, "zeroline": False, "range": extent[0]},
        "yaxis": {
            "title": {"text": "latitude (° N)"},
            "showgrid": False,
            "zeroline": False,
            "range": extent[1],
            "scaleanchor": "x",
            "scaleratio": 1.0 / max(math.cos(math.radians(mid)), 1e-6),
        },
        "legend": {"orientation": "h", "y": -0.1, "yanchor": "top"},
        "uirevision": "map",
        "hovermode": "closest",
        "dragmode": "zoom",
    }
