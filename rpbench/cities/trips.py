"""A city's trips from a user's table: request times, and origins and destinations as nodes or coordinates.

The table's columns (``--column NAME=SOURCE`` maps these names to the file's own):

* ``time``: seconds from midnight (``--time-unit min`` or ``h`` for other units), or an ISO date-time;
* either ``origin_node`` and ``destination_node``: the network file's node ids (or, with ``node_ids =
  "positions"``, positions in its node order, counted from 0);
* or ``origin_lon``, ``origin_lat``, ``destination_lon``, ``destination_lat`` (WGS84), each end snapped to
  the nearest node of the kept network within ``snap_radius_m``.

Trips are dropped, and counted by why, when an end lies farther than the radius from the network, when an
end is a node outside the kept component, or when origin and destination are one node (nobody drives);
an unknown node id, a time that is not one, coordinates of which none lies near the network and a table
with nothing left are errors.
"""

from __future__ import annotations

import datetime as dt
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench.cities.roads import RawRoads
from rpbench.data._table import FLOAT, INT, TEXT, open_csv, read_table
from rpbench.exceptions import DataError, ParameterError, RpbenchError, one_line
from rpbench.network import RoadNetwork, snap
from rpbench.units import DAY_S

#: What an error line about a user's trip table tells them to do.
TRIPS_REMEDY = "check the file given to `rpbench city import --trips` (its columns: --column NAME=SOURCE)"
TRIP_NODE_COLUMNS = ("origin_node", "destination_node")
TRIP_COORDINATE_COLUMNS = ("origin_lon", "origin_lat", "destination_lon", "destination_lat")
TRIP_COLUMNS = ("time", *TRIP_NODE_COLUMNS, *TRIP_COORDINATE_COLUMNS)
#: Seconds per unit of a numeric ``time``.
TIME_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}
NODE_ID_KINDS = ("ids", "positions")


@dataclass(frozen=True)
class TripOptions:
    """How a trip table is read (the importer's options of the same names)."""

    columns: Mapping[str, str] = field(default_factory=dict)
    time_unit: str = "s"
    node_ids: str = "ids"
    snap_radius_m: float = 500.0
    date: str | None = None

    def __post_init__(self) -> None:
        unknown = sorted(set(self.columns) - set(TRIP_COLUMNS))
        if unknown:
            raise ParameterError(
                f"--column {unknown[0]}=...: not a trip column; the columns are {', '.join(TRIP_COLUMNS)}"
            )
        if self.time_unit not in TIME_UNITS:
            raise ParameterError(f"--time-unit {self.time_unit!r}: one of {', '.join(TIME_UNITS)}")
        if self.node_ids not in NODE_ID_KINDS:
            raise ParameterError(f"--node-ids {self.node_ids!r}: one of {', '.join(NODE_ID_KINDS)}")
        if not (np.isfinite(self.snap_radius_m) and 0 < self.snap_radius_m <= 10_000):
            raise ParameterError(f"--snap-radius {self.snap_radius_m!r} m: a distance in (0, 10000] m")
        if self.date is not None:
            try:
                dt.date.fromisoformat(self.date)
            except ValueError:
                raise ParameterError(f"--date {self.date!r}: a date YYYY-MM-DD") from None

    def name_of(self, column: str) -> str:
        return self.columns.get(column, column)


@dataclass(frozen=True)
class Trips:
    """The trips kept: request time (seconds from midnight) and both ends as node ids of the kept network."""

    request_s: np.ndarray
    origin: np.ndarray
    destination: np.ndarray
    record: dict[str, Any]  # what city.json says of them: counts, how they were placed, their day

    @property
    def notes(self) -> list[str]:
        """One line per reason trips were dropped."""
        return [f"{n:,} trips dropped: {why}" for why, n in self.record["dropped"].items() if n]


