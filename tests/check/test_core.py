"""The checker's verdicts: run and folder statuses, the exit status (unreadable wins over failed), the text
and JSON reports, and the tolerant comparison of reported values."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from check.tamper import cli, copy, edit_csv, truncate
from rpbench.check import (
    EXIT_FAILED,
    EXIT_OK,
    EXIT_UNREADABLE,
    FolderResult,
    RunCheck,
    exit_status,
    format_report,
)
from rpbench.check.core import as_number, same, show


# ------------------------------------------------------------------ verdicts
def test_a_run_fails_by_the_checks_it_breaks_and_skips_say_why():
    """A run is ok until a check fails, skipped while no check ran; skip reasons for one check are joined."""
    rc = RunCheck("mb")
    rc.skip("hourly", "no hourly.csv")
    rc.skip("hourly", "no report.md")
    assert rc.ok and rc.status == "skipped" and rc.skipped == {"hourly": "no hourly.csv; no report.md"}
    assert format_report([rc]).splitlines()[0] == "mb: SKIPPED (no check could be made)"
    rc.checked["orders"] = 3
    assert rc.status == "ok" and format_report([rc]).startswith("mb: OK (orders 3)")
    rc.fail("kpi", "KPI pairs: reported 3.0, recomputed 2")
    rc.fail("kpi", "KPI served: reported 9.0, recomputed 8")
    assert not rc.ok and rc.status == "failed" and len(rc.violations["kpi"]) == 2


def test_a_folder_is_unreadable_failed_or_ok_and_the_exit_status_follows():
    """Exit status 2 when some folder is unreadable, else 1 when some check failed, else 0."""
    ok = FolderResult("a", runs=[RunCheck("mb")], folder_check=RunCheck("(folder)"))
    failed = FolderResult("b", runs=[RunCheck("mb", violations={"kpi": ["wrong"]})])
    unreadable = FolderResult("c", error="results file 'c/kpis.csv' is missing")
    assert [r.status for r in (ok, failed, unreadable)] == ["ok", "failed", "unreadable"]
    assert [c.run for c in ok.checks] == ["(folder)", "mb"]
    assert exit_status([ok]) == EXIT_OK == 0
    assert exit_status([ok, failed]) == EXIT_FAILED == 1
    assert exit_status([failed, unreadable, ok]) == EXIT_UNREADABLE == 2


def test_the_text_report_shows_counts_the_first_three_messages_and_the_skipped_checks():
    """An ok run prints its counts; a failed one its violations (three messages at most); skips their reason."""
    good = RunCheck("mb", checked={"orders": 100, "served": 95}, skipped={"report": "the folder has no report.md"})
    bad = RunCheck("rtv", violations={"kpi": [f"message {i}" for i in range(5)]})
    assert format_report([good, bad]).splitlines() == [
        "mb: OK (orders 100, served 95)",
        "  [report] skipped: the folder has no report.md",
        "rtv: FAILED",
        "  [kpi] 5 violation(s): message 0",
        "  [kpi]   message 1",
        "  [kpi]   message 2",
    ]


def test_reported_values_compare_within_the_tolerance_and_print_plainly():
    """Two NaN (an undefined KPI reported empty) are equal; text is not a number; numbers print as floats."""
    assert same(float("nan"), float("nan")) and not same(float("nan"), 0.0) and not same(0.0, float("nan"))
    assert same(1000.0, 1000.0 + 1e-6) and not same(1000.0, 1000.001)
    assert as_number("lots") is None and as_number("2.5") == 2.5 and np.isnan(as_number(float("nan")))
    assert show(np.float64(1.5)) == "1.5" and show("lots") == "'lots'"


# ------------------------------------------------------- the command's output
def test_the_help_states_the_exit_statuses(capsys):
    """``rpbench check --help`` names the three exit statuses."""
    with pytest.raises(SystemExit):
        cli(["check", "--help"], capsys)
    text = capsys.readouterr().out
    assert (
        "0  every check passed" in text
        and "1  a check failed" in text
        and "2  bad usage, or a folder is unreadable" in text
    )


def test_json_output_keeps_its_structure_and_adds_the_status(base, tmp_path, capsys):
    """``--json`` reports per folder and run ok, status, violations, checked and skipped, and the exit status."""
    folder = copy(base, tmp_path)
    edit_csv(
        folder / "kpis.csv",
        lambda t: t.assign(value=np.where((t["run"] == "fl") & (t["kpi"] == "pairs"), 99.0, t["value"])),
    )
    code, out, _ = cli(["check", "--json", str(base), str(folder)], capsys)
    report = json.loads(out)
    assert code == 1 and report["ok"] is False and report["status"] == "failed" and report["exit_status"] == 1
    assert report["unreadable"] == {}
    clean, bad = report["folders"][str(base)], report["folders"][str(folder)]
    assert clean["mb"] == {**clean["mb"], "ok": True, "status": "ok", "violations": {}, "skipped": {}}
    assert bad["fl"]["status"] == "failed" and "KPI pairs: reported 99.0" in bad["fl"]["violations"]["kpi"][0]


def test_json_reports_the_unreadable_folder_and_still_checks_the_others(base, folder, capsys):
    """An unreadable folder is listed with its one-line reason; the other folders are still checked."""
    truncate(folder / "runs/mb/events.csv.gz")
    code, out, err = cli(["check", "--json", str(base), str(folder)], capsys)
    report = json.loads(out)
    assert code == 2 and report["status"] == "unreadable" and report["exit_status"] == 2 and not report["ok"]
    assert report["folders"][str(base)]["mb"]["status"] == "ok" and report["folders"][str(folder)] == {}
    assert "is corrupt" in report["unreadable"][str(folder)] and err.count("rpbench: error:") == 1


def test_unreadable_wins_over_failed_and_both_are_reported(base, folder, tmp_path, capsys):
    """With a failed and an unreadable folder the exit status is 2, and both are reported."""
    failing = tmp_path / "failing"
    shutil.copytree(base, failing)
    edit_csv(
        failing / "kpis.csv",
        lambda t: t.assign(value=np.where((t["run"] == "mb") & (t["kpi"] == "served"), 1.0, t["value"])),
    )
    (folder / "kpis.csv").unlink()
    code, out, err = cli(["check", str(failing), str(folder)], capsys)
    assert code == 2 and "[kpi]" in out and f"== {folder}" in out and "kpis.csv' is missing" in err
    assert "Traceback" not in out + err
    assert cli(["check", str(failing)], capsys)[0] == 1
