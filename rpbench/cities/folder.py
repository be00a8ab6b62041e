"""A city folder: the road network and the day of trips rpbench runs a city's scenarios on.

::

    city.json       format, name, label, where each input came from (file names and SHA-256), what the
                    import kept and dropped, the day, the trips' clock, the city's default speed, and the
                    SHA-256 of the three tables below
    nodes.csv.gz    node_id, lon, lat                      (the largest strongly connected component)
    arcs.csv.gz     from_node, to_node, length_m          (one arc per ordered node pair)
    trips.csv.gz    request_s, origin, destination        (seconds from midnight; node ids)

The tables are gzip files written without a time in their header, so one import gives the same bytes
everywhere; :func:`read_city` checks their digests before it builds anything.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.cities.roads import Reduction
from rpbench.cities.trips import Trips
from rpbench.data._table import FLOAT, INT, read_table
from rpbench.data.road import NetworkTables
from rpbench.exceptions import DataError
from rpbench.files import load_json_object
from rpbench.files.digests import file_sha256
from rpbench.network import RoadNetwork

CITY_FORMAT = "rpbench-city-1"
CITY_JSON = "city.json"
NODES, ARCS, TRIPS = "nodes.csv.gz", "arcs.csv.gz", "trips.csv.gz"
TABLES = (NODES, ARCS, TRIPS)
#: gzip without a time in its header: the same tables give the same bytes.
_REPRODUCIBLE_GZIP = {"method": "gzip", "mtime": 0}
REIMPORT = "import it again (`rpbench city import`), or remove the folder"


@dataclass(frozen=True, eq=False)
class City:
    """A city read from its folder: its network and its day of trips (ends as node indices)."""

    name: str
    folder: Path
    record: dict[str, Any]
    network: RoadNetwork
    request_s: np.ndarray  # seconds from midnight, sorted
    origin: np.ndarray  # node indices of ``network``
    destination: np.ndarray

    @property
    def label(self) -> str:
        return str(self.record.get("label") or self.name)

    @property
    def date(self) -> str | None:
        return self.record["trips"].get("date")

    @property
    def time_resolution_s(self) -> float:
        return float(self.record["trips"].get("time_resolution_s", 1.0))

    def speed_mps(self, start_s: float, end_s: float) -> float | None:
        """The city's vehicle speed over a window of the day (None: the paper's 30 km/h): its one speed, or
        the harmonic mean of its hourly speeds weighted by each hour's share of the window."""
        by_hour = self.record.get("speed_kmh_by_hour")
        if by_hour:
            edges = np.arange(25) * 3600.0
            share = np.clip(np.minimum(edges[1:], end_s) - np.maximum(edges[:-1], start_s), 0.0, None)
            return float(share.sum() / (share / np.asarray(by_hour, dtype=float)).sum()) / 3.6
        speed = self.record.get("speed_kmh")
        return None if speed is None else float(speed) / 3.6

    @property
    def digest(self) -> str:
        """One digest of the city's three tables (what a scenario's provenance records)."""
        files = self.record["files"]
        return hashlib.sha256("|".join(files[t] for t in TABLES).encode()).hexdigest()[:16]


def write_city(folder: Path, record: dict[str, Any], reduction: Reduction, trips: Trips) -> dict[str, Any]:
    """Write the tables and ``city.json`` (``record`` completed with the tables' digests) into ``folder``."""
    t = reduction.tables
    pd.DataFrame({"node_id": t.node_id, "lon": t.lon, "lat": t.lat}).to_csv(
        folder / NODES, index=False, compression=_REPRODUCIBLE_GZIP
    )
    pd.DataFrame({"from_node": t.arc_from, "to_node": t.arc_to, "length_m": t.arc_length_m}).to_csv(
        folder / ARCS, index=False, compression=_REPRODUCIBLE_GZIP
    )
    pd.DataFrame({"request_s": trips.request_s, "origin": trips.origin, "destination": trips.destination}).to_csv(
        folder / TRIPS, index=False, compression=_REPRODUCIBLE_GZIP
    )
    record = {**record, "format": CITY_FORMAT, "files": {name: file_sha256(folder / name) for name in TABLES}}
    (folder / CITY_JSON).write_text(json.dumps(record, indent=2, sort_keys=False) + "\n")
    return record


def read_city(folder: Path) -> City:
    """The city in ``folder``, its tables checked against the digests ``city.json`` records."""
    where = f"city folder {str(folder)!r}"
    record = load_json_object(folder / CITY_JSON, f"{where}: {CITY_JSON}", DataError)
    if record.get("format") != CITY_FORMAT:
        raise DataError(f"{where}: {CITY_JSON} is not a {CITY_FORMAT} description; {REIMPORT}")
    files = record.get("files")
    if not isinstance(files, dict) or set(files) != set(TABLES) or not isinstance(record.get("trips"), dict):
        raise DataError(f"{where}: {CITY_JSON} does not list its tables' digests; {REIMPORT}")
    for name in TABLES:
        path = folder / name
        if not path.is_file() or file_sha256(path) != files[name]:
            state = "is missing" if not path.is_file() else "is not the file the import wrote (its SHA-256 differs)"
            raise DataError(f"{where}: {name} {state}; {REIMPORT}")
    nodes = read_table(folder / NODES, "city node", {"node_id": INT, "lon": FLOAT, "lat": FLOAT}, remedy=REIMPORT)
    arcs = read_table(folder / ARCS, "city arc", {"from_node": INT, "to_node": INT, "length_m": FLOAT}, remedy=REIMPORT)
    trips = read_table(
        folder / TRIPS, "city trip", {"request_s": FLOAT, "origin": INT, "destination": INT}, remedy=REIMPORT
    )
    name = str(record.get("name", folder.name))
    network = RoadNetwork.from_tables(
        NetworkTables(
            name=name,
            node_id=nodes["node_id"].to_numpy(np.int64),
            lon=nodes["lon"].to_numpy(float),
            lat=nodes["lat"].to_numpy(float),
            arc_from=arcs["from_node"].to_numpy(np.int64),
            arc_to=arcs["to_node"].to_numpy(np.int64),
            arc_length_m=arcs["length_m"].to_numpy(float),
            arc_link_id=np.arange(len(arcs), dtype=np.int64),
            source=f"city {name}",
        )
    )
    return City(
        name=name,
        folder=folder,
        record=record,
        network=network,
        request_s=trips["request_s"].to_numpy(float),
        origin=network.index_of(trips["origin"], what=f"{where}: origin node id"),
        destination=network.index_of(trips["destination"], what=f"{where}: destination node id"),
    )