def read_and_place(path: Path, options: TripOptions, raw: RawRoads, network: RoadNetwork) -> Trips:
    """The trips of table ``path``, their ends placed on ``network`` (the kept part of ``raw``)."""
    header = _header(path)
    by_node = all(options.name_of(c) in header for c in TRIP_NODE_COLUMNS)
    by_coordinates = all(options.name_of(c) in header for c in TRIP_COORDINATE_COLUMNS)
    wanted = TRIP_NODE_COLUMNS if by_node else TRIP_COORDINATE_COLUMNS
    if options.name_of("time") not in header or not (by_node or by_coordinates):
        named = ", ".join(options.name_of(c) for c in ("time", *TRIP_NODE_COLUMNS))
        coords = ", ".join(options.name_of(c) for c in TRIP_COORDINATE_COLUMNS)
        raise DataError(
            f"trip table {str(path)!r} has columns {', '.join(header) or '(none)'}; it needs {named}, or "
            f"{options.name_of('time')} and {coords}; map the file's own with --column NAME=SOURCE"
        )
    kinds = {options.name_of("time"): TEXT, **{options.name_of(c): INT if by_node else FLOAT for c in wanted}}
    frame = read_table(
        path, "trip table", kinds, rename={options.name_of(c): c for c in ("time", *wanted)}, remedy=TRIPS_REMEDY
    )
    if frame.empty:
        raise DataError(f"trip table {str(path)!r} holds no trips; {TRIPS_REMEDY}")
    rows = len(frame)
    dropped: dict[str, int] = {}
    seconds, day, keep = _seconds(frame["time"], options, path)
    if (~keep).any():
        dropped[f"requested on another day than {day}"] = int((~keep).sum())
    frame, seconds = frame[keep], seconds[keep]
    if by_node:
        origin, destination, ok = _nodes(frame, options, raw, network, path)
        dropped["an end outside the largest strongly connected component"] = int((~ok).sum())
        placed: dict[str, Any] = {"by": f"node {options.node_ids}"}
    else:
        origin, destination, ok, placed = _snapped(frame, options, network, path)
        dropped[f"an end farther than {options.snap_radius_m:g} m from the network"] = int((~ok).sum())
    same = ok & (origin == destination)
    dropped["origin and destination are one node"] = int(same.sum())
    keep = ok & ~same
    if not keep.any():
        raise DataError(
            f"trip table {str(path)!r}: no trip is left ({'; '.join(f'{n:,} {w}' for w, n in dropped.items() if n)})"
        )
    request_s = seconds[keep]
    order = np.argsort(request_s, kind="stable")
    record = {
        "rows": rows,
        "kept": int(keep.sum()),
        "dropped": dropped,
        "placed": placed,
        "date": day,
        "time_resolution_s": _resolution(request_s),
        "first_request_s": float(request_s.min()),
        "last_request_s": float(request_s.max()),
    }
    return Trips(request_s[order], origin[keep][order], destination[keep][order], record)


def _header(path: Path) -> list[str]:
    """The table's column names (a file that is not a readable CSV is one line)."""
    try:
        with open_csv(path, "trip table", TRIPS_REMEDY) as source:
            return [str(c) for c in pd.read_csv(source, nrows=0, compression=None).columns]
    except RpbenchError:
        raise
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, OSError, EOFError, zlib.error) as exc:
        raise DataError(f"trip table {str(path)!r} cannot be read as CSV ({one_line(exc)}); {TRIPS_REMEDY}") from None


