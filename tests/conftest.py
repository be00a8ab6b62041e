"""Shared fixtures: the real data folder (tests skip without it) and a tiny fake one in its format."""

from __future__ import annotations

import gzip
import sys
from pathlib import Path

import numpy as np
import pytest

from rpbench.paths import find_data_dir

# Let test modules in sub-folders import tests/helpers.py as `helpers`.
sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The Haikou data folder; tests needing it are skipped when it is absent."""
    folder = find_data_dir()
    if folder is None:
        pytest.skip("Haikou data folder not found (set RPBENCH_DATA)")
    return folder


def write_gz(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with gzip.open(path, "wt") as fh:
        fh.write(text)


@pytest.fixture
def fake_data(tmp_path: Path) -> Path:
    """A tiny data folder in the Haikou format: a 3x3 two-way grid, one peak-hour order file,
    a month OD table and hourly counts.  Tests damage copies of it to provoke errors."""
    root = tmp_path / "haikou"
    (root / "network").mkdir(parents=True)
    nodes = ["node_id,name,x_coord,y_coord"]
    for i in range(9):
        r, c = divmod(i, 3)
        nodes.append(f"{i},,{110.3 + 0.005 * c:.6f},{20.0 + 0.005 * r:.6f}")
    (root / "network" / "node.csv").write_text("\n".join(nodes) + "\n")
    links = ["link_id,from_node_id,to_node_id,link_type,geometry,length"]
    k = 0
    for i in range(9):
        r, c = divmod(i, 3)
        for j in ([i + 1] if c < 2 else []) + ([i + 3] if r < 2 else []):
            links.append(f'{k},{i},{j},5,"LINESTRING (0 0, 1 1)",{600.0 + k:.1f}')
            k += 1
    write_gz(root / "network" / "link.csv.gz", "\n".join(links) + "\n")
    pre = "dwv_order_make_haikou_1."
    rows = [f",{pre}order_id,{pre}departure_time,O_location,D_location,OD_id,origin_id,destination_id"]
    rng = np.random.default_rng(1)
    for n in range(40):
        o, d = rng.choice(9, size=2, replace=False)
        rows.append(f"{n},{1000 + n},2017-05-01 08:{n:02d}:{(7 * n) % 60:02d},{o}.0,{d}.0,{n},{o},{d}")
    rows.append(f"40,2000,2017-05-03 08:20:00,1.0,2.0,40,1,2")          # reservation outside the hour: dropped
    write_gz(root / "demand_0800_0900" / "orders" / "2017-05-01.csv.gz", "\n".join(rows) + "\n")
    od = ["OD_id,origin_id,destination_id,lambda"] + [f"{i},{i % 9}.0,{(i + 4) % 9}.0,0.01" for i in range(9)]
    write_gz(root / "demand_0800_0900" / "month_5_OD.csv.gz", "\n".join(od) + "\n")
    hours = [10] * 24
    (root / "samples_and_aggregates").mkdir(parents=True)
    (root / "samples_and_aggregates" / "data_dayly_hourly_count.csv").write_text(
        f'date,day_count,hour_count\n05/01,{sum(hours)},"{hours}"\n')
    return root


@pytest.fixture
def two_day_data(fake_data: Path) -> Path:
    """The fake data folder with a second peak-hour day: the first day's orders moved to 2017-05-02."""
    folder = fake_data / "demand_0800_0900" / "orders"
    with gzip.open(folder / "2017-05-01.csv.gz", "rt") as fh:
        text = fh.read().replace("2017-05-01 08:", "2017-05-02 08:")
    write_gz(folder / "2017-05-02.csv.gz", text)
    return fake_data
