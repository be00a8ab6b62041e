"""``--figures``: reports write PNG only by default, SVG and PDF copies when asked for (``rpbench run``,
``sweep``, ``evaluate``, ``report``), and an unknown format is one error line, exit 2, nothing written."""

from __future__ import annotations

import pytest

from rpbench.check import check_tree
from rpbench.cli import main
from rpbench.exceptions import ParameterError
from rpbench.spec import FIGURE_FORMATS, RunSpec, figure_formats

RUN = ["run", "--scenario", "toy", "--sample", "0.1", "--seed", "3", "--strategies", "mb,bound", "--no-progress"]


def figures_in(folder) -> dict[str, list[str]]:
    """The figure files of a folder, by suffix."""
    found: dict[str, list[str]] = {}
    for path in sorted(folder.iterdir()):
        if path.suffix.lstrip(".") in FIGURE_FORMATS:
            found.setdefault(path.suffix.lstrip("."), []).append(path.stem)
    return found


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("figures") / "default"
    assert main([*RUN, "--out", str(folder)]) == 0
    return folder


def test_the_formats_are_checked_and_png_is_always_among_them():
    assert figure_formats("png") == ("png",)
    assert figure_formats("pdf, SVG") == ("png", "svg", "pdf")  # in their order, PNG first
    assert figure_formats(["svg"]) == ("png", "svg")
    assert RunSpec.of("toy", ["mb"]).formats == ("png",)
    assert RunSpec.of("toy", ["mb"], formats=("pdf",)).formats == ("png", "pdf")
    for bad in ("png,jpg", "", " , "):
        with pytest.raises(ParameterError, match="--figures"):
            figure_formats(bad)
    with pytest.raises(ParameterError, match="unknown figure format 'eps'"):
        RunSpec.of("toy", ["mb"], formats=("eps",))


def test_a_run_writes_png_only_by_default(default_run):
    assert figures_in(default_run) == {"png": ["kpis", "timeline"]}
    assert (
        "Figures are PNG; SVG and PDF copies are written beside them on request"
        in (default_run / "report.md").read_text()
    )
    assert all(r.status == "ok" for r in check_tree(default_run))


def test_a_run_writes_the_vector_copies_asked_for(tmp_path):
    folder = tmp_path / "vector"
    assert main([*RUN, "--out", str(folder), "--figures", "png,svg,pdf"]) == 0
    assert figures_in(folder) == {f: ["kpis", "timeline"] for f in ("pdf", "png", "svg")}
    assert (folder / "kpis.svg").read_text().lstrip().startswith("<?xml")
    assert (folder / "kpis.pdf").read_bytes()[:5] == b"%PDF-"
    assert all(r.status == "ok" for r in check_tree(folder))


@pytest.mark.parametrize(
    "command",
    [
        RUN,
        ["sweep", "--over", "dt=10,30", "--scenario", "toy", "--sample", "0.1", "--strategies", "mb"],
        ["evaluate", "toy-quick"],
    ],
    ids=["run", "sweep", "evaluate"],
)
def test_an_unknown_format_is_one_line_and_nothing_is_written(tmp_path, capsys, command):
    out = tmp_path / "never"
    assert main([*command, "--out", str(out), "--figures", "png,jpg"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--figures 'png,jpg': unknown figure format 'jpg'" in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_report_adds_the_vector_figures_to_a_folder_later(default_run, tmp_path, capsys):
    folder = tmp_path / "later"
    assert main([*RUN, "--out", str(folder)]) == 0
    report = (folder / "report.md").read_text()
    tables = {name: (folder / name).read_bytes() for name in ("kpis.csv", "table.tex", "table.csv")}
    capsys.readouterr()
    assert main(["report", str(folder), "--figures", "svg,pdf"]) == 0
    assert figures_in(folder) == {f: ["kpis", "timeline"] for f in ("pdf", "png", "svg")}
    assert (folder / "report.md").read_text() == report  # the report reads the same, whatever the formats
    assert {name: (folder / name).read_bytes() for name in tables} == tables
    assert main(["report", str(folder)]) == 0  # PNG again: the vector copies stay
    assert set(figures_in(folder)) == {"pdf", "png", "svg"}
    assert all(r.status == "ok" for r in check_tree(folder))


def test_report_out_writes_the_vector_figures_beside_the_file(default_run, tmp_path, capsys):
    out = tmp_path / "out" / "summary.md"
    out.parent.mkdir()
    assert main(["report", str(default_run), "--out", str(out), "--figures", "svg"]) == 0
    names = {p.name for p in out.parent.iterdir()}
    assert {"summary-kpis.png", "summary-kpis.svg", "summary-timeline.svg"} <= names
    assert not any(name.endswith(".pdf") for name in names)
    assert figures_in(default_run) == {"png": ["kpis", "timeline"]}  # the folder is only read


def test_report_refuses_an_unknown_format_before_writing(default_run, tmp_path, capsys):
    before = {p.name: p.stat().st_mtime_ns for p in default_run.iterdir()}
    out = tmp_path / "summary.md"
    for extra in ([], ["--out", str(out)]):
        assert main(["report", str(default_run), "--figures", "svg,tiff", *extra]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "unknown figure format 'tiff'" in err
    assert {p.name: p.stat().st_mtime_ns for p in default_run.iterdir()} == before and not out.exists()
