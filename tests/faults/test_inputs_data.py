"""Bad data files: each damage of the fake Haikou folder (tests/conftest.py ``fake_data``) is one line and
exit status 2 from ``rpbench run ... --out OUT``, and OUT is never created.

Covers ids that do not fit an int64, damaged gzip streams, files or samples without orders, and absurd
values (link lengths, coordinates, hourly counts, OD rates, trace times).
"""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

from .test_inputs_helpers import PEAK, cli_error, cli_ok, edit_csv_cell, edit_gz, flip_byte, read_gz, truncate, write_gz

NODES = Path("network") / "node.csv"
LINKS = Path("network") / "link.csv.gz"
MONTH = Path("demand_0800_0900") / "month_5_OD.csv.gz"
HOURLY = Path("samples_and_aggregates") / "data_dayly_hourly_count.csv"
PRE = "dwv_order_make_haikou_1."


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


def run_fails(capsys, tmp_path: Path, data: Path, *extra: str, scenario: str = "haikou-peak") -> str:
    """``rpbench run`` on ``data``: one error line, and no results folder."""
    out = tmp_path / "results"
    line = cli_error(
        capsys,
        "run",
        "--scenario",
        scenario,
        "--data",
        data,
        "--strategies",
        "np",
        "--no-progress",
        "--out",
        out,
        *extra,
    )
    assert not out.exists()
    return line


def test_the_undamaged_fake_folder_runs(capsys, tmp_path, fake_data):
    cli_ok(
        capsys,
        "run",
        "--scenario",
        "haikou-peak",
        "--data",
        fake_data,
        "--strategies",
        "np",
        "--no-progress",
        "--out",
        tmp_path / "results",
        "--json",
    )
    assert (tmp_path / "results").is_dir()


# --------------------------------------------------------------------- integer ids
@pytest.mark.parametrize(
    "file, column, value, message",
    [
        (PEAK, PRE + "order_id", "99999999999999999999", "not an exact integer"),
        (PEAK, PRE + "order_id", "1e30", "not an exact integer"),
        (PEAK, PRE + "order_id", "18446744073709551615", "within the 64-bit range"),
        (PEAK, PRE + "order_id", "9223372036854775808", "within the 64-bit range"),
        (PEAK, PRE + "order_id", "1000.5", "not a whole number"),
        (PEAK, "origin_id", "1e30", "not an exact integer"),
        (NODES, "node_id", "99999999999999999999", "not an exact integer"),
        (LINKS, "to_node_id", "18446744073709551615", "within the 64-bit range"),
    ],
)
def test_id_that_does_not_fit_an_int64(capsys, tmp_path, fake_data, file, column, value, message):
    edit_csv_cell(fake_data / file, 3, column, value)
    line = run_fails(capsys, tmp_path, fake_data)
    assert message in line and repr(column) in line and str(fake_data / file) in line
    assert "not a node" not in line  # not the misleading message of a wrapped-around id


