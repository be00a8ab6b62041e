"""Several comparison folders of one scenario as one comparison: rpbench.report.combine and `rpbench report A B`.

The folders are real toy runs of one scenario (module-scoped: each takes a few seconds), one with the
upper bound, one under another solver preset, one with FL under another option, and one of another
seed; the other cases are copies of them with one fact changed.
"""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from rpbench.cli import main
from rpbench.exceptions import ResultsError
from rpbench.harness.comparison import run_comparison
from rpbench.harness.render import render
from rpbench.report.combine import combine
from rpbench.results import layout
from rpbench.results.metrics import TIMING_KPIS
from rpbench.results.ratios import DERIVED_KPIS
from rpbench.results.read import load_kpis
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

TOY = ScenarioRequest("toy", sample=0.1, seed=5)


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("combine")
    specs = {
        "one": RunSpec.of(TOY, ["mb", "bound"]),
        "two": RunSpec.of(TOY, ["mb", "fl"], preset="scipy"),
        "three": RunSpec.of(TOY, ["fl"], options={"fl": {"tau0_s": 60.0}}),
        "seed-6": RunSpec.of(ScenarioRequest("toy", sample=0.1, seed=6), ["mb"]),
    }
    return {name: run_comparison(spec, root / name, progress=False).folder for name, spec in specs.items()}


def light_copy(folder: Path, dest: Path) -> Path:
    """The folder's meta.json and tables only, as a published light copy keeps them."""
    dest.mkdir(parents=True)
    for name in (layout.META, layout.KPIS, layout.ROUNDS):
        shutil.copyfile(folder / name, dest / name)
    return dest


def edit_meta(folder: Path, edit) -> None:
    meta = json.loads((folder / layout.META).read_text())
    edit(meta)
    (folder / layout.META).write_text(json.dumps(meta))


def reported(folder: Path) -> pd.DataFrame:
    """kpis.csv as a KPI x run table, nothing recomputed."""
    return pd.read_csv(folder / layout.KPIS).pivot(index="kpi", columns="run", values="value")


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


# ------------------------------------------------------------------- one table
def test_two_folders_of_one_scenario_are_one_table_of_all_their_runs(runs):
    combined = combine([runs["one"], runs["two"]])
    assert list(combined.table.columns) == ["mb", "fl", "bound"]  # MB is one run: shown once; offline runs last
    for folder in (runs["one"], runs["two"]):
        own = reported(folder)
        for run in own.columns:
            kpis = [k for k in own.index if k not in DERIVED_KPIS and (run != "mb" or k not in TIMING_KPIS)]
            assert combined.table.loc[kpis, run].tolist() == pytest.approx(own.loc[kpis, run].tolist(), nan_ok=True)
    # a run shown once carries the first folder's timings (its clock), and the notes say so
    assert combined.table.loc["wall_s", "mb"] == reported(runs["one"]).loc["wall_s", "mb"]
    assert any("MB is the same run in `one` and `two`" in note for note in combined.notes)
    assert combined.styles["fl"] == ("FL", "tab:green")


def test_the_shared_bound_divides_the_other_folders_runs(runs):
    assert "competitive_ratio_bound" not in load_kpis(runs["two"]).index  # its own folder has no bound
    table = combine([runs["two"], runs["one"]]).table
    expected = table.loc["total_saving_km", "fl"] / reported(runs["one"]).loc["total_saving_km", "bound"]
    assert table.loc["competitive_ratio_bound", "fl"] == pytest.approx(expected)
    assert pd.isna(table.loc["competitive_ratio_bound", "bound"])  # the bound has no ratio of its own
    notes = combine([runs["one"], runs["two"]]).notes
    assert any("the runs of `two` are divided by Upper bound of `one`" in note for note in notes)


def test_the_best_known_schedule_is_the_best_run_of_every_folder(runs):
    """One instance: LB is the largest saving among every folder's simulated runs, and divides them all."""
    combined = combine([runs["one"], runs["two"], runs["three"]])
    table = combined.table
    savings = table.loc["total_saving_km", ["mb", "two/fl", "three/fl"]]
    best = savings.idxmax()
    assert table.loc["competitive_ratio_best_known", best] == 1.0
    for run in savings.index:
        assert table.loc["competitive_ratio_best_known", run] == pytest.approx(savings[run] / savings.max())
    assert table.loc["best_known_saving_km", "bound"] == pytest.approx(savings.max())
    assert table.loc["bound_over_best_known", "bound"] == pytest.approx(
        table.loc["total_saving_km", "bound"] / savings.max()
    )
    assert any("divided by the best known schedule over all the folders" in note for note in combined.notes)
    md, _ = render([runs["one"], runs["two"], runs["three"]])
    assert "OPT lies in [LB, U] = [" in md and "best known schedule: " in md


