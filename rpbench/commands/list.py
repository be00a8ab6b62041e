"""``rpbench list``: scenarios, the data folders, solver presets and whether each is installed.

The data folder of each city rpbench knows (:data:`rpbench.files.paths.CITY_LABELS`): Haikou's under the keys
``data_dir``, ``data_dir_source``, ``data_dir_candidates`` and ``data_fetch_pending`` (``--data`` names it),
and every city's, Haikou's too, under ``data_folders[CITY]`` with the same keys and its ``label``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rpbench.backends.presets import load_preset, preset_names
from rpbench.commands.args import add_data_arg
from rpbench.commands.output import print_json
from rpbench.data import available_peak_dates
from rpbench.data.first_run import fetch_plan
from rpbench.exceptions import RpbenchError
from rpbench.files.paths import (
    CITY_LABELS,
    DEFAULT_CITY,
    candidate_data_dirs,
    describe_candidate,
    fetch_command,
    fetched_data_dir,
    locate_data_dir,
)
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.scenarios import SCENARIOS
from rpbench.scenarios.base import Params
from rpbench.spec import options_class
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class, strategy_plugin_names


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "list",
        help="list scenarios, data folders and solver presets",
        description="List scenarios, the data folder in use for each city, and solver presets "
        "with whether each preset's backend is installed.",
    )
    add_data_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_run)


def data_folder_info(city: str, data: str | None = None) -> dict:
    """Where ``city``'s data folder is (``data``: its ``--data``), and what the first command needing it
    would fetch (nothing is downloaded here): the keys ``rpbench list --json`` gives each city."""
    folder, origin = locate_data_dir(data, city)
    pending = None
    if folder is None or origin == describe_candidate(fetched_data_dir(city), city):
        try:
            plan = fetch_plan(city)
            pending = plan.as_dict() if plan.todo else None
        except RpbenchError as exc:  # a bad $RPBENCH_DATA_MIRROR: said here, raised by the fetch
            pending = {"error": str(exc)}
    return {
        "label": CITY_LABELS[city],
        "data_dir": str(folder) if folder else None,
        "data_dir_source": origin,
        "data_dir_candidates": [str(c) for c in candidate_data_dirs(city)],
        "data_fetch_pending": pending,
    }


def gather(data: str | None) -> dict:
    """Everything ``rpbench list`` says; ``data`` (``--data``) is Haikou's folder, the scenarios' city."""
    folders = {city: data_folder_info(city, data if city == DEFAULT_CITY else None) for city in CITY_LABELS}
    haikou = folders[DEFAULT_CITY]
    folder = Path(haikou["data_dir"]) if haikou["data_dir"] else None
    presets = []
    for name in preset_names():
        try:
            preset = load_preset(name)
            cls = preset.adapter()
            presets.append(
                {
                    "name": name,
                    "backend": preset.backend,
                    "installed": cls.is_installed(),
                    "missing": cls.missing_libraries(),
                    "exact": sorted(s.value for s in cls.exact),
                    "description": preset.description,
                }
            )
        except RpbenchError as exc:
            presets.append({"name": name, "backend": None, "installed": False, "error": str(exc)})
    return {
        **{key: value for key, value in haikou.items() if key != "label"},
        "data_folders": folders,
        "peak_dates": available_peak_dates(folder) if folder else [],
        "scenarios": [
            {
                "name": s.name,
                "description": s.description,
                "needs_data": s.needs_data,
                "available": (not s.needs_data) or folder is not None,
            }
            for s in SCENARIOS.values()
        ],
        "presets": presets,
        "strategies": [_run_entry(name) for name in [*STRATEGY_REGISTRY, *strategy_plugin_names(), *ORACLE_RUNS]],
        "parameters": Params().as_dict(),
    }


def _print_data_folder(entry: dict, title: str, now: str) -> None:
    """A city's data folder (``entry``: :func:`data_folder_info`'s keys), and what its first use fetches."""
    folder, pending = entry["data_dir"], entry["data_fetch_pending"]
    if folder:
        print(f"{title}: {folder} (from {entry['data_dir_source']})")
    else:
        print(f"{title}: none found")
    if pending and "error" in pending:
        print(f"  the first command that needs the data cannot fetch it: {pending['error']}")
    elif pending:
        lacks = f"lacks {pending['files']} of its {pending['registry_files']} files: " if folder else ""
        source = "the pinned GitHub sources" if pending["source"] == "registry" else f"the mirror {pending['source']}"
        print(
            f"  {lacks}the first command that needs the data fetches {pending['files']} files "
            f"({pending['content_bytes'] / 1e6:.1f} MB of content) from {source} into {pending['dest']} {now}"
        )


def _run_entry(name: str) -> dict:
    """A strategy's or oracle run's label, description and declared options (``--opt NAME.OPTION=VALUE``)."""
    if name in ORACLE_RUNS:
        run = ORACLE_RUNS[name]
        label, description = run.label, run.description
    else:
        try:
            cls = strategy_class(name)
        except RpbenchError as exc:  # one broken plug-in is listed as broken; the rest are still listed
            return {"name": name, "label": "", "description": "", "options": {}, "error": str(exc)}
        label, description = cls.label, cls.description
    return {"name": name, "label": label, "description": description, "options": options_class(name).help()}


def _run(args: argparse.Namespace) -> int:
    info = gather(args.data)
    if args.json:
        print_json(info)
        return 0
    _print_data_folder(info, "data folder", "(now: `rpbench data fetch`; --offline runs the toy city instead)")
    if info["peak_dates"]:
        dates = info["peak_dates"]
        print(f"  peak-hour dates: {len(dates)} ({dates[0]} .. {dates[-1]})")
    for city, entry in info["data_folders"].items():
        if city != DEFAULT_CITY:
            _print_data_folder(entry, f"{entry['label']} data folder", f"(now: `{fetch_command(city)}`)")
    print("\nscenarios:")
    for s in info["scenarios"]:
        mark = "" if s["available"] else "  [needs data]"
        print(f"  {s['name']:<14} {s['description']}{mark}")
    print("\nsolver presets (--solver NAME):")
    if not info["presets"]:
        print("  none")
    for p in info["presets"]:
        if p.get("error"):
            print(f"  {p['name']:<14} BROKEN: {p['error']}")
            continue
        state = "installed" if p["installed"] else f"NOT INSTALLED (missing {', '.join(p['missing'])})"
        print(f"  {p['name']:<14} {p['backend']:<9} {state:<10} exact: {', '.join(p['exact'])}")
    print("\nstrategies and oracles (--strategies; options: --opt NAME.OPTION=VALUE):")
    for s in info["strategies"]:
        if s.get("error"):
            print(f"  {s['name']:<16} BROKEN: {s['error']}")
            continue
        print(f"  {s['name']:<16} {s['label']:<20} {s['description']}")
        for option, text in s["options"].items():
            print(f"      {option:<22} {text}")
    print("\nparameters (--param NAME=VALUE): " + ", ".join(f"{k}={v:g}" for k, v in info["parameters"].items()))
    return 0
