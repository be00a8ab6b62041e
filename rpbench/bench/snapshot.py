"""Freeze chosen rounds of simulation runs, and offline pairing models, into instance files
(:mod:`rpbench.model.instances`).

Each strategy is simulated on the scenario with the preset; the models of
the chosen rounds (round indices, or the largest rounds by columns) are
written with their provenance.  Each offline run (``bound``, ``oracle1``,
``oracle2``) is one pairing model over all the scenario's orders, built as
the run builds it (:func:`rpbench.oracle.solve.oracle_model`) but not solved
(its ``objective`` is null).  A ``manifest.json`` lists them all.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from rpbench import results
from rpbench.backends import load_preset
from rpbench.harness.comparison import calibrated, simulate_strategy
from rpbench.model import Model, Solution
from rpbench.model.instances import save_instance
from rpbench.options import RunOptions
from rpbench.oracle.pairs import find_candidates
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.oracle.solve import oracle_model
from rpbench.results.store import check_new_folder
from rpbench.scenarios.base import Scenario
from rpbench.spec import RunSpec
from rpbench.strategies.base import RoundModel

#: A captured round: its number, time, model, the solver's objective and status.
_Captured = tuple[int, float, Model, float, str]


def take_snapshots(
    spec: RunSpec,
    out: str | Path,
    *,
    scenario: Scenario | None = None,
    rounds: list[int] | None = None,
    largest: int = 3,
) -> tuple[Path, list[dict]]:
    """Simulate each strategy of ``spec`` and save the chosen rounds' models under ``out`` (a new folder).

    ``scenario``: the one ``spec.request`` builds, when built already.  Each offline run adds its pairing
    model (not solved: the full day's bound has millions of columns).
    """
    check_new_folder(out)
    preset = load_preset(spec.preset)
    scenario = scenario if scenario is not None else spec.request.build()
    entries: list[dict] = []
    done: dict = {}
    out = Path(out)
    with results.new_results_folder(out, out.name) as (tmp, final):
        for entry in spec.simulated:
            seen: list[_Captured] = []

            def capture(k: int, t: float, rm: RoundModel, solution: Solution, seen: list[_Captured] = seen) -> None:
                if rounds is None or k in rounds:
                    seen.append((k, t, rm.model, solution.objective, solution.status.value))

            entry = calibrated(entry, scenario, preset, done, progress=False)  # as in a comparison
            simulate_strategy(scenario, entry, preset, progress=False, capture=capture, strict=spec.strict)
            picked = seen if rounds is not None else sorted(seen, key=lambda s: (-s[2].n_cols, s[0]))[:largest]
            for k, t, model, objective, status in sorted(picked, key=lambda s: s[0]):
                stem = f"{scenario.name}_{entry.name}_round{k:05d}"
                meta = {
                    "scenario": scenario.label,
                    "scenario_name": scenario.name,
                    "seed": scenario.seed,
                    "strategy": entry.name,
                    "round": k,
                    "t_s": t,
                    "preset": preset.name,
                    "objective": objective,
                    "status": status,
                    "size": model.size,
                }
                save_instance(tmp / f"{stem}.npz", model, meta)
                entries.append({"file": f"{stem}.npz", **meta})
        for entry in spec.offline:
            stem = f"{scenario.name}_{entry.name}"
            model, meta = offline_model(scenario, entry.name, entry.options)
            save_instance(tmp / f"{stem}.npz", model, meta)
            entries.append({"file": f"{stem}.npz", **meta})
        results.write_json(
            tmp / "manifest.json", {"format": "rpbench-instance-1", "instances": entries, **results.environment()}
        )
    return final, entries


def offline_model(scenario: Scenario, run: str, options: RunOptions) -> tuple[Model, dict]:
    """The pairing model offline run ``run`` solves on ``scenario``, and its provenance (objective null)."""
    spec = ORACLE_RUNS[run]
    candidates = find_candidates(scenario.network.distances(), scenario.orders, spec.rules(scenario.params, options))
    model = oracle_model(candidates, spec.variant)[0].renamed(run)
    return model, {
        "scenario": scenario.label,
        "scenario_name": scenario.name,
        "seed": scenario.seed,
        "strategy": run,
        "objective": None,
        "size": model.size,
        "rules": dataclasses.asdict(candidates.rules),
    }
