"""What an evaluation's protocol gives each run of a unit: its name, its solver preset, its options.

A protocol lists its runs (``strategies``: built-in names, variants such as ``fl@tau0_s=200``, plug-in
sources) and two presets, and sets no option: a unit's runs are those entries, each under the name the
harness gives it (:func:`rpbench.report.evaluation.entry_run`), solved by the protocol's presets, each with
its class's default options and its variant's settings.  A simulated run's option whose default is None is
filled in by the strategy itself (FL's τ_0 and l̄, calibrated on each unit), so it is not compared; an offline
run's pair rules are compared flag by flag (their thresholds are the unit's parameters, which its own
``oracle-rules`` check holds them to).  A plug-in's options are not compared: the checker imports no code a
folder names.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

from rpbench.exceptions import RpbenchError, one_line
from rpbench.oracle.pairs import PairRules
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.report.evaluation import entry_run
from rpbench.results.store import to_jsonable
from rpbench.spec import VARIANT_SEP, options_class
from rpbench.strategies import STRATEGY_REGISTRY

#: The pair rules that are flags of the offline run (the others are the scenario's thresholds).
OFFLINE_RULE_FLAGS = ("both_pickup_orders", "pickup_check", "allow_enroute", "order_rule", "window")


def preset_name(given: str) -> str:
    """The name a unit records for a preset the protocol gives by name or as a ``.toml`` path (its stem)."""
    return given.rsplit("/", 1)[-1].removesuffix(".toml") if given.endswith(".toml") else given


def recorded_runs(meta: Mapping[str, Any]) -> list[str]:
    """A unit's runs: its manifest (``manifest.runs``), else the runs it records."""
    manifest = meta.get("manifest")
    if isinstance(manifest, Mapping) and isinstance(manifest.get("runs"), list):
        return [str(r) for r in manifest["runs"]]
    runs = meta.get("runs")
    return [str(r) for r in runs] if isinstance(runs, Mapping) else []


def matched_runs(strategies: Sequence[str], meta: Mapping[str, Any]) -> tuple[dict[str, str], list[str]]:
    """Each protocol entry's run in a unit (entries it lacks left out) and the problems: an entry without a
    run, a run no entry names."""
    records = meta.get("runs") if isinstance(meta.get("runs"), Mapping) else {}
    assert isinstance(records, Mapping)
    found = {entry: entry_run(entry, records) for entry in strategies}
    matched = {entry: run for entry, run in found.items() if run is not None}
    problems = [f"holds no run of the protocol's {entry!r}" for entry, run in found.items() if run is None]
    named = set(matched.values())
    problems += [
        f"holds run {run!r}, which the protocol does not list" for run in recorded_runs(meta) if run not in named
    ]
    return matched, problems


def preset_problems(meta: Mapping[str, Any], preset: str, oracle_preset: str | None) -> list[str]:
    """The unit's simulations are solved by the protocol's preset, its offline runs by its oracle preset."""
    problems = []
    recorded = meta.get("preset")
    name = recorded.get("name") if isinstance(recorded, Mapping) else None
    if name != preset_name(preset):
        problems.append(f"was solved with preset {name!r}, the protocol's is {preset_name(preset)!r}")
    offline = preset_name(oracle_preset or preset)
    records = meta.get("runs") if isinstance(meta.get("runs"), Mapping) else {}
    assert isinstance(records, Mapping)
    for run, record in records.items():
        if isinstance(record, Mapping) and record.get("kind") == "oracle" and record.get("solver") != offline:
            problems.append(
                f"solved its offline run {run!r} with {record.get('solver')!r}, the protocol's is {offline!r}"
            )
    return problems


def option_problems(entry: str, run: str, record: Mapping[str, Any]) -> tuple[list[str], str | None]:
    """A run's recorded options (a simulation) or pair rules (an offline run) against the protocol's entry;
    returns the problems and, when the run's class cannot be loaded here, why nothing was compared."""
    if record.get("kind") == "oracle":
        return _rule_problems(run, record), None
    _, *settings = entry.split(VARIANT_SEP)
    source = record.get("source")
    if source not in STRATEGY_REGISTRY:
        return [], f"run {run!r}: the options of a plug-in ({source!r}) are not compared"
    try:
        declared = options_class(str(source)).parse(run, dict(s.split("=", 1) for s in settings))
    except (RpbenchError, ValueError) as exc:
        return [f"run {run!r}: the protocol's {entry!r} gives options its strategy refuses ({one_line(exc)})"], None
    want = to_jsonable(declared.as_dict())
    have = record.get("options")
    if not isinstance(have, Mapping):
        return [f"run {run!r} records no options"], None
    problems = [f"run {run!r} records option {k!r}, which its strategy does not declare" for k in have if k not in want]
    for key, value in want.items():
        if value is not None and key in have and have[key] != value:  # a key missing: an older rpbench's record
            problems.append(f"run {run!r} ran with {key}={have[key]!r}; the protocol gives it {value!r}")
    return problems, None


def _rule_problems(run: str, record: Mapping[str, Any]) -> list[str]:
    """An offline run's pair-rule flags are its defaults: the protocol sets no option."""
    spec = ORACLE_RUNS.get(run)
    rules = record.get("rules")
    if spec is None or not isinstance(rules, Mapping):
        return [f"offline run {run!r} is not one rpbench knows, or records no pair rules"]
    defaults = {f.name: f.default for f in dataclasses.fields(PairRules)}
    want = {k: spec.defaults.get(k, defaults[k]) for k in OFFLINE_RULE_FLAGS}
    return [
        f"offline run {run!r} ran with {k}={rules[k]!r}; the protocol gives it {v!r}"
        for k, v in want.items()
        if k in rules and rules[k] != v
    ]
