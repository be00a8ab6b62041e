"""Import a city: a road network file and a trip table in, a city folder (:mod:`.folder`) out.

:func:`import_city` reads the network (:mod:`.roads`: an OSMnx GraphML, or a node table and an arc
table), keeps its largest strongly connected component, merges parallel arcs and drops self-loops, places
the trips on what is kept (:mod:`.trips`), and writes the folder under a hidden name, renamed into place
once whole: an error leaves nothing behind.  What was dropped is counted in ``city.json`` and said in
:attr:`ImportedCity.notes`.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rpbench.cities.folder import write_city
from rpbench.cities.roads import RawRoads, read_graphml, read_node_arc_tables, reduce_roads
from rpbench.cities.trips import TripOptions, read_and_place
from rpbench.exceptions import ParameterError
from rpbench.files.digests import content_sha256
from rpbench.files.paths import temporary_folder
from rpbench.network import RoadNetwork

#: A city's name: it names its folder and ``--city NAME``.
CITY_NAME = re.compile(r"^[a-z0-9][a-z0-9_-]{0,63}$")
#: Importing a city bumps this when the same files would give another city folder.
IMPORTER_VERSION = 1
#: Speeds a city may default to (km/h): walking pace to motorway.
SPEED_RANGE_KMH = (3.0, 130.0)


@dataclass(frozen=True)
class Sources:
    """The files a city is imported from: ``network`` (GraphML) or ``nodes`` and ``arcs``, and ``trips``."""

    trips: Path
    network: Path | None = None
    nodes: Path | None = None
    arcs: Path | None = None
    #: the node and arc tables' column names, by rpbench's (``node_id``, ``lon``, ``lat``, ``from_node``, ...)
    columns: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if (self.network is None) == (self.nodes is None and self.arcs is None):
            raise ParameterError("give the network as --network FILE (GraphML) or as --nodes FILE --arcs FILE")
        if self.network is None and (self.nodes is None or self.arcs is None):
            raise ParameterError("a network given as tables needs both --nodes FILE and --arcs FILE")

    def files(self) -> list[Path]:
        return [p for p in (self.network, self.nodes, self.arcs, self.trips) if p is not None]

    def read_roads(self) -> RawRoads:
        if self.network is not None:
            return read_graphml(self.network)
        assert self.nodes is not None and self.arcs is not None  # __post_init__
        return read_node_arc_tables(self.nodes, self.arcs, self.columns)


@dataclass(frozen=True)
class ImportedCity:
    """A city folder just written, with what its ``city.json`` records and one line per thing dropped."""

    folder: Path
    record: dict[str, Any]
    notes: list[str]


def check_city_name(name: str) -> str:
    if not CITY_NAME.match(name):
        raise ParameterError(
            f"city name {name!r}: lower-case letters, digits, '-' and '_', starting with a letter or digit, "
            "at most 64 characters (it names the city's folder)"
        )
    return name


def import_city(
    name: str,
    sources: Sources,
    trip_options: TripOptions,
    dest: Path,
    *,
    label: str | None = None,
    speed_kmh: float | None = None,
    speed_kmh_by_hour: list[float] | None = None,
    provenance: Mapping[str, Any] | None = None,
    make_parent: bool = False,
) -> ImportedCity:
    """Read ``sources``, keep what rpbench can run, and write the city folder ``dest`` (which must not exist).

    ``label``: how reports name the city; ``speed_kmh``: its vehicles' speed, or ``speed_kmh_by_hour``: one
    per hour of the day (neither: the paper's 30 km/h); ``provenance``: what else ``city.json`` should say of
    where the files come from; ``make_parent``: create ``dest``'s missing parent folders (once the inputs
    have been read whole: bad input creates nothing).
    """
    check_city_name(name)
    for speed in ([speed_kmh] if speed_kmh is not None else []) + list(speed_kmh_by_hour or []):
        if not SPEED_RANGE_KMH[0] <= speed <= SPEED_RANGE_KMH[1]:
            low, high = SPEED_RANGE_KMH
            raise ParameterError(f"--speed {speed!r} km/h: a speed in [{low:g}, {high:g}] km/h")
    if speed_kmh_by_hour is not None and len(speed_kmh_by_hour) != 24:
        raise ParameterError(f"a speed per hour of the day: 24 values, not {len(speed_kmh_by_hour)}")
    if dest.exists() or dest.is_symlink():
        raise ParameterError(f"city folder {str(dest)!r} exists already; remove it or choose another name or --out")
    if not make_parent and not dest.parent.is_dir():
        raise ParameterError(f"cannot write city folder {str(dest)!r}: its parent folder does not exist")
    raw = sources.read_roads()
    reduction = reduce_roads(raw, name)
    network = RoadNetwork.from_tables(reduction.tables)
    trips = read_and_place(sources.trips, trip_options, raw, network)
    record = {
        "name": name,
        "label": label or name,
        "importer_version": IMPORTER_VERSION,
        "sources": {p.name: content_sha256(p) for p in sources.files()},
        "provenance": dict(provenance or {}),
        "network": {"nodes_are": raw.ids, **reduction.record()},
        "trips": trips.record,
        "speed_kmh": speed_kmh,
        "speed_kmh_by_hour": speed_kmh_by_hour,
    }
    if make_parent:
        dest.parent.mkdir(parents=True, exist_ok=True)
    staging = temporary_folder(dest)
    try:
        record = write_city(staging, record, reduction, trips)
        staging.rename(dest)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return ImportedCity(dest, record, _notes(reduction.record(), trips.notes))


def _notes(network: dict[str, int], trip_notes: list[str]) -> list[str]:
    notes = []
    if network["nodes_dropped"]:
        notes.append(
            f"{network['nodes_dropped']:,} of {network['nodes_in']:,} nodes dropped: outside the largest of "
            f"{network['strong_components']:,} strongly connected components (with "
            f"{network['arcs_dropped_with_their_nodes']:,} arcs)"
        )
    if network["parallel_arcs_merged"]:
        notes.append(f"{network['parallel_arcs_merged']:,} parallel arcs merged into the shortest of their pair")
    if network["self_loops_dropped"]:
        notes.append(f"{network['self_loops_dropped']:,} self-loops dropped")
    return notes + trip_notes
