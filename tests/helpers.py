"""Builders for hand-made networks, scenarios and round states used across tests."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np

from rpbench.data.road import NetworkTables
from rpbench.network import RoadNetwork
from rpbench.scenarios.base import Fleet, Params, Scenario
from rpbench.scenarios.common import make_orders
from rpbench.strategies.base import RoundState


def network_from_edges(edges: list[tuple[int, int, float]], name: str = "hand-made") -> RoadNetwork:
    """A two-way network from (a, b, length_m) edges; node coordinates are placeholders."""
    a = np.array([e[0] for e in edges])
    b = np.array([e[1] for e in edges])
    length = np.array([e[2] for e in edges], dtype=float)
    ids = np.unique(np.concatenate([a, b]))
    tables = NetworkTables(
        name=name,
        node_id=ids,
        lon=110.0 + ids * 1e-4,
        lat=20.0 + ids * 0.0,
        arc_from=np.concatenate([a, b]),
        arc_to=np.concatenate([b, a]),
        arc_length_m=np.concatenate([length, length]),
        arc_link_id=np.concatenate([np.arange(len(a))] * 2),
        source="tests",
    )
    return RoadNetwork.from_tables(tables)


def line_network(n: int = 6, length: float = 1000.0) -> RoadNetwork:
    return network_from_edges([(i, i + 1, length) for i in range(n - 1)], name=f"line-{n}")


def scenario_of(
    network: RoadNetwork,
    orders: list[tuple[float, int, int]],
    vehicles: list[int],
    *,
    patience_s: float = 90.0,
    params: Params | None = None,
    horizon_s: float = 3600.0,
) -> Scenario:
    """A scenario with orders (request_s, origin id, destination id) and vehicles at node ids."""
    req = np.array([o[0] for o in orders], dtype=float)
    o = network.index_of([x[1] for x in orders]) if orders else np.zeros(0, np.int32)
    d = network.index_of([x[2] for x in orders]) if orders else np.zeros(0, np.int32)
    return Scenario(
        name="hand-made",
        label="hand-made test scenario",
        network=network,
        orders=make_orders(np.arange(len(orders)), req, o, d, np.full(len(orders), patience_s)),
        fleet=Fleet(initial_node=network.index_of(vehicles)),
        params=params or Params(),
        seed=0,
        horizon_s=horizon_s,
        start_time="2017-05-01T08:00:00",
        synthetic=True,
    )


def round_state(
    network: RoadNetwork,
    passengers: list[tuple[int, int]],
    vacant: list[tuple[int, float]],
    *,
    params: Params | None = None,
    occupied: list[dict] | None = None,
    t: float = 0.0,
    waited: list[int] | None = None,
) -> RoundState:
    """A RoundState with passengers (origin, destination), vacant vehicles (node, pre_m) and
    partially occupied vehicles {node, delta, pre, origin, destination, onboard} (node ids)."""
    dist = network.distances().dist
    idx = network.index_of
    p_o = idx([p[0] for p in passengers]) if passengers else np.zeros(0, np.int32)
    p_d = idx([p[1] for p in passengers]) if passengers else np.zeros(0, np.int32)
    occupied = occupied or []
    v1_o = idx([v["origin"] for v in occupied]) if occupied else np.zeros(0, np.int32)
    v1_d = idx([v["destination"] for v in occupied]) if occupied else np.zeros(0, np.int32)
    n_p = len(passengers)
    return RoundState(
        t_s=t,
        params=params or Params(),
        dist=dist,
        p_order=np.arange(n_p),
        p_origin=p_o.astype(np.int64),
        p_destination=p_d.astype(np.int64),
        p_solo_m=dist[p_o, p_d],
        p_request_s=np.zeros(n_p),
        p_rounds_waited=np.asarray(waited if waited is not None else [1] * n_p, dtype=np.int64),
        v0_vehicle=np.arange(len(vacant)),
        v0_node=idx([v[0] for v in vacant]).astype(np.int64) if vacant else np.zeros(0, np.int64),
        v0_pre_m=np.array([v[1] for v in vacant], dtype=float),
        v1_vehicle=len(vacant) + np.arange(len(occupied)),
        v1_node=idx([v["node"] for v in occupied]).astype(np.int64) if occupied else np.zeros(0, np.int64),
        v1_delta_m=np.array([v.get("delta", 0.0) for v in occupied], dtype=float),
        v1_pre_m=np.array([v.get("pre", 0.0) for v in occupied], dtype=float),
        v1_order=n_p + np.arange(len(occupied)),
        v1_origin=v1_o.astype(np.int64),
        v1_destination=v1_d.astype(np.int64),
        v1_solo_m=dist[v1_o, v1_d],
        v1_onboard=np.array([v.get("onboard", True) for v in occupied], dtype=bool),
    )


def write_gz(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with gzip.open(path, "wt") as fh:
        fh.write(text)


def write_fake_haikou(root: Path, days=("2017-05-01",), reservation: bool = True) -> Path:
    """A tiny data folder in the Haikou format: a 3x3 two-way grid, 40 orders per peak-hour file (one file per
    day, drawn from one seeded stream), a month OD table and hourly counts.  ``reservation`` adds a row dated
    outside the first day's hour (the readers drop it).  Tests damage copies of it to provoke errors."""
    (root / "network").mkdir(parents=True)
    nodes = ["node_id,name,x_coord,y_coord"]
    for i in range(9):
        r, c = divmod(i, 3)
        nodes.append(f"{i},,{110.3 + 0.005 * c:.6f},{20.0 + 0.005 * r:.6f}")
    (root / "network" / "node.csv").write_text("\n".join(nodes) + "\n")
    links = ["link_id,from_node_id,to_node_id,link_type,geometry,length"]
    k = 0
    for i in range(9):
        r, c = divmod(i, 3)
        for j in ([i + 1] if c < 2 else []) + ([i + 3] if r < 2 else []):
            links.append(f'{k},{i},{j},5,"LINESTRING (0 0, 1 1)",{600.0 + k:.1f}')
            k += 1
    write_gz(root / "network" / "link.csv.gz", "\n".join(links) + "\n")
    pre = "dwv_order_make_haikou_1."
    rng = np.random.default_rng(1)
    for n_day, day in enumerate(days):
        rows = [f",{pre}order_id,{pre}departure_time,O_location,D_location,OD_id,origin_id,destination_id"]
        for n in range(40):
            o, d = rng.choice(9, size=2, replace=False)
            rows.append(f"{n},{1000 + n},{day} 08:{n:02d}:{(7 * n) % 60:02d},{o}.0,{d}.0,{n},{o},{d}")
        if reservation and n_day == 0:
            rows.append("40,2000,2017-05-03 08:20:00,1.0,2.0,40,1,2")  # outside the hour: dropped
        write_gz(root / "demand_0800_0900" / "orders" / f"{day}.csv.gz", "\n".join(rows) + "\n")
    od = ["OD_id,origin_id,destination_id,lambda"] + [f"{i},{i % 9}.0,{(i + 4) % 9}.0,0.01" for i in range(9)]
    write_gz(root / "demand_0800_0900" / "month_5_OD.csv.gz", "\n".join(od) + "\n")
    hours = [10] * 24
    (root / "samples_and_aggregates").mkdir(parents=True)
    (root / "samples_and_aggregates" / "data_dayly_hourly_count.csv").write_text(
        f'date,day_count,hour_count\n05/01,{sum(hours)},"{hours}"\n'
    )
    return root
