"""Helpers of the checker's tests (no test here): build a clean folder, tamper with a copy, read the outcome.

Each test builds its clean folders once per module (the fixtures of ``conftest.py``), then tampers with a copy
per case and asserts the exact outcome: a named check failing with a given message fragment, or ``rpbench
check`` exiting 2 with one error line.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
from helpers import write_fake_haikou as _write_fake_haikou

from rpbench.check import check_folder, check_tree
from rpbench.cli import main
from rpbench.harness.comparison import run_comparison
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

#: The clean folder every tampering starts from: each kind of run rpbench writes.
RUNS = ["mb", "rtv", "fl", "bound", "oracle1", "oracle2"]


def build(out: Path, runs=RUNS, *, sample: float = 0.25, seed: int = 3, run_options=None, **overrides) -> Path:
    request = ScenarioRequest("toy", sample=sample, seed=seed, params=tuple(overrides.items()))
    spec = RunSpec.of(request, list(runs), options=run_options, oracle_preset="matching")
    folder = run_comparison(spec, out, progress=False).folder
    return folder


def copy(source: Path, tmp_path: Path, name: str = "copy") -> Path:
    target = tmp_path / name
    shutil.copytree(source, target)
    return target


# ------------------------------------------------------------------- tampering
def edit_csv(path: Path, fn) -> None:
    table = pd.read_csv(path)
    out = fn(table)
    (table if out is None else out).to_csv(path, index=False)


def edit_npz(path: Path, fn) -> None:
    arrays = dict(np.load(path))
    fn(arrays)
    np.savez_compressed(path, **arrays)


def edit_meta(folder: Path, fn) -> None:
    meta = json.loads((folder / "meta.json").read_text())
    fn(meta)
    (folder / "meta.json").write_text(json.dumps(meta))


def set_kpi(folder: Path, run: str, kpi: str, fn) -> None:
    """Replace a reported KPI value by ``fn(value)`` (the column becomes text where fn returns text)."""

    def edit(table):
        table["value"] = table["value"].astype(object)
        sel = (table["run"] == run) & (table["kpi"] == kpi)
        assert sel.sum() == 1, (run, kpi)
        table.loc[sel, "value"] = fn(table.loc[sel, "value"].iloc[0])

    edit_csv(folder / "kpis.csv", edit)


def events(folder: Path, run: str) -> pd.DataFrame:
    return pd.read_csv(folder / "runs" / run / "events.csv.gz")


def edit_events(folder: Path, run: str, fn) -> None:
    edit_csv(folder / "runs" / run / "events.csv.gz", fn)


def first_row(table: pd.DataFrame, **where) -> int:
    sel = np.ones(len(table), dtype=bool)
    for column, value in where.items():
        sel &= (table[column] == value).to_numpy() if not callable(value) else value(table[column]).to_numpy()
    return int(table.index[sel][0])


def joined_pair(folder: Path, run: str = "mb") -> tuple[int, int, pd.Series]:
    """(joining order, first order, its assign event) of a pair of the run."""
    ev = events(folder, run)
    row = ev.loc[first_row(ev, event="assign", partner=lambda c: c >= 0)]
    return int(row["order"]), int(row["partner"]), row


def truncate(path: Path, keep: float = 0.5) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])


# -------------------------------------------------------------------- outcomes
def violations(folder: Path) -> dict[str, list[str]]:
    """Every failed check of the folder tree (runs and the folders' own checks), with its messages;
    an unreadable folder raises AssertionError."""
    out: dict[str, list[str]] = {}
    for result in check_tree(folder):
        assert result.error is None, result.error
        for rc in result.checks:
            for check, messages in rc.violations.items():
                out.setdefault(check, []).extend(f"{rc.run}: {m}" for m in messages)
    return out


def run_violations(folder: Path) -> dict[str, list[str]]:
    """Every failed check of :func:`check_folder`'s verdicts (the runs, the folder's own checks when they
    failed), with its messages as reported."""
    out: dict[str, list[str]] = {}
    for rc in check_folder(folder):
        for check, messages in rc.violations.items():
            out.setdefault(check, []).extend(messages)
    return out


def assert_fails(folder: Path, check: str, fragment: str, run: str | None = None) -> dict[str, list[str]]:
    """The check fails with a message containing ``fragment`` (for ``run`` when given)."""
    found = violations(folder)
    assert check in found, f"{check} did not fail; failures: {found}"
    prefix = f"{run}: " if run else ""
    assert any(m.startswith(prefix) and fragment in m for m in found[check]), found[check]
    return found


def assert_passes(folder: Path, capsys=None) -> list:
    results = check_tree(folder)
    bad = {
        r.folder: r.error or {c.run: c.violations for c in r.checks if not c.ok} for r in results if r.status != "ok"
    }
    assert not bad, bad
    if capsys is not None:
        capsys.readouterr()
        assert main(["check", str(folder)]) == 0
        out, err = capsys.readouterr()
        assert "Traceback" not in out + err and "FAILED" not in out
    return results


def cli(args: list[str], capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def assert_unreadable(folder: Path, fragment: str, capsys) -> str:
    """``rpbench check`` exits 2 with one error line naming the problem, no traceback, no verdict."""
    code, out, err = cli(["check", str(folder)], capsys)
    lines = [line for line in err.splitlines() if not line.startswith("rpbench: note:")]
    assert code == 2, (code, out, err)
    assert len(lines) == 1 and lines[0].startswith("rpbench: error: "), err
    assert fragment in lines[0], lines[0]
    assert "Traceback" not in out + err and out == ""
    return lines[0]


# ---------------------------------------------------------------- fake data
def write_fake_haikou(root: Path, days=("2017-05-01", "2017-05-02")) -> Path:
    """The shared fake Haikou folder (tests/helpers.py) with one order file per day: what a multi-day run
    needs."""
    return _write_fake_haikou(root, days, reservation=False)


def with_empty_hour(scenario):
    """The scenario with its second half of orders moved two hours later: hour 1 has no order at all."""
    o = scenario.orders
    late = np.arange(len(o.request_s)) >= len(o.request_s) // 2
    orders = dataclasses.replace(o, request_s=np.where(late, o.request_s + 7200.0, o.request_s))
    return dataclasses.replace(scenario, orders=orders, horizon_s=3 * 3600.0)
