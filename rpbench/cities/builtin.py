"""The cities rpbench knows by name, each made from its public data folder by the same importer a user's
city goes through (:func:`~rpbench.cities.importer.import_city`).

**Manhattan** (``../shared/data/manhattan``, or the folder ``rpbench data fetch --city manhattan`` fills):
the OSMnx drive network of Manhattan (GraphML) and one real weekday of 98,235 NYC yellow-cab trips whose
ends are positions in the GraphML's node order and whose times are minutes of the day (the TLC's meter-on
time, used as the request time).  Its speed: per hour of the day, the total straight-line length of the
arcs of the Alonso-Mora et al. (PNAS 2017) Manhattan network over their total weekday travel time in that
hour (arcs with a time of 0 s left out): 12.4 km/h at 08:00, 14.2 km/h over the day.  A scenario's
vehicles drive at that speed over its window (:func:`window_speed_kmh`); within one run the speed is one
constant, as the paper's 30 km/h is (the distances rpbench plans on are all-pairs shortest paths of
lengths, so a speed that changes by the hour would need a time-dependent planner).

An imported built-in city is kept in the cache, keyed by the importer's version, its recipe and the
content of its input files, so it is made once per machine and again whenever one of them changes.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from rpbench.cities.importer import IMPORTER_VERSION, Sources, import_city
from rpbench.cities.trips import TripOptions
from rpbench.exceptions import DataError, ParameterError, one_line
from rpbench.files.digests import content_sha256
from rpbench.files.paths import cache_dir, sweep_stale_temporaries
from rpbench.network import great_circle_m

#: Where built-in cities are kept, under the cache.
CITIES_CACHE = "cities"


@dataclass(frozen=True)
class Recipe:
    """How a built-in city is imported from its data folder."""

    name: str
    label: str
    network: str  # GraphML, relative to the data folder
    trips: str
    trip_options: TripOptions
    speeds: str | None = None  # the hourly travel times the speed comes from (PNAS network folder)
    provenance: dict[str, Any] = field(default_factory=dict)

    def key(self, data_dir: Path) -> str:
        """A digest of what decides the city folder: the importer, this recipe and its inputs' content."""
        inputs = {p: content_sha256(data_dir / p) for p in self.inputs()}
        text = json.dumps([IMPORTER_VERSION, asdict(self), inputs], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def inputs(self) -> list[str]:
        return [self.network, self.trips] + ([f"{self.speeds}/{f}" for f in PNAS_FILES] if self.speeds else [])


PNAS_FILES = ("points.csv.gz", "edges.csv.gz", "week.csv.gz")

MANHATTAN = Recipe(
    name="manhattan",
    label="Manhattan",
    network="network/Manhattan.graphml.gz",
    trips="demand/trips_fullday_by_node.csv.gz",
    trip_options=TripOptions(
        columns={"origin_node": "pick_up_index", "destination_node": "drop_off_index"},
        time_unit="min",
        node_ids="positions",
    ),
    speeds="network_pnas2017",
    provenance={
        "network": "OpenStreetMap via OSMnx (jackye330/ridesharing a4625d6, network_data/Manhattan.graphml); "
        "© OpenStreetMap contributors (ODbL)",
        "trips": "NYC TLC yellow-cab trips of one weekday, mapped to the network's nodes (jackye330/ridesharing "
        "a4625d6, order_data/trip_order_data.csv); the date is not recorded (probably June 2016), a filtered "
        "subset of the day's trips; meter-on time used as request time",
        "speed": "hourly weekday travel times of the Alonso-Mora et al. (PNAS 2017) Manhattan network "
        "(a20r/nyc-taxi-analysis 6d166f2, data/nyc-graph)",
    },
)
RECIPES = {r.name: r for r in (MANHATTAN,)}


def builtin_city(name: str, data_dir: Path) -> Path:
    """The city folder of built-in city ``name`` made from ``data_dir``: from the cache, or imported now."""
    recipe = RECIPES[name]
    root = cache_dir() / CITIES_CACHE
    root.mkdir(exist_ok=True)
    sweep_stale_temporaries(root)
    folder = root / f"{name}-{recipe.key(data_dir)}"
    if folder.is_dir():
        return folder
    if folder.exists() or folder.is_symlink():  # not a folder: a damaged entry
        folder.unlink()
    speeds = hourly_speeds_kmh(data_dir / recipe.speeds) if recipe.speeds else None
    sources = Sources(trips=data_dir / recipe.trips, network=data_dir / recipe.network)
    try:
        import_city(
            name, sources, recipe.trip_options, folder, label=recipe.label, speed_kmh_by_hour=speeds,
            provenance=recipe.provenance,
        )  # fmt: skip
    except (ParameterError, OSError):
        if not folder.is_dir():  # else another process imported it meanwhile: the same inputs, the same folder
            raise
    return folder


def hourly_speeds_kmh(folder: Path) -> list[float]:
    """Per hour of a weekday: Σ straight-line arc length / Σ travel time over the arcs of the PNAS 2017
    Manhattan network with a time > 0 (km/h, 0.1 km/h steps)."""
    remedy = "fetch it again (`rpbench data fetch --city manhattan` replaces damaged files)"
    try:  # the three files have no header row
        pts = pd.read_csv(folder / "points.csv.gz", header=None, names=["id", "lat", "lon"]).set_index("id")
        arcs = pd.read_csv(folder / "edges.csv.gz", header=None, names=["id", "source", "sink"]).set_index("id")
        week = pd.read_csv(folder / "week.csv.gz", header=None).set_index(0)
    except (OSError, EOFError, ValueError, pd.errors.ParserError) as exc:
        raise DataError(
            f"the PNAS 2017 network in {str(folder)!r} cannot be read ({one_line(exc)}); {remedy}"
        ) from None
    if week.shape[1] != 24 or not arcs.index.isin(week.index).all() or not arcs["source"].isin(pts.index).all():
        raise DataError(f"the PNAS 2017 network in {str(folder)!r} is not whole (24 hourly times per arc); {remedy}")
    a, b = pts.loc[arcs["source"]], pts.loc[arcs["sink"]]
    length = great_circle_m(a["lon"].to_numpy(), a["lat"].to_numpy(), b["lon"].to_numpy(), b["lat"].to_numpy())
    times = week.loc[arcs.index].to_numpy(float)
    timed = times > 0
    speeds = [(length[timed[:, h]].sum() / times[timed[:, h], h].sum()) * 3.6 for h in range(24)]
    return [round(float(s), 1) for s in speeds]
