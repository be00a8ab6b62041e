"""An evaluation is checked end to end: its recorded protocol, its units against it, its tables, its reports
and its published light copy.  Each case tampers with a copy of one small evaluation (two toy seeds, built
once) and, where the tampering would otherwise show, recomputes the parent's tables and reports with
rpbench's own functions, as a forger would: the check must still fail by name (exit status 1)."""

from __future__ import annotations

import base64
import json
import re
import shutil

import numpy as np
import pytest
from check.tamper import assert_fails, assert_passes, cli, copy, edit_csv, edit_meta, violations

from rpbench.check import check_tree
from rpbench.harness.comparison import run_comparison
from rpbench.harness.evaluate import run_evaluation
from rpbench.harness.publish import publish
from rpbench.protocols import load_protocol
from rpbench.report.comparison import write_report
from rpbench.report.evaluation import write_evaluation_report, write_evaluation_tables
from rpbench.report.html import write_html
from rpbench.results.digest import json_sha256, protocol_digest, recorded_spec
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

PROTOCOL = """
name = "tiny"
version = 1
description = "two toy seeds"
scenario = "toy"
sample = 0.1
seeds = [0, 1]
strategies = ["mb", "rtv", "bound"]
preset = "highs"
oracle_preset = "matching"
metrics = ["total_saving_km", "competitive_ratio_bound", "pairing_ratio"]
[bootstrap]
resamples = 100
"""
RUNS = ["mb", "rtv", "bound"]


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    path = tmp_path_factory.mktemp("protocol") / "tiny.toml"
    path.write_text(PROTOCOL)
    return run_evaluation(load_protocol(str(path)), tmp_path_factory.mktemp("eval") / "tiny", workers=1).folder


@pytest.fixture(scope="module")
def stranger(tmp_path_factory):
    """A unit of another experiment: the same runs and seed 1, another sample."""
    spec = RunSpec.of(ScenarioRequest("toy", sample=0.15, seed=1), RUNS, oracle_preset="matching", command="test")
    return run_comparison(spec, tmp_path_factory.mktemp("other") / "seed1", progress=False).folder


@pytest.fixture(scope="module")
def published(evaluated, tmp_path_factory):
    return publish(evaluated, tmp_path_factory.mktemp("pub") / "tiny-published")


@pytest.fixture
def ev(evaluated, tmp_path):
    return copy(evaluated, tmp_path, "ev")


@pytest.fixture
def pub(published, tmp_path):
    return copy(published, tmp_path, "pub")


def recompute(folder) -> None:
    """What a forger runs after an edit: the parent's tables, report.md, table.tex and page, by rpbench itself
    (the PNG figures, which the checker does not read, left as they are)."""
    write_evaluation_tables(folder)
    write_evaluation_report(folder, folder.name, figures=False)
    write_html(folder, folder.name)


def edit_protocol(folder, fn, *, rehash: bool = False) -> None:
    def edit(meta):
        fn(meta["protocol"])
        if rehash:
            meta["protocol"]["digest"] = protocol_digest(meta["protocol"])

    edit_meta(folder, edit)


def set_unit_kpi(unit, run: str, kpi: str, delta: float) -> None:
    def edit(table):
        sel = (table["run"] == run) & (table["kpi"] == kpi)
        table.loc[sel, "value"] = table.loc[sel, "value"] + delta

    edit_csv(unit / "kpis.csv", edit)


def exit_status(folder, capsys) -> int:
    return cli(["check", str(folder)], capsys)[0]


# ----------------------------------------------------------------------- the recorded protocol
def test_a_clean_evaluation_and_its_light_copy_pass(evaluated, published, capsys):
    (parent, *units) = assert_passes(evaluated, capsys)
    assert parent.folder_check.checked["protocol_units"] == 2 and parent.folder_check.checked["held_runs"] == 3
    (parent, *units) = assert_passes(published, capsys)
    assert [u.folder_check.checked["published_files"] for u in units] == [3, 3]
    assert all("runs" in u.folder_check.skipped for u in units)  # the event logs are not there, and it says so


