"""The first run on a machine without a data folder: fetch the city's data, else say loudly that it is the toy city.

A command that needs a city's data (Haikou unless it says otherwise), or
defaults to it, asks :func:`obtain_data_dir` for the folder.  When none of the
city's default folders exists (no ``--data``, for Haikou no ``$RPBENCH_DATA``,
see :mod:`rpbench.files.paths`), or the fetched folder lacks registry files (a fetch
that was cut), it says so in one line on stderr and fetches the city's pinned
registry into :func:`~rpbench.files.paths.fetched_data_dir` exactly as
``rpbench data fetch --city CITY`` does (:func:`rpbench.data.fetch.fetch`:
checksums, atomic writes, ``$RPBENCH_DATA_MIRROR``), so the next command finds
it.  ``offline`` skips the fetch.  Messages name the city
(:data:`~rpbench.files.paths.CITY_LABELS`).

Without a folder, :func:`ensure_data_dir` raises a one-line error saying why,
and a command whose default scenario is the Haikou one runs the toy city
after :func:`warn_synthetic`'s banner instead
(:func:`rpbench.scenarios.registry.default_scenario_name`).  Only the default
falls back: a scenario named on the command line is never swapped for another.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rpbench.data.fetch import RegistryEntry, disk_full_hint, fetch, load_registry, mirror_base, rerun_hint
from rpbench.exceptions import DataNotFoundError, RpbenchError
from rpbench.files import paths
from rpbench.files.paths import (
    DATA_ENV,
    DATA_MIRROR_ENV,
    DEFAULT_CITY,
    city_label,
    describe_candidate,
    fetch_command,
    fetched_data_dir,
    locate_data_dir,
)

#: The command that fetches Haikou's data (:func:`rpbench.files.paths.fetch_command` names any city's).
FETCH_COMMAND = fetch_command()


@dataclass(frozen=True)
class FetchPlan:
    """What the automatic fetch would download: the registry files missing from ``city``'s fetched folder."""

    dest: Path
    source: str  # "registry" (the pinned upstream URLs) or the mirror's base URL
    registry_files: int
    todo: tuple[RegistryEntry, ...]
    city: str = DEFAULT_CITY

    @property
    def resuming(self) -> bool:
        return len(self.todo) < self.registry_files

    @property
    def content_bytes(self) -> int:
        """Bytes of content to fetch: what comes over the wire from the pinned sources (they serve it plain)."""
        return sum(e.size for e in self.todo)

    def lack(self) -> str:
        """What is missing, as the subject of a sentence."""
        label = city_label(self.city)
        if self.resuming:
            return (
                f"the fetched {label} data folder {self.dest} lacks {len(self.todo)} of its {self.registry_files} files"
            )
        return f"no {label} data folder found"

    def announcement(self) -> str:
        """The one line said before fetching: what, how much, from where, to where."""
        files = f"{len(self.todo)} file{'s' if len(self.todo) != 1 else ''}"
        if self.source == "registry":
            size, origin = f"{_mb(self.content_bytes)} to download", "its pinned GitHub sources"
        else:
            size, origin = f"{_mb(self.content_bytes)} of content, served gzipped", f"the mirror {self.source}"
        return (
            f"rpbench: {self.lack()}: {'resuming the fetch' if self.resuming else 'fetching it once'} "
            f"({files}, {size}, SHA-256 checked) from {origin} into {self.dest}"
        )

    def as_dict(self) -> dict:
        return {
            "dest": str(self.dest),
            "source": self.source,
            "files": len(self.todo),
            "registry_files": self.registry_files,
            "content_bytes": self.content_bytes,
        }


def fetch_plan(city: str = DEFAULT_CITY) -> FetchPlan:
    """The automatic fetch's plan for ``city`` (a file present counts as fetched: :func:`fetch` checks its
    content).  A city without a registry, a mangled registry or a bad ``$RPBENCH_DATA_MIRROR`` raises."""
    entries = _registry(city)
    dest = fetched_data_dir(city)
    todo = tuple(e for e in entries if not (dest / e.name).is_file())
    source = mirror_base(None, city) or "registry"
    return FetchPlan(dest=dest, source=source, registry_files=len(entries), todo=todo, city=city)