def _seconds(text: pd.Series, options: TripOptions, path: Path) -> tuple[np.ndarray, str | None, np.ndarray]:
    """Seconds from midnight of every row, the day (ISO times: their date), and which rows that day holds."""
    numeric = pd.to_numeric(text, errors="coerce")
    if numeric.notna().all():
        seconds = numeric.to_numpy(float) * TIME_UNITS[options.time_unit]
        bad = ~(np.isfinite(seconds) & (seconds >= 0) & (seconds < DAY_S))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise DataError(
                f"trip table {str(path)!r}, data row {row + 1}: time {text.iloc[row]!r} ({options.time_unit}) is "
                f"not within the day [0, 24 h); numeric times count from midnight (--time-unit s, min or h)"
            )
        return seconds, options.date, np.ones(len(seconds), dtype=bool)
    stamps = pd.to_datetime(text, errors="coerce", format="ISO8601")
    if stamps.isna().any():
        row = int(np.flatnonzero(stamps.isna().to_numpy())[0])
        raise DataError(
            f"trip table {str(path)!r}, data row {row + 1}: time {text.iloc[row]!r} is neither a number of "
            "seconds from midnight nor an ISO date-time (YYYY-MM-DD HH:MM:SS)"
        )
    if stamps.dt.tz is not None:
        stamps = stamps.dt.tz_localize(None)
    days = stamps.dt.normalize()
    dates = sorted({d.date().isoformat() for d in days})
    day = options.date if options.date is not None else (dates[0] if len(dates) == 1 else None)
    if day is None:
        raise DataError(
            f"trip table {str(path)!r} holds trips of {len(dates)} days ({dates[0]} .. {dates[-1]}); a city is one "
            "day of trips: choose it with --date YYYY-MM-DD"
        )
    keep = (days == pd.Timestamp(day)).to_numpy()
    if not keep.any():
        raise DataError(f"trip table {str(path)!r} holds no trip on {day} (its days: {dates[0]} .. {dates[-1]})")
    return (stamps - pd.Timestamp(day)).dt.total_seconds().to_numpy(), day, keep


def _nodes(
    frame: pd.DataFrame, options: TripOptions, raw: RawRoads, network: RoadNetwork, path: Path
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both ends as node ids of the file (``ids``) or positions in it (``positions``); kept: both in ``network``."""
    ends = []
    for column in TRIP_NODE_COLUMNS:
        values = frame[column].to_numpy(np.int64)
        if options.node_ids == "positions":
            bad = (values < 0) | (values >= len(raw.node_id))
            if bad.any():
                raise DataError(
                    f"trip table {str(path)!r}: {column} {int(values[bad][0])} is not a position in the network "
                    f"file's {len(raw.node_id):,} nodes (0 .. {len(raw.node_id) - 1}); {TRIPS_REMEDY}"
                )
            values = raw.node_id[values]
        else:
            unknown = ~np.isin(values, raw.node_id)
            if unknown.any():
                raise DataError(
                    f"trip table {str(path)!r}: {int(unknown.sum()):,} trips name nodes the network file does not "
                    f"list ({column} {int(values[unknown][0])}, say); with positions instead of ids, give "
                    f"--node-ids positions; {TRIPS_REMEDY}"
                )
        ends.append(values)
    ok = np.isin(ends[0], network.node_id) & np.isin(ends[1], network.node_id)
    return ends[0], ends[1], ok


def _snapped(
    frame: pd.DataFrame, options: TripOptions, network: RoadNetwork, path: Path
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Both ends snapped to the nearest node of ``network``; kept: both within the radius."""
    ends, distances = [], []
    for end in ("origin", "destination"):
        index, metres = snap(network, frame[f"{end}_lon"], frame[f"{end}_lat"], rule="nearest")
        ends.append(network.node_id[index])
        distances.append(metres)
    near = (distances[0] <= options.snap_radius_m) & (distances[1] <= options.snap_radius_m)
    if not near.any():
        nearest = float(np.minimum(distances[0], distances[1]).min())
        raise DataError(
            f"trip table {str(path)!r}: no trip has both ends within {options.snap_radius_m:g} m of the network "
            f"(the closest end lies {nearest:,.0f} m away): are the coordinates outside the network, or "
            "longitude and latitude swapped?"
        )
    used = np.concatenate([distances[0][near], distances[1][near]])
    placed = {
        "by": "coordinates, snapped to the nearest node",
        "snap_radius_m": options.snap_radius_m,
        "snap_distance_m": {"median": float(np.median(used)), "p95": float(np.quantile(used, 0.95))},
    }
    return ends[0], ends[1], near, placed


def _resolution(seconds: np.ndarray) -> float:
    """The clock the times were recorded with: 60 s when every one is a whole minute, else 1 s."""
    return 60.0 if len(seconds) > 1 and np.all(np.mod(seconds, 60.0) == 0) else 1.0
