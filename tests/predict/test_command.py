"""``rpbench predict`` on the tiny fake data folder (and one real-data run when present)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from rpbench.cli import main


def run_json(capsys, *argv):
    code = main(["predict", *argv, "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out)


def test_predict_month_json_and_csv(fake_data, tmp_path, capsys):
    csv = tmp_path / "pred.csv"
    r = run_json(capsys, "--rates", "month", "--data", str(fake_data), "--out", str(csv), "--no-cache")
    for key in ("ods", "states", "candidate_pairs", "iterations", "residual", "converged", "clip_count", "time_s"):
        assert key in r
    assert r["ods"] == 9 and r["converged"] is True and r["csv"] == str(csv)
    table = pd.read_csv(csv)
    assert len(table) == 9 and {"matching_prob", "e_vacant", "e_seeker", "ride_distance"} <= set(table.columns)


def test_predict_day_default_csv_name_and_options(fake_data, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    r = run_json(
        capsys,
        "--rates",
        "day",
        "--date",
        "2017-05-01",
        "--data",
        str(fake_data),
        "--tau0",
        "60",
        "--param",
        "max_detour_m=1000",
        "--accel",
        "anderson",
        "--no-cache",
    )
    assert (tmp_path / "prediction-day-2017-05-01.csv").is_file()
    assert r["config"]["tau0_s"] == 60 and r["params"]["max_detour_m"] == 1000 and r["config"]["accel"] == "anderson"


def test_predict_validate_fcfs(fake_data, tmp_path, capsys):
    r = run_json(
        capsys,
        "--rates",
        "month",
        "--data",
        str(fake_data),
        "--out",
        str(tmp_path / "p.csv"),
        "--validate-fcfs",
        "--hours",
        "20",
        "--min-samples",
        "5",
    )
    f = r["fcfs"]
    assert f["hours"] == 20 and f["ods_compared"] >= 1 and "mape_pct" in f["pairing_prob"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--rates", "weekly"], "--rates 'weekly'"),
        (["--rates", "day", "--date", "2017-05-02"], "no peak-hour order file for 2017-05-02"),
        (["--rates", "month", "--date", "2017-05-01"], "--date only applies"),
        (["--rates", "month", "--param", "max_detour_m=-3"], "max_detour_m"),
        (["--rates", "month", "--tau0", "-1"], "--tau0 -1 is out of range"),
    ],
)
def test_bad_input_is_one_line_exit_2(fake_data, tmp_path, capsys, argv, message):
    code = main(["predict", "--data", str(fake_data), "--out", str(tmp_path / "x.csv"), *argv])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert message in err and len(err.strip().splitlines()) == 1


def test_negative_rate_table_is_rejected(fake_data, tmp_path, capsys):
    path = tmp_path / "od.csv"
    path.write_text("OD_id,origin_id,destination_id,lambda\n0,0,4,0.1\n1,1,5,-0.2\n")
    code = main(["predict", "--data", str(fake_data), "--rates", str(path), "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert code == 2 and "negative rate" in err and len(err.strip().splitlines()) == 1