def test_a_run_name_of_two_distinct_runs_is_one_column_per_folder(runs):
    combined = combine([runs["two"], runs["three"]])  # FL with tau0_s 60 in `three`
    assert list(combined.table.columns) == ["mb", "two/fl", "three/fl"]
    assert combined.styles["two/fl"] == ("FL (two)", "tab:green")
    assert combined.styles["three/fl"] == ("FL (three)", "tab:green")  # the colour is carried over
    assert combined.table.loc["total_saving_km", "three/fl"] == reported(runs["three"]).loc["total_saving_km", "fl"]
    assert any("FL differs between `two` and `three`" in note for note in combined.notes)


def test_one_run_has_the_same_options_and_kpis_but_may_differ_in_timings(runs, tmp_path):
    clock = light_copy(runs["one"], tmp_path / "clock")
    kpis = pd.read_csv(clock / layout.KPIS)
    kpis.loc[kpis["kpi"].isin(["wall_s", "decision_p50_s"]), "value"] *= 3
    kpis.to_csv(clock / layout.KPIS, index=False)
    assert list(combine([runs["one"], clock]).table.columns) == ["mb", "bound"]
    other = light_copy(runs["one"], tmp_path / "other")
    kpis.loc[(kpis["run"] == "mb") & (kpis["kpi"] == "total_saving_km"), "value"] += 1.0
    kpis.to_csv(other / layout.KPIS, index=False)
    assert list(combine([runs["one"], other]).table.columns) == ["one/mb", "other/mb", "bound"]
    # the same KPIs under other options (or rules): another run that happened to score the same
    options = light_copy(runs["one"], tmp_path / "options")
    edit_meta(options, lambda m: m["inputs_digest"]["runs"].update(mb="0" * 64))
    assert list(combine([runs["one"], options]).table.columns) == ["one/mb", "options/mb", "bound"]


def test_two_distinct_bounds_leave_each_folder_its_own_ratios(runs, tmp_path):
    other = light_copy(runs["one"], tmp_path / "other")
    kpis = pd.read_csv(other / layout.KPIS)
    kpis.loc[(kpis["run"] == "bound") & (kpis["kpi"] == "total_saving_km"), "value"] *= 2
    kpis.to_csv(other / layout.KPIS, index=False)
    combined = combine([runs["two"], runs["one"], other])
    assert list(combined.table.columns) == ["mb", "fl", "one/bound", "other/bound"]
    ratio = combined.table.loc["competitive_ratio_bound"]
    assert ratio["mb"] == pytest.approx(load_kpis(runs["one"]).loc["competitive_ratio_bound", "mb"])
    assert pd.isna(ratio["fl"]) and pd.isna(ratio["other/bound"])
    assert any("Upper bound differs between the folders" in note for note in combined.notes)


def test_folders_of_one_name_are_named_by_their_paths(runs, tmp_path):
    a = light_copy(runs["two"], tmp_path / "a" / "run")
    b = light_copy(runs["three"], tmp_path / "b" / "run")
    combined = combine([a, b])
    assert combined.styles[f"{a}/fl"][0] == f"FL ({a})" and f"{b}/fl" in combined.table.columns


def test_differences_besides_the_instance_are_listed_once(runs):
    md, written = render([runs["one"], runs["two"], runs["three"]])
    assert written == []
    assert md.count("SYNTHETIC toy city") == 1  # the scenario's label, once
    assert "- Differences between the folders: preset highs (one, three) vs scipy (two)." in md
    assert "- In every folder: rpbench " in md and "preset" not in md.split("- In every folder:")[1].splitlines()[0]
    assert "| Metric | MB | FL (two) | FL (three) | Upper bound |" in md


# ------------------------------------------------------------- one instance only
def test_folders_of_different_seeds_do_not_combine(runs):
    with pytest.raises(ResultsError) as caught:
        combine([runs["one"], runs["seed-6"]])
    message = str(caught.value)
    assert message.startswith(f"cannot combine {str(runs['one'])!r} and {str(runs['seed-6'])!r}: their scenarios")
    assert "(seed 5 vs 6)" in message and "only folders of one scenario combine" in message
    assert "\n" not in message


def test_without_digests_the_scenario_description_decides(runs, tmp_path):
    a, b = light_copy(runs["one"], tmp_path / "a"), light_copy(runs["two"], tmp_path / "b")
    for folder in (a, b):
        edit_meta(folder, lambda m: m.pop("inputs_digest"))
    assert list(combine([a, b]).table.columns) == ["mb", "fl", "bound"]
    edit_meta(b, lambda m: m["params"].update(dt_s=30.0))
    with pytest.raises(ResultsError, match=r"their scenarios differ \(dt_s 10.0 vs 30.0\)"):
        combine([a, b])


