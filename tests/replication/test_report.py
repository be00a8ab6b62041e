"""The agreement criterion of ``rpbench replicate``: counted over the days with committed outputs, not evaluated
(never failed) where there is nothing to compare with."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from rpbench.cli import main
from rpbench.replication.reference import REFERENCE_FILE
from rpbench.replication.report import NO_REFERENCE, criterion, criterion_text, markdown, required_days


def authors_rows(strategy: str, days: dict[str, tuple[float | None, float]]) -> list[dict]:
    """One authors' run per day: ``{date: (committed pairing or None, our pairing)}``; the saving and the
    response follow the pairing (saving = 1000 x pairing km, response = pairing)."""
    rows = []
    for date, (committed, ours) in days.items():
        rows.append(
            {
                "engine": "authors",
                "strategy": strategy,
                "date": date,
                "pairing_ratio": ours,
                "total_saving_km": 1000 * ours,
                "response_rate": ours,
                "avg_detour_m": 500.0,
                "avg_shared_m": 2000.0,
                "committed_pairing_ratio": committed,
                "committed_total_saving_km": None if committed is None else 1000 * committed,
                "committed_response_rate": committed,
            }
        )
    return rows


def test_required_days_scale_10_of_14():
    assert [required_days(n) for n in (14, 7, 4, 1, 0)] == [10, 5, 3, 1, 0]


def test_the_criterion_counts_only_the_days_with_committed_outputs():
    # 4 days with outputs (3 within 15 %), 3 without: 3 of 4 needed, met.
    days = {f"2017-05-{d:02d}": (0.2, 0.2) for d in (1, 2, 3)}
    days["2017-05-04"] = (0.2, 0.5)
    days |= {f"2017-05-{d:02d}": (None, 0.3) for d in (15, 16, 17)}
    frame = pd.DataFrame(authors_rows("mb", days))
    assert criterion(frame) == {
        "mb": "met: 3 of 4 days within (at least 3 needed); no committed outputs for 2017-05-15, 2017-05-16, "
        "2017-05-17, not counted"
    }
    text = criterion_text(frame)
    assert "each on at least 3 of 4 days (the days with committed outputs; 10 of 14 in proportion)" in text
    assert "10 of 14 days" not in text


def test_fourteen_days_keep_the_papers_bar():
    days = {f"2017-05-{d:02d}": (0.2, 0.2 if d <= 9 else 0.5) for d in range(1, 15)}  # 9 of 14 within
    frame = pd.DataFrame(authors_rows("rtv", days))
    assert criterion(frame) == {"rtv": "not met: 9 of 14 days within (at least 10 needed)"}
    assert "each on at least 10 of 14 days (the days with committed outputs)." in criterion_text(frame)


def test_days_without_committed_outputs_are_not_evaluated():
    days = {f"2017-05-{d:02d}": (None, 0.3) for d in range(15, 22)}
    frame = pd.DataFrame(authors_rows("mb", days) + authors_rows("np", days))
    crit = criterion(frame)
    assert crit == {
        "mb": "not evaluated: no committed outputs for 7 days (2017-05-15 .. 2017-05-21)",
        "np": "not evaluated: no committed outputs for 7 days (2017-05-15 .. 2017-05-21)",
    }
    assert not any("0 of" in v for v in crit.values())
    assert criterion_text(frame).startswith("No committed outputs for 7 days (2017-05-15 .. 2017-05-21)")


def test_without_reference_outputs_nothing_is_compared():
    frame = pd.DataFrame(authors_rows("mb", {"2017-05-01": (None, 0.2)}))
    assert criterion(frame, reference=False) == {"mb": f"not evaluated: {NO_REFERENCE}"}
    text = markdown(frame, {}, reference=False)
    assert "No reference outputs to compare with" in text and "| date | strategy | pairing (committed)" not in text


# --------------------------------------------------------------------------- the command


def data_folder(tmp_path: Path, data_dir: Path, reference: pd.DataFrame | None) -> Path:
    """The data folder without the authors' outputs (as fetched), or with ``reference`` in their place."""
    folder = tmp_path / "haikou"
    folder.mkdir()
    for entry in data_dir.iterdir():
        if entry.name != REFERENCE_FILE.parts[0]:
            (folder / entry.name).symlink_to(entry)
    if reference is not None:
        (folder / REFERENCE_FILE).parent.mkdir()
        reference.to_csv(folder / REFERENCE_FILE, index=False)
    return folder


def replicate(capsys, data: Path, out: Path, date: str) -> tuple[dict, str]:
    argv = ["replicate", "--data", str(data), "--date", date, "--strategies", "mb", "--no-ablation", "--no-rpbench"]
    code = main([*argv, "--json", "--out", str(out)])
    stdout, _ = capsys.readouterr()
    assert code == 0
    return json.loads(stdout)["criterion"], (out / "report.md").read_text()


def test_replicate_on_a_data_folder_without_the_authors_outputs(capsys, data_dir, tmp_path):
    if not (data_dir / REFERENCE_FILE).is_file():
        pytest.skip(f"the data folder {data_dir} has no committed outputs to leave out")
    crit, report = replicate(capsys, data_folder(tmp_path, data_dir, None), tmp_path / "rep", "2017-05-01")
    assert crit == {"mb": "not evaluated: no reference outputs to compare with"}
    assert "No reference outputs to compare with" in report and "so the criterion is not evaluated" in report
    assert "0 of 1" not in report and "10 of 14 days" not in report


def test_replicate_on_a_day_without_committed_outputs(capsys, data_dir, tmp_path):
    if not (data_dir / REFERENCE_FILE).is_file():
        pytest.skip(f"the data folder {data_dir} has no committed outputs")
    committed = pd.read_csv(data_dir / REFERENCE_FILE)
    assert "2017-05-02" in set(committed["day"])
    data = data_folder(tmp_path, data_dir, committed[committed["day"] != "2017-05-02"])
    crit, report = replicate(capsys, data, tmp_path / "rep", "2017-05-02")
    assert crit == {"mb": "not evaluated: no committed outputs for 2017-05-02"}
    assert "No committed outputs for 2017-05-02: the criterion is not evaluated" in report and "0 of 1" not in report
