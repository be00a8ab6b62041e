"""``rpbench list``: scenarios, the data folder, solver presets and whether each is installed."""

from __future__ import annotations

import argparse

from rpbench.backends.presets import load_preset, preset_names
from rpbench.commands.args import add_data_arg
from rpbench.commands.output import print_json
from rpbench.data import available_peak_dates
from rpbench.data.first_run import fetch_plan
from rpbench.exceptions import RpbenchError
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.paths import default_data_candidates, describe_candidate, fetched_data_dir, locate_data_dir
from rpbench.scenarios import SCENARIOS
from rpbench.scenarios.base import Params
from rpbench.spec import options_class
from rpbench.strategies import STRATEGY_REGISTRY, strategy_class, strategy_plugin_names


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "list",
        help="list scenarios, data folder and solver presets",
        description="List scenarios, the data folder in use, and solver presets "
        "with whether each preset's backend is installed.",
    )
    add_data_arg(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_run)


def gather(data: str | None) -> dict:
    folder, origin = locate_data_dir(data)
    pending = None  # what the first command needing the data would fetch (nothing is downloaded here)
    if folder is None or origin == describe_candidate(fetched_data_dir()):
        try:
            plan = fetch_plan()
            pending = plan.as_dict() if plan.todo else None
        except RpbenchError as exc:  # a bad $RPBENCH_DATA_MIRROR: said here, raised by the fetch
            pending = {"error": str(exc)}
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
        "data_dir": str(folder) if folder else None,
        "data_dir_source": origin,
        "data_dir_candidates": [str(c) for c in default_data_candidates()],
        "data_fetch_pending": pending,
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


def _run_entry(name: str) -> dict:
    """A strategy's or oracle run's label, description and declared options (``--opt NAME.OPTION=VALUE``)."""
    if name in ORACLE_RUNS:
        run = ORACLE_RUNS[name]
        label, description = run.label, run.description
    else:
        cls = strategy_class(name)
        label, description = cls.label, cls.description
    return {"name": name, "label": label, "description": description, "options": options_class(name).help()}


def _run(args: argparse.Namespace) -> int:
    info = gather(args.data)
    if args.json:
        print_json(info)
        return 0
    folder, pending = info["data_dir"], info["data_fetch_pending"]
    if folder:
        print(f"data folder: {folder} (from {info['data_dir_source']})")
    else:
        print("data folder: none found")
    if pending and "error" in pending:
        print(f"  the first command that needs the data cannot fetch it: {pending['error']}")
    elif pending:
        lacks = f"lacks {pending['files']} of its {pending['registry_files']} files: " if folder else ""
        source = "the pinned GitHub sources" if pending["source"] == "registry" else f"the mirror {pending['source']}"
        print(
            f"  {lacks}the first command that needs the data fetches {pending['files']} files "
            f"({pending['content_bytes'] / 1e6:.1f} MB of content) from {source} into {pending['dest']} "
            "(now: `rpbench data fetch`; --offline runs the toy city instead)"
        )
    if info["peak_dates"]:
        dates = info["peak_dates"]
        print(f"  peak-hour dates: {len(dates)} ({dates[0]} .. {dates[-1]})")
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
        print(f"  {s['name']:<16} {s['label']:<20} {s['description']}")
        for option, text in s["options"].items():
            print(f"      {option:<22} {text}")
    print("\nparameters (--param NAME=VALUE): " + ", ".join(f"{k}={v:g}" for k, v in info["parameters"].items()))
    return 0
