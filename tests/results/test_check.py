"""The independent checker: a clean run passes, and every kind of tampering is caught and named."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from rpbench.cli import main
from rpbench.exceptions import ResultsError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.spec import RunSpec
from rpbench.results.check import check_folder
from rpbench.scenarios import ScenarioRequest


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory):
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.25, seed=3), ["mb", "rtv", "oracle1"])
    folder, _ = run_comparison(spec, tmp_path_factory.mktemp("runs") / "clean", progress=False)
    return folder


@pytest.fixture
def run(clean_run, tmp_path):
    copy = tmp_path / "run"
    shutil.copytree(clean_run, copy)
    return copy


def violations(folder) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for rc in check_folder(folder):
        for check, messages in rc.violations.items():
            out.setdefault(check, []).extend(messages)
    return out


def edit_events(folder, run_name, fn):
    path = folder / "runs" / run_name / "events.csv.gz"
    events = pd.read_csv(path)
    fn(events).to_csv(path, index=False)


def test_clean_run_passes(clean_run, capsys):
    assert violations(clean_run) == {}
    assert main(["check", str(clean_run)]) == 0
    assert "mb: OK" in capsys.readouterr().out


def test_pickup_time_tampering_is_caught(run, capsys):
    def shift(ev):
        i = ev.index[ev["event"] == "pickup"][0]
        ev.loc[i, "t_s"] += 7.0
        return ev

    edit_events(run, "mb", shift)
    assert "service" in violations(run)
    assert main(["check", str(run)]) == 1
    assert "[service]" in capsys.readouterr().out


def test_double_assignment_is_caught(run):
    edit_events(run, "rtv", lambda ev: pd.concat([ev, ev[ev["event"] == "assign"].head(1)]))
    assert "assigned-once" in violations(run)


def test_reported_kpi_tampering_is_caught(run):
    kpis = pd.read_csv(run / "kpis.csv")
    kpis.loc[(kpis["run"] == "mb") & (kpis["kpi"] == "total_saving_km"), "value"] += 1.0
    kpis.to_csv(run / "kpis.csv", index=False)
    found = violations(run)
    assert any("total_saving_km" in m for m in found["kpi"])


def test_thresholds_are_rechecked(run):
    meta = json.loads((run / "meta.json").read_text())
    meta["params"]["max_detour_m"] = 100.0
    meta["params"]["max_pickup_m"] = 200.0
    (run / "meta.json").write_text(json.dumps(meta))
    found = violations(run)
    assert "max-detour" in found and "max-pickup" in found


def test_teleporting_vehicle_is_caught(run):
    path = run / "runs" / "mb" / "trajectories.npz"
    z = dict(np.load(path))
    z["t_s"][5:] -= 3.0  # arrive at node 5 three seconds too early
    np.savez_compressed(path, **z)
    assert "movement" in violations(run)


def test_assignment_after_patience_is_caught(run):
    orders = pd.read_csv(run / "orders.csv.gz")
    orders["patience_s"] = 0.5
    orders.to_csv(run / "orders.csv.gz", index=False)
    assert "within-patience" in violations(run)


def test_oracle_pair_tampering_is_caught(run):
    path = run / "runs" / "oracle1" / "pairs.csv.gz"
    pairs = pd.read_csv(path)
    pairs.loc[1, "first_id"] = pairs.loc[0, "first_id"]  # one order in two pairs
    pairs.to_csv(path, index=False)
    assert "oracle-pairs" in violations(run)


def test_not_a_results_folder(tmp_path):
    with pytest.raises(ResultsError, match="no meta.json"):
        check_folder(tmp_path)
    assert main(["check", str(tmp_path / "missing")]) == 2


def test_a_parent_folder_checks_every_run_folder_inside_and_fails_if_one_fails(clean_run, tmp_path, capsys):
    parent = tmp_path / "days"
    for day in ("d1", "d2"):
        shutil.copytree(clean_run, parent / day)
    assert main(["check", str(parent)]) == 0
    out = capsys.readouterr().out
    assert f"== {parent / 'd1'}" in out and f"== {parent / 'd2'}" in out
    edit_events(parent / "d2", "mb", lambda ev: ev[ev["event"] != "dropoff"])
    assert main(["check", str(parent)]) == 1
