"""``rpbench bench --out``: every file of the folder with what it must hold; the summary printed after the table;
the progress bar only on a terminal; the machine and versions beside ``--csv``; the HTML page's summary."""

from __future__ import annotations

import io
import json
import math
from pathlib import Path

import pandas as pd
import pytest

from rpbench.cli import main
from rpbench.model.instances import save_instance

EXAMPLES = Path(__file__).resolve().parents[2] / "instances" / "examples"
FAST = ["--solver", "matching", "--solver", "highs", "--repeat", "2", "--no-isolate"]


@pytest.fixture(scope="module")
def tiered(tmp_path_factory):
    """The committed toy rounds, copied with tiers S (two of them) and M (one)."""
    from rpbench.model.instances import load_instance

    folder = tmp_path_factory.mktemp("tiered")
    for path, tier in zip(sorted(EXAMPLES.glob("toy_*.npz")), ("S", "S", "M"), strict=True):
        model, meta = load_instance(path)
        save_instance(folder / path.name, model, {**meta, "tier": tier})
    return folder


def test_out_writes_every_file_and_the_summary(tiered, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["bench", str(tiered), *FAST, "--out", str(out)]) == 0
    stdout, err = capsys.readouterr()
    names = {p.name for p in out.iterdir()}
    assert {"results.csv", "summary.csv", "profile.csv", "profile.png", "profile.svg"} <= names
    assert {"environment.json", "report.md"} <= names and not list(tmp_path.glob(".*partial*"))

    rows = pd.read_csv(out / "results.csv")
    assert len(rows) == 6 and set(rows["verdict"]) == {"optimal"}
    assert dict(zip(rows["model"], rows["tier"], strict=False)) == {
        "toy_fl_round00056": "S",
        "toy_mb_round00025": "S",
        "toy_rtv_round00056": "M",
    }
    assert (rows["repeats"] == 2).all() and (rows["total_s"] == rows["total_s_min"]).all()
    assert (rows["total_s_min"] <= rows["total_s_median"]).all()
    assert (rows["total_s_median"] <= rows["total_s_max"]).all()
    assert (rows["time_limit_s"] == 300.0).all()

    summary = pd.read_csv(out / "summary.csv")
    assert summary[["tier", "preset"]].values.tolist() == [
        ["S", "highs"],
        ["S", "matching"],
        ["M", "highs"],
        ["M", "matching"],
        ["total", "highs"],
        ["total", "matching"],
    ]
    assert summary["solved"].tolist() == summary["instances"].tolist() == [2, 2, 1, 1, 3, 3]
    assert summary["shift_s"].tolist() == [0.01, 0.01, 0.1, 0.1, 0.01, 0.01]
    for _, g in summary.groupby("tier"):
        assert g["sgm_ratio"].min() == 1.0 and (g["sgm_ratio"] >= 1.0).all()

    profile = pd.read_csv(out / "profile.csv")
    last = profile.sort_values("tau").groupby("preset")["fraction"].last()
    assert last.tolist() == [1.0, 1.0]  # both solved every instance
    assert (profile.groupby("preset")["fraction"].apply(lambda f: f.is_monotonic_increasing)).all()

    env = json.loads((out / "environment.json").read_text())
    assert {"platform", "cpu_model", "logical_cores", "memory_gib"} <= set(env["machine"])
    assert {"highspy", "ortools", "pyomo", "cvxpy", "pymatching", "lap", "scipy", "networkx"} <= set(env["versions"])
    assert env["bench"]["presets"] == ["highs", "matching"] and env["bench"]["repeat"] == 2

    report = (out / "report.md").read_text()
    assert "## Per preset" in report and "| S | matching | 2 / 2 |" in report and "![performance profile]" in report
    assert f"highspy {env['versions']['highspy']}" in report and "toy_rtv_round00056" in report
    assert (out / "profile.png").read_bytes()[:4] == b"\x89PNG" and "<svg" in (out / "profile.svg").read_text()

    # the printed summary follows the per-instance table
    table_at, summary_at = stdout.index("verdict"), stdout.index("SGM ms")
    assert table_at < summary_at and "M        matching" in stdout
    assert f"wrote {out}" in err


def test_out_must_be_new_and_is_checked_before_any_solve(tmp_path, capsys, monkeypatch):
    (tmp_path / "taken").mkdir()
    monkeypatch.setattr("rpbench.commands.bench.run_benchmark", lambda *a, **k: pytest.fail("benchmarked"))
    assert main(["bench", str(EXAMPLES), *FAST, "--out", str(tmp_path / "taken")]) == 2
    assert "already exists" in capsys.readouterr().err


def _bench_tiny(extra=()):
    return main(["bench", "--synthetic", "--sizes", "tiny", "--structures", "assignment", *FAST, *extra])


def test_no_progress_lines_when_stderr_is_not_a_terminal(capsys):
    assert _bench_tiny() == 0
    err = capsys.readouterr().err
    assert err.splitlines() == ["building the 'tiny' synthetic models (seed 0) ..."]  # no line per solve, no bar


class _Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("extra, drawn", [((), True), (("--no-progress",), False)])
def test_a_bar_on_a_terminal_unless_no_progress(monkeypatch, capsys, extra, drawn):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert _bench_tiny(extra) == 0
    text = terminal.getvalue()
    assert ("bench" in text and "\r" in text) is drawn
    assert "assignment-5x12-s0\n" not in text  # never a line per solve


def test_csv_keeps_the_rows_and_puts_the_environment_beside_it(tmp_path):
    csv = tmp_path / "bench.csv"
    assert _bench_tiny(["--csv", str(csv)]) == 0
    rows = pd.read_csv(csv)
    assert {"verdict", "total_s_min", "total_s_median", "total_s_max", "tier"} <= set(rows.columns)
    assert not {"cpu_model", "highspy", "platform"} & set(rows.columns)  # the machine is not per row
    env = json.loads((tmp_path / "bench.environment.json").read_text())
    assert env["machine"]["logical_cores"] >= 1 and "highspy" in env["versions"]


def test_the_html_page_shows_the_verdict_summary(tmp_path):
    from rpbench.report.html.bench import write_bench_html

    rows = [
        ("m1", "a", "optimal", "optimal", 0.002),
        ("m1", "b", "optimal", "wrong", 0.001),  # fast, but wrong: not solved
        ("m2", "a", "optimal", "optimal", 0.004),
        ("m2", "b", "time_limit", "time_limit", 0.5),
    ]
    t = pd.DataFrame(rows, columns=["model", "preset", "status", "verdict", "total_s"])
    t = t.assign(structure="pairing", cols=10, objective=1.0, gap=0.0, message="", time_limit_s=0.5, tier="all")
    env = {"machine": {"platform": "TestOS", "cpu_model": "Test CPU", "logical_cores": 4}, "versions": {"lap": "9"}}
    page = write_bench_html(t, tmp_path / "b.html", "test", env=env).read_text()
    assert 'id="bench-summary"' in page and "SGM / best" in page and "Test CPU" in page and "lap 9" in page
    summary_html = page[page.index('id="bench-summary"') :].split("</table>")[0]
    best = math.sqrt(0.012 * 0.014) - 0.01  # a: shift 10 ms
    assert summary_html.count(">1.00<") == 1 and f">{0.5 / best:.2f}<" in summary_html  # b: at the 0.5 s limit
