"""``rpbench check`` of a ``rpbench bench --out`` folder: an honest folder passes; each claim edited after the
fact (an objective, a verdict, a known value, a summary figure, the profile, the report, a listed file) fails
the check that owns it by name; a folder that cannot be read is exit status 2."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest

from rpbench.check.bench import expected_verdict
from rpbench.check.tree import check_tree
from rpbench.cli import main
from rpbench.results.solu import Known, read_solu, write_solu

EXAMPLES = Path(__file__).resolve().parents[2] / "instances" / "examples"
FAST = ["--solver", "matching", "--solver", "highs", "--repeat", "2", "--no-isolate", "--no-progress"]


@pytest.fixture(scope="module")
def bench_folder(tmp_path_factory):
    """A bench of the committed toy rounds, judged against known optima: the objectives a first bench proved."""
    base = tmp_path_factory.mktemp("bench")
    paths = [str(p) for p in sorted(EXAMPLES.glob("toy_*.npz"))]
    assert main(["bench", *paths, *FAST, "--csv", str(base / "first.csv")]) == 0
    first = pd.read_csv(base / "first.csv")
    solu = base / "known.solu"
    write_solu(solu, {str(m): Known("opt", float(v)) for m, v in zip(first["model"], first["objective"], strict=True)})
    out = base / "report"
    assert main(["bench", *paths, "--solu", str(solu), *FAST, "--out", str(out)]) == 0
    return out


def copy(folder: Path, tmp_path: Path) -> Path:
    dest = tmp_path / "copy"
    shutil.copytree(folder, dest)
    return dest


def failed(folder: Path) -> dict[str, list[str]]:
    (result,) = check_tree(folder)
    assert result.error is None, result.error
    return {check: msgs for c in result.checks for check, msgs in c.violations.items()}


def test_an_honest_bench_folder_passes_every_check(bench_folder, capsys):
    assert (bench_folder / "known.solu").is_file()
    (result,) = check_tree(bench_folder)
    assert result.status == "ok"
    checked = {k: v for c in result.checks for k, v in c.checked.items()}
    assert checked["verdict"] == 3 and checked["known-values"] == 3 and checked["summary"] == 2
    assert checked["profile"] > 0 and checked["environment"] == 1
    assert main(["check", str(bench_folder)]) == 0
    assert "preset highs: OK (verdict 3)" in capsys.readouterr().out


def test_an_edited_objective_is_a_wrong_verdict_in_disguise(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    rows = pd.read_csv(folder / "results.csv")
    rows.loc[0, "objective"] += 1  # an answer other than the known optimum, still called optimal
    rows.to_csv(folder / "results.csv", index=False)
    (msg,) = failed(folder)["verdict"]
    assert rows.loc[0, "model"] in msg and "earns 'wrong'" in msg


def test_an_edited_known_value_fails_the_verdicts(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    known = read_solu(folder / "known.solu")
    name = sorted(known)[0]
    known[name] = Known("opt", known[name].value + 5)
    write_solu(folder / "known.solu", known)
    assert all(name in m for m in failed(folder)["verdict"])  # both presets' answers now contradict it


def test_a_known_value_of_an_instance_not_benchmarked_is_named(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    known = read_solu(folder / "known.solu")
    write_solu(folder / "known.solu", {**known, "ghost": Known("opt", 1.0)})
    assert "'ghost'" in failed(folder)["known-values"][0]


@pytest.mark.parametrize(
    ("column", "change", "owner"),
    [("solved", 1, "summary"), ("sgm_s", 1e-3, "summary"), ("sgm_ratio", 0.5, "summary")],
)
def test_an_edited_summary_figure_fails_summary(bench_folder, tmp_path, column, change, owner):
    folder = copy(bench_folder, tmp_path)
    summary = pd.read_csv(folder / "summary.csv")
    summary.loc[1, column] += change
    summary.to_csv(folder / "summary.csv", index=False)
    assert owner in failed(folder)


def test_a_faster_time_in_results_fails_the_summary_it_was_summed_into(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    rows = pd.read_csv(folder / "results.csv")
    rows.loc[0, "total_s"] /= 10
    rows.to_csv(folder / "results.csv", index=False)
    assert "shifted geometric mean" in " ".join(failed(folder)["summary"])


def test_an_edited_profile_and_report_fail_by_name(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    profile = pd.read_csv(folder / "profile.csv")
    profile.loc[0, "fraction"] = 0.123
    profile.to_csv(folder / "profile.csv", index=False)
    report = (folder / "report.md").read_text()
    (folder / "report.md").write_text(report.replace("| highs | 3 / 3 |", "| highs | 2 / 3 |"))
    found = failed(folder)
    assert "fraction 0.123" in found["profile"][0] and "highs solving 3 / 3" in found["report"][0]


def test_a_missing_listed_file_and_a_bare_environment_fail(bench_folder, tmp_path):
    folder = copy(bench_folder, tmp_path)
    (folder / "profile.svg").unlink()
    (folder / "environment.json").write_text("{}")
    found = failed(folder)
    assert "profile.svg" in found["manifest"][0] and "machine" in found["environment"][0]


@pytest.mark.parametrize("missing", ["results.csv", "known.solu", "summary.csv"])
def test_an_unreadable_bench_folder_is_exit_status_2(bench_folder, tmp_path, missing, capsys):
    folder = copy(bench_folder, tmp_path)
    (folder / missing).unlink()
    assert main(["check", str(folder)]) == 2
    (result,) = check_tree(folder)
    assert result.error is not None and missing in result.error


def test_expected_verdict_by_hand():
    t = pd.DataFrame(
        {
            "model": ["m", "m", "m", "n"],
            "preset": ["a", "b", "c", "a"],
            "status": ["optimal", "optimal", "time_limit", "optimal"],
            "objective": [10.0, 11.0, 12.0, 5.0],
            "recorded": [float("nan")] * 4,
        }
    )
    # two proven optima differ and nothing else is known: both are wrong; the stopped 12 exceeds both
    assert [expected_verdict(t, i, None) for i in range(3)] == ["wrong", "wrong", "wrong"]
    assert expected_verdict(t, 1, Known("opt", 11.0)) == "optimal"
    assert expected_verdict(t, 3, Known("best", 6.0)) == "wrong"  # a better solution is known
    assert expected_verdict(t, 3, Known("bound", 5.0)) == "optimal"
    assert expected_verdict(t, 3, Known("inf")) == "wrong"
