"""``protocol-units``: an evaluation's units are exactly its protocol's (day, seed) units, each run as it says.

The recorded protocol (:mod:`.protocol`) names days and seeds: the evaluation must hold one unit per pair, no
more and none fewer (``children`` in meta.json, and the folders), each named as ``rpbench evaluate`` names it.
Each unit's meta.json must record that day, that seed, the protocol's scenario and sample and no parameter
override, the protocol's runs (:mod:`.unit_runs`), presets and options, and the evaluation's decision budget.
The units of one protocol share its scenario, hence one road network and one set of parameters: a unit
copied in from another experiment and relabelled in its meta.json still differs there.  These are the
records the tables are built from; the units' own checks prove their numbers from their event logs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rpbench import results
from rpbench.check.core import RunCheck
from rpbench.check.protocol import RecordedProtocol
from rpbench.check.unit_runs import matched_runs, option_problems, preset_problems
from rpbench.exceptions import RpbenchError, one_line
from rpbench.report.evaluation import unit_name
from rpbench.results.layout import META, NETWORK
from rpbench.scenarios import ScenarioRequest

UNITS_CHECK = "protocol-units"
#: What every unit of one evaluation shares (a path into its meta.json, and what it is called).
SHARED = ((("params",), "parameters"), (("inputs_digest", "files", NETWORK), "road network"))


def check_units(fc: RunCheck, parent: Path, meta: dict, protocol: RecordedProtocol) -> None:
    """The unit list against the protocol's days x seeds, then each listed unit's record against the protocol."""
    expected = {unit_name(day, seed): (day, seed) for day in protocol.days for seed in protocol.seeds}
    listed = _list(meta.get("children"))
    for name, (day, seed) in expected.items():
        if name not in listed:
            fc.fail(UNITS_CHECK, f"unit {name} ({_unit_text(day, seed)}) of {protocol.title} is not among the units")
    for name in listed:
        if name not in expected:
            fc.fail(UNITS_CHECK, f"{name} is not a unit of {protocol.title} (days {_days_text(protocol)} x seeds "
                                 f"{', '.join(map(str, protocol.seeds))})")  # fmt: skip
    shared: dict[str, tuple[str, Any]] = {}
    mapping: dict[str, tuple[str, dict[str, str]]] = {}
    not_compared: set[str] = set()
    for name in (n for n in listed if n in expected and (parent / n / META).is_file()):
        try:
            unit = results.read_meta(parent / name)
        except RpbenchError as exc:
            fc.fail(UNITS_CHECK, f"{name}: {one_line(exc)}")
            continue
        problems, notes = _unit_problems(unit, protocol, *expected[name], meta.get("decision_budget_s"))
        for problem in problems:
            fc.fail(UNITS_CHECK, f"{name} {problem}")
        not_compared |= notes
        for path, what in SHARED:
            value, first = _at(unit, path), shared.setdefault(what, (name, _at(unit, path)))
            if value != first[1]:
                fc.fail(UNITS_CHECK, f"{name}'s {what} differ from {first[0]}'s: the units of one protocol share them")
        runs = matched_runs(protocol.strategies, unit)[0]
        first_runs = mapping.setdefault("runs", (name, runs))
        if runs != first_runs[1]:
            fc.fail(UNITS_CHECK, f"{name} names the protocol's runs {runs}, {first_runs[0]} names them {first_runs[1]}")
    for note in sorted(not_compared):
        fc.skip(UNITS_CHECK, note)
    fc.checked["protocol_units"] = len(expected)


def _unit_problems(
    unit: dict, protocol: RecordedProtocol, day: str | None, seed: int, budget: object
) -> tuple[list[str], set[str]]:
    """What in one unit's meta.json differs from what the protocol (and the evaluation's budget) give it, and
    what could not be compared (a plug-in's options)."""
    scenario = _dict(unit.get("scenario"))
    problems = []
    if scenario.get("name") != protocol.scenario:
        problems.append(f"is of scenario {scenario.get('name')!r}, the protocol's is {protocol.scenario!r}")
    try:
        want = ScenarioRequest(protocol.scenario, date=day, sample=protocol.sample, seed=seed).meta()
    except RpbenchError as exc:
        problems.append(f"cannot be compared with the protocol's scenario ({one_line(exc)})")
        want = {}
    have = _dict(scenario.get("args"))
    for key in sorted(set(want) | set(have)):
        if have.get(key) != want.get(key):
            problems.append(f"records {key} {have.get(key)!r}, the protocol gives it {want.get(key)!r}")
    if unit.get("decision_budget_s") != budget:
        problems.append(f"records decision budget {unit.get('decision_budget_s')!r}, the evaluation {budget!r}")
    matched, run_problems = matched_runs(protocol.strategies, unit)
    problems += run_problems + preset_problems(unit, protocol.preset, protocol.oracle_preset)
    records = _dict(unit.get("runs"))
    notes = set()
    for entry, run in matched.items():
        found, not_compared = option_problems(entry, run, records[run])
        problems += found
        notes |= {not_compared} if not_compared else set()
    return problems, notes


def _at(record: dict, path: tuple[str, ...]) -> Any:
    value: Any = record
    for key in path:
        value = value.get(key) if isinstance(value, dict) else None
    return value


def _dict(value: object) -> dict:
    return value if isinstance(value, dict) else {}


def _list(value: object) -> list:
    return value if isinstance(value, list) else []


def _unit_text(day: str | None, seed: int) -> str:
    return f"day {day}, seed {seed}" if day else f"seed {seed}"


def _days_text(protocol: RecordedProtocol) -> str:
    return protocol.dates or "(undated)"