@pytest.mark.parametrize(
    "field, edit",
    [
        ("seeds", lambda p: p.update(seeds=[0])),
        ("sample", lambda p: p.update(sample=0.2)),
        ("metrics", lambda p: p.update(metrics=["total_saving_km"])),
        ("bootstrap level", lambda p: p["bootstrap"].update(level=0.9)),
        ("digest zeroed", lambda p: p.update(digest="0" * 16)),
    ],
)
def test_an_edited_protocol_record_fails_its_digest(ev, field, edit, capsys):
    edit_protocol(ev, edit)
    recompute(ev)
    assert_fails(ev, "protocol", "does not hash to its digest")
    assert exit_status(ev, capsys) == 1


def test_seeds_rewritten_with_their_digest_are_caught_by_the_units(ev):
    edit_protocol(ev, lambda p: p.update(seeds=[0, 1, 2]), rehash=True)
    recompute(ev)
    assert_fails(ev, "protocol-units", "unit seed2 (seed 2) of protocol 'tiny' version 1 is not among the units")


def test_a_sample_rewritten_with_its_digest_is_caught_by_the_units(ev):
    edit_protocol(ev, lambda p: p.update(sample=0.2), rehash=True)
    recompute(ev)
    found = assert_fails(ev, "protocol-units", "seed0 records sample 0.1, the protocol gives it 0.2")
    assert "protocol" not in found


@pytest.mark.parametrize(
    "record, message",
    [
        (None, "meta.json records no protocol"),
        ("toy-quick", "meta.json's protocol is a str, not a record of its fields"),
        ({"name": "tiny"}, "meta.json's protocol is malformed: bootstrap is None"),
    ],
)
def test_a_missing_or_malformed_protocol_fails_by_name(ev, record, message, capsys):
    edit_meta(ev, lambda m: m.pop("protocol") if record is None else m.update(protocol=record))
    assert_fails(ev, "protocol", message)
    code, out, _ = cli(["check", str(ev)], capsys)
    assert code == 1 and "[protocol]" in out and "parent-tables] skipped" in out


def test_seeds_given_as_text_are_a_malformed_record(ev):
    edit_protocol(ev, lambda p: p.update(seeds="01"), rehash=True)
    assert_fails(ev, "protocol", "seeds is '01', not a non-empty list of distinct whole numbers")


# ----------------------------------------------------------------------- the units against the protocol
def test_a_unit_deleted_with_its_entry_fails(ev, capsys):
    shutil.rmtree(ev / "seed1")
    edit_meta(ev, lambda m: m.update(children=["seed0"]))
    recompute(ev)
    assert_fails(ev, "protocol-units", "unit seed1 (seed 1) of protocol 'tiny' version 1 is not among the units")
    assert exit_status(ev, capsys) == 1


def test_a_unit_of_another_sample_copied_in_fails(ev, stranger):
    """The stranger is a valid folder (its own checks pass); its record says it is not the protocol's."""
    shutil.rmtree(ev / "seed1")
    shutil.copytree(stranger, ev / "seed1")
    recompute(ev)
    found = assert_fails(ev, "protocol-units", "seed1 records sample 0.15, the protocol gives it 0.1")
    assert set(found) == {"protocol-units"}


def test_a_unit_added_with_its_entry_fails(ev, stranger):
    shutil.copytree(stranger, ev / "seed7")
    edit_meta(ev, lambda m: m.update(children=[*m["children"], "seed7"]))
    recompute(ev)
    assert_fails(ev, "protocol-units", "seed7 is not a unit of protocol 'tiny' version 1")