def _registry(city: str) -> list[RegistryEntry]:
    # As in rpbench.data.fetch: Haikou's registry is asked for without an argument, so that a replacement
    # of this module's load_registry that takes no city keeps serving it.
    return load_registry() if city == DEFAULT_CITY else load_registry(city=city)


def obtain_data_dir(
    explicit: str | os.PathLike | None = None,
    *,
    offline: bool = False,
    progress: bool | None = None,
    say: Callable[[str], None] | None = None,
    city: str = DEFAULT_CITY,
) -> tuple[Path | None, str]:
    """``city``'s data folder, fetched first when needed: ``(folder, "")``, or ``(None, why)`` when there is none.

    ``why`` is one line naming the city (``"no Haikou data folder found and
    --offline skips fetching it"``, ``"... and fetching it failed: ERROR"``).
    A folder the user provides (``explicit``, for Haikou ``$RPBENCH_DATA``,
    ``../shared``) is used as it is; an explicit one that does not exist, or
    an unknown city, raises, as in :func:`rpbench.files.paths.locate_data_dir`.
    ``progress``: the download's progress bar (default: when stderr is a
    terminal); ``say`` prints the announcement and the closing line (default:
    stderr).
    """
    say = say or _stderr
    folder, origin = locate_data_dir(explicit, city)
    # Only the folder rpbench fills itself is checked for completeness and completed.
    if folder is not None and origin != describe_candidate(fetched_data_dir(city), city):
        return folder, ""
    try:
        plan = fetch_plan(city)
    except RpbenchError as exc:  # a bad $RPBENCH_DATA_MIRROR, a mangled registry
        return None, f"no {city_label(city)} data folder found and fetching it failed: {_one_line(exc, city)}"
    if folder is not None and not plan.todo:
        return folder, ""
    them = "them" if plan.resuming else "it"
    if offline:
        return None, f"{plan.lack()} and --offline skips fetching {them}"
    say(plan.announcement())
    try:
        report = fetch(plan.dest, city=city, progress=sys.stderr.isatty() if progress is None else progress)
    except RpbenchError as exc:
        return None, f"{plan.lack()} and fetching {them} failed: {_one_line(exc, city)}"
    dest = report.dest
    on_disk = sum((dest / e.name).stat().st_size for e in _registry(city))
    say(
        f"rpbench: fetched {len(report.downloaded)} files ({_mb(report.content_bytes)} of content, checksums "
        f"verified) into {dest}, {_mb(on_disk)} on disk; rpbench finds it there from now on"
    )
    return dest, ""


def ensure_data_dir(
    explicit: str | os.PathLike | None = None,
    *,
    what: str,
    offline: bool = False,
    progress: bool | None = None,
    city: str = DEFAULT_CITY,
) -> Path:
    """``city``'s data folder for ``what`` (fetched first when needed, see :func:`obtain_data_dir`), or a
    :class:`DataNotFoundError` naming the city, saying why there is none and how to get it."""
    folder, why = obtain_data_dir(explicit, offline=offline, progress=progress, city=city)
    if folder is not None:
        return folder
    tried = ", ".join(str(c) for c in paths.candidate_data_dirs(city))  # through the module: tests replace it
    named = f"pass --data DIR or set ${DATA_ENV}" if city == DEFAULT_CITY else "or pass --data DIR"
    raise DataNotFoundError(
        f"no {city_label(city)} data for {what}: {why} (folders tried: {tried}); get it with `{fetch_command(city)}` "
        f"(it resumes a cut fetch; ${DATA_MIRROR_ENV} names a mirror), {named}"
    )


def synthetic_banner(why: str) -> list[str]:
    """The lines said before a default run falls back to the toy city: what the numbers are, why, and the fix."""
    return [
        "rpbench: SYNTHETIC DATA: the numbers that follow are from the built-in toy city (a small grid generated "
        "in code), not from Haikou",
        f"rpbench:   why: {why}",
        f"rpbench:   to get the real data: {FETCH_COMMAND}",
    ]


def warn_synthetic(why: str) -> None:
    """Print :func:`synthetic_banner` on stderr."""
    for line in synthetic_banner(why):
        _stderr(line)


def _mb(n: int) -> str:
    return f"{n / 1e6:.1f} MB"


def _one_line(exc: BaseException, city: str) -> str:
    # The errors here name the command to rerun themselves.
    return " ".join(str(exc).removesuffix(rerun_hint(city)).removesuffix(disk_full_hint(city)).split())


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)