# ---------------------------------------------------------------------- gzip streams
def bad_deflate(path: Path) -> None:
    flip_byte(path, len(path.read_bytes()) // 2)  # a byte inside the deflate stream


def bad_crc(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[:-8] + bytes(8))  # CRC-32 and length trailer zeroed


@pytest.mark.parametrize(
    "damage",
    [truncate, bad_deflate, bad_crc, lambda p: p.write_text(read_gz(p))],  # plain text under a .gz name
    ids=["truncated", "deflate byte flipped", "crc trailer", "not gzipped"],
)
def test_damaged_gzip_stream(capsys, tmp_path, fake_data, damage):
    damage(fake_data / PEAK)
    line = run_fails(capsys, tmp_path, fake_data)
    assert "is not a valid gzip stream" in line and str(fake_data / PEAK) in line and "rpbench data fetch" in line


def test_empty_gzip_file(capsys, tmp_path, fake_data):
    (fake_data / LINKS).write_bytes(b"")
    line = run_fails(capsys, tmp_path, fake_data)
    assert "cannot be parsed as CSV" in line and str(fake_data / LINKS) in line


# -------------------------------------------------------------------- no orders at all
def test_header_only_orders_file(capsys, tmp_path, fake_data):
    edit_gz(fake_data / PEAK, lambda text: text.splitlines()[0] + "\n")
    line = run_fails(capsys, tmp_path, fake_data)
    assert line.startswith("no orders to simulate") and "holds no order" in line


def test_no_order_in_the_chosen_hour(capsys, tmp_path, fake_data):
    edit_gz(fake_data / PEAK, lambda text: text.replace("2017-05-01 08:", "2017-05-01 10:"))
    line = run_fails(capsys, tmp_path, fake_data)
    assert line.startswith("no orders to simulate") and "2017-05-01 08:00-09:00" in line


def test_sample_that_keeps_no_order(capsys, tmp_path, fake_data):
    line = run_fails(capsys, tmp_path, fake_data, "--sample", "0.001")
    assert line.startswith("no orders to simulate") and "--sample 0.001 keeps none of the 40 orders" in line


def test_toy_sample_that_keeps_no_order(capsys, tmp_path):
    out = tmp_path / "results"
    line = cli_error(capsys, "run", "--scenario", "toy", "--sample", "0.001", "--out", out)
    assert line.startswith("no orders to simulate") and not out.exists()


def test_day_without_orders(capsys, tmp_path, fake_data):
    (fake_data / HOURLY).write_text(f'date,day_count,hour_count\n05/01,0,"{[0] * 24}"\n')
    line = run_fails(capsys, tmp_path, fake_data, scenario="haikou-day")
    assert line.startswith("no orders to simulate") and "2017-05-01" in line


def test_day_sample_that_keeps_no_order(capsys, tmp_path, fake_data):
    line = run_fails(capsys, tmp_path, fake_data, "--sample", "0.001", scenario="haikou-day")
    assert "--sample 0.001 keeps none of the 240 orders" in line


# ------------------------------------------------------------------ absurd values
def test_duplicate_order_id(capsys, tmp_path, fake_data):
    edit_csv_cell(fake_data / PEAK, 5, PRE + "order_id", "1002")
    line = run_fails(capsys, tmp_path, fake_data)
    assert "order id 1002 appears more than once" in line


def test_absurd_link_length(capsys, tmp_path, fake_data):
    edit_csv_cell(fake_data / LINKS, 2, "length", "1e300")
    line = run_fails(capsys, tmp_path, fake_data)
    assert "length 1e+300 m exceeds 1e+06 m" in line


def test_coordinates_that_are_not_degrees(capsys, tmp_path, fake_data):
    edit_csv_cell(fake_data / NODES, 4, "x_coord", "12345678.9")  # metres where degrees belong
    line = run_fails(capsys, tmp_path, fake_data)
    assert "are not WGS84 degrees" in line and str(fake_data / NODES) in line


@pytest.mark.parametrize(
    "hours, total, message",
    [
        ([10] * 23 + [10**8], 10**8 + 230, "not plausible"),
        ([10] * 23 + [10**20], 230, "is not a list of 24 integers"),  # beyond int64
        ([10] * 23, 230, "must hold 24 non-negative integers"),
        ([10] * 24, 10**30, "not an exact integer"),
    ],
)
def test_absurd_hourly_counts(capsys, tmp_path, fake_data, hours, total, message):
    (fake_data / HOURLY).write_text(f'date,day_count,hour_count\n05/01,{total},"{hours}"\n')
    line = run_fails(capsys, tmp_path, fake_data, scenario="haikou-day")
    assert message in line


def test_absurd_od_rate(capsys, tmp_path, fake_data):
    edit_csv_cell(fake_data / MONTH, 2, "lambda", "1e300")
    line = run_fails(capsys, tmp_path, fake_data, scenario="haikou-day")
    assert "exceeds 10000" in line and str(fake_data / MONTH) in line


# -------------------------------------------------------------- the 2017-07-01 trace
@pytest.fixture
def trace_data(fake_data: Path) -> Path:
    """The fake folder plus a 4-vertex predecessor network (a two-way square) and a 6-order trace."""
    folder = fake_data / "predecessor_trb2021_network"
    folder.mkdir()
    square = [(0, 1), (1, 2), (2, 3), (3, 0)]
    write_gz(
        folder / "all_vertexes.csv.gz",
        "id,coor\n" + "".join(f'{i},"[{110.3 + 0.01 * (i % 2)}, {20.0 + 0.01 * (i // 2)}]"\n' for i in range(4)),
    )
    edges = [(a, b) for a, b in square] + [(b, a) for a, b in square]
    write_gz(
        folder / "all_edges.csv.gz",
        "id,length,head_ver,tail_ver\n" + "".join(f"{k},{900.0 + k},{a},{b}\n" for k, (a, b) in enumerate(edges)),
    )
    write_gz(
        folder / "SIMULATION_RESULTS_ALL_DIDI_CHUXING_HAIKOU_2017-07-01.csv.gz",
        "passenger_id,real_start_time,start_ver,end_ver\n"
        + "".join(f"{p},2017-07-01 0{p}:1{p}:00,{p % 4},{(p + 2) % 4}\n" for p in range(6)),
    )
    return fake_data


TRACE = Path("predecessor_trb2021_network") / "SIMULATION_RESULTS_ALL_DIDI_CHUXING_HAIKOU_2017-07-01.csv.gz"


def test_the_fake_trace_runs(capsys, tmp_path, trace_data):
    cli_ok(capsys, "scenario", "haikou-trace", "--data", trace_data, "--json")


@pytest.mark.parametrize("when", ["2017-07-05 08:00:00", "2016-07-01 08:00:00", "9999-12-31 23:59:00"])
def test_trace_order_outside_its_day(capsys, tmp_path, trace_data, when):
    edit_csv_cell(trace_data / TRACE, 2, "real_start_time", when)
    line = run_fails(capsys, tmp_path, trace_data, scenario="haikou-trace")
    assert "departs at" in line and "outside 2017-07-01" in line


def test_header_only_trace(capsys, tmp_path, trace_data):
    edit_gz(trace_data / TRACE, lambda text: text.splitlines()[0] + "\n")
    line = run_fails(capsys, tmp_path, trace_data, scenario="haikou-trace")
    assert line.startswith("no orders to simulate") and "trace" in line


def test_trace_vertex_beyond_int64(capsys, tmp_path, trace_data):
    with gzip.open(trace_data / TRACE, "rt") as fh:
        assert fh.readline().startswith("passenger_id")
    edit_csv_cell(trace_data / TRACE, 1, "start_ver", "1e30")
    line = run_fails(capsys, tmp_path, trace_data, scenario="haikou-trace")
    assert "not an exact integer" in line and "'start_ver'" in line