def test_a_unit_relabelled_as_the_protocols_keeps_its_parameters(ev, stranger):
    """The stranger's sample and seed relabelled in its meta.json: what it shares with no other unit remains."""
    shutil.rmtree(ev / "seed1")
    shutil.copytree(stranger, ev / "seed1")

    def relabel(meta):
        meta["scenario"]["args"]["sample"] = 0.1
        meta["params"]["max_detour_m"] = 3500.0  # and it ran under a relaxed rule, its digest rewritten
        meta["inputs_digest"]["params"] = json_sha256(meta["params"])

    edit_meta(ev / "seed1", relabel)
    recompute(ev)
    assert_fails(ev, "protocol-units", "seed1's parameters differ from seed0's")


def test_a_run_option_not_the_protocols_fails_even_with_its_digest(ev):
    def other_rule(meta):
        meta["runs"]["mb"]["options"]["order_rule"] = "min_then_check"
        meta["inputs_digest"]["runs"]["mb"] = json_sha256(recorded_spec(meta["runs"]["mb"]))

    edit_meta(ev / "seed0", other_rule)
    assert_fails(ev, "protocol-units", "seed0 run 'mb' ran with order_rule='min_then_check'")


def test_a_unit_solved_with_another_preset_fails(ev):
    edit_meta(ev / "seed1", lambda m: m["preset"].update(name="scipy"))
    edit_meta(ev / "seed1", lambda m: m["runs"]["bound"].update(solver="highs"))
    found = assert_fails(ev, "protocol-units", "seed1 was solved with preset 'scipy', the protocol's is 'highs'")
    assert any("offline run 'bound' with 'highs'" in m for m in found["protocol-units"])


# ----------------------------------------------------------------------- the reports
def test_a_leaderboard_mean_edited_in_the_report_fails(ev):
    text = (ev / "report.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| online 1 |"))
    edited = re.sub(r"\| [0-9.]+ \[", "| 999.9 [", row, count=1)
    (ev / "report.md").write_text(text.replace(row, edited))
    assert_fails(ev, "report", "report.md's table Rank | Strategy ...: row 1 shows online 1")


def test_the_reports_header_edited_fails(ev):
    text = (ev / "report.md").read_text()
    (ev / "report.md").write_text(text.replace("seeds 0, 1;", "seeds 0, 1, 2, 3;", 1))
    assert_fails(ev, "report", "report.md's header reads")


def test_a_mean_edited_in_table_tex_fails(ev):
    text = (ev / "table.tex").read_text()
    row = next(line for line in text.splitlines() if line.startswith("online 1 &"))
    (ev / "table.tex").write_text(text.replace(row, re.sub(r"& [0-9.]+ \[", "& 999.9 [", row, count=1)))
    assert_fails(ev, "report", "table.tex reads 'online 1")


def test_a_mean_edited_in_the_pages_figure_data_fails(ev):
    text = (ev / "report.html").read_text()
    found = re.search(r'"y":\{"dtype":"f8","bdata":"([^"]+)"', text)
    y = np.frombuffer(base64.b64decode(found.group(1)), dtype="f8").copy()
    y[0] += 5.0
    (ev / "report.html").write_text(text.replace(found.group(1), base64.b64encode(y.tobytes()).decode(), 1))
    assert_fails(ev, "report-html", "report.html's leaderboard figure, trace 'Total distance saving")


def test_a_cell_edited_in_the_pages_table_fails(ev):
    text = (ev / "report.html").read_text()
    cell = re.search(r'<td style="text-align:right">([0-9.]+) \[', text)
    (ev / "report.html").write_text(text.replace(cell.group(0), '<td style="text-align:right">999.9 [', 1))
    assert_fails(ev, "report-html", "report.html's table Rank | Strategy")


# ----------------------------------------------------------------------- the published light copy
def test_an_edited_published_units_table_fails(pub, capsys):
    edit_csv(pub / "units.csv", lambda t: t.assign(value=np.where(t["kpi"] == "pairs", t["value"] + 1, t["value"])))
    assert_fails(pub, "parent-tables", "units.csv: value of")
    assert exit_status(pub, capsys) == 1


