"""Where a city folder is: a path to one, a city imported into the data home, or a built-in city.

``rpbench city import NAME`` writes ``<data home>/cities/NAME`` (``$RPBENCH_DATA_HOME`` moves the data
home); a built-in city (:data:`~rpbench.cities.builtin.RECIPES`) is made from its data folder into the cache
the first time it is used.
"""

from __future__ import annotations

from pathlib import Path

from rpbench.cities.builtin import RECIPES, builtin_city
from rpbench.cities.folder import CITY_JSON, City, read_city
from rpbench.data.first_run import ensure_data_dir
from rpbench.exceptions import DataNotFoundError
from rpbench.files.paths import data_home

#: The data home's folder of imported cities.
CITIES_FOLDER = "cities"


def cities_home() -> Path:
    """Where ``rpbench city import`` writes a city by default: ``<data home>/cities``."""
    return data_home() / CITIES_FOLDER


def imported_cities() -> list[str]:
    """The names of the cities imported into the data home."""
    home = cities_home()
    return sorted(p.name for p in home.iterdir() if (p / CITY_JSON).is_file()) if home.is_dir() else []


def find_city(name: str, data_dir: str | Path | None = None) -> Path:
    """The city folder ``name`` names: a folder holding a ``city.json``, a city of the data home, or a built-in
    city made from its data folder (``data_dir``, else its default folders, fetched when none is found)."""
    path = Path(name).expanduser()
    if (path / CITY_JSON).is_file():
        return path
    if (cities_home() / name / CITY_JSON).is_file():
        return cities_home() / name
    if name in RECIPES:
        return builtin_city(name, ensure_data_dir(data_dir, what=f"city {name!r}", city=name))
    known = [*RECIPES, *imported_cities()]
    raise DataNotFoundError(
        f"city {name!r} is neither a city folder, nor a city imported with `rpbench city import`, nor a built-in "
        f"city (known: {', '.join(known) or 'none'})"
    )


def load_city(name: str, data_dir: str | Path | None = None) -> City:
    """The city ``name`` names (:func:`find_city`), read and checked."""
    return read_city(find_city(name, data_dir))
