"""``rpbench city import NAME``: turn a road network and a trip table into a city rpbench runs; ``rpbench city
list``: the cities it knows.

The importer and the city folder: :mod:`rpbench.cities`, docs/cities.md.  What the import dropped is said in
one note line per reason on stderr; the summary goes to stdout (one JSON object with ``--json``).  Bad input is
one line and exit status 2, and nothing is written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rpbench.cities.builtin import RECIPES
from rpbench.cities.importer import Sources, check_city_name, import_city
from rpbench.cities.places import cities_home, imported_cities
from rpbench.cities.roads import ARC_COLUMNS, NODE_COLUMNS
from rpbench.cities.trips import NODE_ID_KINDS, TIME_UNITS, TRIP_COLUMNS, TripOptions
from rpbench.commands.output import note, print_json
from rpbench.exceptions import ParameterError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "city",
        help="import a city (a road network and a trip table), or list the cities rpbench knows",
        description="Import any city: an OSMnx GraphML (or a node table and an arc table) and a trip table with "
        "request times and origins and destinations as nodes or coordinates become a city folder that "
        "`rpbench run --scenario city --city NAME --window HH:MM-HH:MM` runs.",
    )
    p.set_defaults(handler=lambda args: _usage(p))
    actions = p.add_subparsers(dest="city_action", metavar="ACTION")
    imp = actions.add_parser(
        "import",
        help="import a city from a road network and a trip table",
        description="Keep the network's largest strongly connected component (what is dropped is counted), "
        "merge parallel arcs into the shortest, place each trip on the network (node ids, positions in the "
        "network file, or coordinates snapped to the nearest node within a radius) and write the city folder.",
    )
    imp.add_argument("name", metavar="NAME", help="the city's name (lower-case letters, digits, '-', '_')")
    imp.add_argument("--network", metavar="FILE", default=None, help="an OSMnx GraphML (.graphml, or .graphml.gz)")
    imp.add_argument("--nodes", metavar="FILE", default=None, help=f"or a node table: {', '.join(NODE_COLUMNS)}")
    imp.add_argument("--arcs", metavar="FILE", default=None, help=f"and an arc table: {', '.join(ARC_COLUMNS)}")
    imp.add_argument(
        "--trips",
        metavar="FILE",
        required=True,
        help="the trip table (CSV, plain or .gz): time, and origin_node, destination_node or origin_lon, "
        "origin_lat, destination_lon, destination_lat",
    )
    imp.add_argument(
        "--column",
        action="append",
        default=[],
        metavar="NAME=SOURCE",
        help="read rpbench's column NAME from the file's column SOURCE (repeatable), e.g. "
        "--column origin_node=pick_up_index",
    )
    imp.add_argument(
        "--time-unit", default="s", choices=sorted(TIME_UNITS), help="unit of numeric times from midnight (default s)"
    )
    imp.add_argument(
        "--node-ids",
        default="ids",
        choices=NODE_ID_KINDS,
        help="trip nodes are the network file's node ids (default) or positions in its node order, from 0",
    )
    imp.add_argument(
        "--snap-radius",
        type=float,
        default=500.0,
        metavar="M",
        help="coordinates farther than M metres from every node are dropped (default 500)",
    )
    imp.add_argument("--date", default=None, help="the day to keep when ISO times span several (YYYY-MM-DD)")
    imp.add_argument("--label", default=None, help="how reports name the city (default: NAME)")
    imp.add_argument("--speed", type=float, default=None, metavar="KMH", help="its vehicles' speed (default 30 km/h)")
    imp.add_argument(
        "--out", metavar="DIR", default=None, help=f"the city folder (default {cities_home()}/NAME, found by name)"
    )
    imp.add_argument("--json", action="store_true", help="print one JSON object")
    imp.set_defaults(handler=_run_import)
    lst = actions.add_parser("list", help="the cities rpbench knows: imported ones and built-in ones")
    lst.add_argument("--json", action="store_true", help="print one JSON object")
    lst.set_defaults(handler=_run_list)


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help(sys.stderr)
    return 2


def _run_import(args: argparse.Namespace) -> int:
    name = check_city_name(args.name)
    columns = _columns(args.column)
    road_columns = {k: v for k, v in columns.items() if k in (*NODE_COLUMNS, *ARC_COLUMNS)}
    trip_columns = {k: v for k, v in columns.items() if k not in road_columns}
    options = TripOptions(
        columns=trip_columns,
        time_unit=args.time_unit,
        node_ids=args.node_ids,
        snap_radius_m=args.snap_radius,
        date=args.date,
    )
    sources = Sources(
        trips=Path(args.trips),
        network=None if args.network is None else Path(args.network),
        nodes=None if args.nodes is None else Path(args.nodes),
        arcs=None if args.arcs is None else Path(args.arcs),
        columns=road_columns,
    )
    dest = Path(args.out) if args.out is not None else cities_home() / name
    city = import_city(
        name, sources, options, dest, label=args.label, speed_kmh=args.speed, make_parent=args.out is None
    )
    for line in city.notes:
        note(f"rpbench: note: {line}")
    record = city.record
    if args.json:
        print_json({"city": name, "folder": str(city.folder), "notes": city.notes, **record})
        return 0
    net, trips = record["network"], record["trips"]
    first, last = trips["first_request_s"], trips["last_request_s"]
    print(
        f"city {name}: {net['nodes_kept']:,} nodes, {net['arcs_kept']:,} arcs, {trips['kept']:,} of "
        f"{trips['rows']:,} trips ({_clock(first)}-{_clock(last)}), written to {city.folder}"
    )
    where = "" if args.out is None else f" (or --city {city.folder})"
    print(f"run it: rpbench run --scenario city --city {name}{where} --window 08:00-09:00")
    return 0


def _run_list(args: argparse.Namespace) -> int:
    imported = imported_cities()
    builtin = {name: recipe.label for name, recipe in RECIPES.items()}
    if args.json:
        print_json({"imported": imported, "builtin": builtin, "folder": str(cities_home())})
        return 0
    print(f"imported (in {cities_home()}): {', '.join(imported) or 'none'}")
    print("built-in: " + ", ".join(f"{n} ({label}; scenarios {n}-peak, {n}-day)" for n, label in builtin.items()))
    return 0


def _columns(items: list[str]) -> dict[str, str]:
    known = (*TRIP_COLUMNS, *NODE_COLUMNS, *ARC_COLUMNS)
    out: dict[str, str] = {}
    for item in items:
        name, sep, source = item.partition("=")
        name, source = name.strip(), source.strip()
        if not sep or not source or name not in known:
            raise ParameterError(f"--column {item!r}: expected NAME=SOURCE with NAME one of {', '.join(known)}")
        if name in out:
            raise ParameterError(f"--column {name} is given twice; give it once")
        out[name] = source
    return out


def _clock(seconds: float) -> str:
    return f"{int(seconds // 3600):02d}:{int(seconds % 3600 // 60):02d}"
