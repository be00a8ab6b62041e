"""What a ``rpbench replicate`` folder keeps so that ``rpbench check`` can verify it: rpbench's own engine's runs
as full results folders (``engines/<date>_<strategy>_<engine>/``), and the SHA-256 of every file written
(meta.json's ``manifest``)."""

from __future__ import annotations

from pathlib import Path

from rpbench.backends.presets import Preset
from rpbench.files.digests import file_sha256
from rpbench.report.comparison import write_report
from rpbench.results.folder import StrategyRun, write_folder
from rpbench.scenarios.base import Scenario
from rpbench.scenarios.request import ScenarioRequest
from rpbench.spec import RunEntry, RunSpec

__all__ = ["file_manifest", "write_engine_folder"]


def write_engine_folder(dest: Path, scenario: Scenario, run: StrategyRun, preset: Preset, command: str | None) -> None:
    """One run of rpbench's own engine as a results folder (inputs, event log, trajectories, KPIs, report.md
    without figures): ``rpbench check`` verifies it as it verifies ``rpbench run``'s."""
    dest.mkdir(parents=True)
    write_folder(dest, engine_spec(scenario, run, preset, command), scenario, [run], {}, preset)
    write_report(dest, name=dest.name, figures=False)


def engine_spec(scenario: Scenario, run: StrategyRun, preset: Preset, command: str | None) -> RunSpec:
    """What an engine folder records of its comparison: the scenario as its provenance names it, and its run."""
    provenance = scenario.provenance
    request = ScenarioRequest(
        scenario.name, date=provenance.get("date"), sample=provenance.get("sample"), seed=scenario.seed
    )
    return RunSpec(request, (RunEntry(run.name, run.source, run.options),), preset=preset.name, command=command)


def file_manifest(folder: Path) -> dict[str, str]:
    """SHA-256 of every file under ``folder`` but meta.json, by path relative to it (``/``-separated)."""
    return {
        path.relative_to(folder).as_posix(): file_sha256(path)
        for path in sorted(folder.rglob("*"))
        if path.is_file() and path.relative_to(folder).as_posix() != "meta.json"
    }