def test_a_consistent_forgery_in_the_light_copy_is_caught_by_the_units_digest(pub, capsys):
    """A unit's KPI edited and every parent table and report recomputed from it by rpbench itself: the parent
    is consistent, the unit is not the one published."""
    set_unit_kpi(pub / "seed0", "mb", "total_saving_km", +5.0)
    write_report(pub / "seed0", "seed0", figures=False)  # the unit's own report too
    recompute(pub)
    found = assert_fails(pub, "light-copy", "kpis.csv is not the file published")
    assert set(found) == {"light-copy"}
    assert exit_status(pub, capsys) == 1


def test_a_consistent_forgery_in_the_full_folder_is_caught_by_the_units_event_log(ev):
    """The same forgery in the full folder, the unit's own report and page re-rendered too: its event log
    gives the saving."""
    set_unit_kpi(ev / "seed0", "mb", "total_saving_km", +5.0)
    write_report(ev / "seed0", "seed0")
    write_html(ev / "seed0", "seed0")
    recompute(ev)
    found = assert_fails(ev, "kpi", "KPI total_saving_km: reported", run="mb")
    assert set(found) == {"kpi"}


def test_a_light_copy_claiming_its_record_with_a_file_missing_fails(pub, capsys):
    (pub / "seed1" / "kpis.csv").unlink()
    assert_fails(pub, "light-copy", "kpis.csv is missing (the parent records the SHA-256 it was published with)")
    assert exit_status(pub, capsys) == 1


def test_an_edited_verdict_fails(pub):
    path = pub / "seed0" / "check.txt"
    path.write_text(path.read_text().replace("mb: OK", "mb: FAILED"))
    found = assert_fails(pub, "check-verdict", "check.txt is not the verdict of a full folder that passed")
    assert any("check.txt is not the file published" in m for m in found["light-copy"])


def test_a_light_copy_published_before_the_record_skips_the_digests_by_name(pub, capsys):
    edit_meta(pub, lambda m: m.pop("light_copy"))
    (parent, *units) = assert_passes(pub, capsys)
    assert all("published before rpbench recorded the digests" in u.folder_check.skipped["light-copy"] for u in units)


def test_a_malformed_light_copy_record_fails(pub):
    edit_meta(pub, lambda m: m["light_copy"].update(format=7))
    found = assert_fails(pub, "light-copy", "meta.json records a light copy of format 7, this rpbench reads 1")
    assert any("has no digests of seed0/" in m for m in found["light-copy"])


def test_a_unit_stripped_of_its_runs_among_full_ones_fails(ev):
    """A unit's event logs removed and a verdict written beside it, as if published: not in a full folder."""
    shutil.rmtree(ev / "seed1" / "runs")
    (ev / "seed1" / "check.txt").write_text((ev / "seed0" / "report.md").read_text())
    assert_fails(ev, "light-copy", "a light copy among full folders")


def test_publishing_refuses_a_light_copy_that_would_fail(evaluated, tmp_path, monkeypatch):
    """The copy is checked as a light copy before it is moved into place."""
    from rpbench.exceptions import ResultsError
    from rpbench.harness import publish as publishing

    monkeypatch.setattr(publishing, "light_copy_record", lambda light, children: {"format": 1, "children": {}})
    with pytest.raises(ResultsError, match="fails rpbench check"):
        publish(evaluated, tmp_path / "refused")
    assert not (tmp_path / "refused").exists()


def test_the_record_names_each_unit_and_what_it_keeps(published):
    record = json.loads((published / "meta.json").read_text())["light_copy"]
    assert record["format"] == 1 and sorted(record["children"]) == ["seed0", "seed1"]
    assert sorted(record["children"]["seed0"]) == ["check.txt", "kpis.csv", "meta.json"]
    assert all(r.status == "ok" for r in check_tree(published))
    assert "light-copy" not in violations(published)