def test_inputs_of_one_content_combine_and_of_another_are_named(runs, tmp_path):
    # light copies: the inputs are written byte for byte the same, so their digests agree
    assert list(combine([light_copy(runs["one"], tmp_path / "a"), light_copy(runs["two"], tmp_path / "b")]).table)
    # full folders whose orders differ in their gzip header only (another writing time): one content
    full = tmp_path / "full"
    shutil.copytree(runs["two"], full)
    text = gzip.decompress((full / layout.ORDERS).read_bytes())
    (full / layout.ORDERS).write_bytes(gzip.compress(text, mtime=12345))
    edit_meta(full, lambda m: m["inputs_digest"]["files"].update({layout.ORDERS: "0" * 64}))
    assert "fl" in combine([runs["one"], full]).table.columns
    # another content: the files are named, as nothing the scenario says differs
    (full / layout.ORDERS).write_bytes(gzip.compress(text.replace(b"\n1,", b"\n1,0"), mtime=0))
    with pytest.raises(ResultsError, match=r"their scenarios differ \(input files orders.csv.gz\)"):
        combine([runs["one"], full])
    light = light_copy(full, tmp_path / "light")
    with pytest.raises(ResultsError, match="a published light copy holds no inputs to compare: combine the full"):
        combine([runs["one"], light])


@pytest.mark.parametrize("kind, words", [("multi-day", "a multi-day"), ("sweep", "a sweep")])
def test_a_parent_folder_among_several_is_refused(runs, tmp_path, kind, words):
    parent = tmp_path / kind
    parent.mkdir()
    (parent / layout.META).write_text(json.dumps({"kind": kind, "scenario": "toy"}))
    with pytest.raises(ResultsError) as caught:
        render([runs["one"], parent])
    assert str(caught.value) == (f"{str(parent)!r} is {words} folder; only comparison folders combine: render it alone")


def test_a_folder_given_twice_is_refused(runs):
    with pytest.raises(ResultsError, match="is given twice"):
        combine([runs["one"], runs["one"]])


# ------------------------------------------------------------------------ the CLI
def test_the_cli_refuses_in_one_line_with_status_2(runs, capsys):
    before = snapshot(runs["one"])
    assert main(["report", str(runs["one"]), str(runs["seed-6"])]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and err.startswith("rpbench: error: cannot combine")
    assert main(["report", str(runs["one"]), str(runs["two"]), "--html"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--html renders one folder's page" in err
    assert snapshot(runs["one"]) == before


def test_the_cli_prints_the_combination_and_writes_nothing_in_the_folders(runs, capsys):
    before = {name: snapshot(runs[name]) for name in ("one", "two")}
    assert main(["report", str(runs["one"]), str(runs["two"])]) == 0
    assert "# rpbench combined comparison: SYNTHETIC toy city" in capsys.readouterr().out
    assert {name: snapshot(runs[name]) for name in ("one", "two")} == before


def test_out_writes_the_markdown_with_its_tables_and_figure_beside_it(runs, tmp_path, capsys):
    before = {name: snapshot(runs[name]) for name in ("one", "two")}
    out = tmp_path / "out" / "both.md"
    out.parent.mkdir()
    assert main(["report", str(runs["one"]), str(runs["two"]), "--out", str(out)]) == 0
    assert "report written to" in capsys.readouterr().out
    beside = ["both-kpis.png", "both-table.tex", "both-table.csv"]  # PNG only: vector copies on request
    assert sorted(p.name for p in out.parent.iterdir()) == sorted(["both.md", *beside])
    text = out.read_text()
    assert "![headline KPIs per run](both-kpis.png)" in text and "](both-table.tex)" in text
    table = pd.read_csv(out.parent / "both-table.csv", index_col="kpi")
    assert list(table.columns) == ["metric", "mb", "fl", "bound"]
    assert table.loc["total_saving_km", "fl"] == pytest.approx(reported(runs["two"]).loc["total_saving_km", "fl"])
    assert "competitive_ratio_bound" in table.index
    assert "FL" in (out.parent / "both-table.tex").read_text()
    assert {name: snapshot(runs[name]) for name in ("one", "two")} == before


def test_out_with_metrics_writes_those_rows(runs, tmp_path, capsys):
    out = tmp_path / "two.md"
    argv = ["report", str(runs["one"]), str(runs["two"]), "--metrics", "total_saving_km,competitive_ratio_bound"]
    assert main([*argv, "--out", str(out)]) == 0
    table = pd.read_csv(tmp_path / "two-table.csv", index_col="kpi")
    assert list(table.index) == ["total_saving_km", "competitive_ratio_bound"]
    assert "Response rate" not in out.read_text()
