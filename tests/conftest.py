"""Shared fixtures: the real data folders (tests skip without them) and a tiny fake Haikou one in its format.

The tests never write into the user's cache: the session runs with ``$RPBENCH_CACHE`` pointed at a
temporary folder (removed at the end), inherited by the worker processes and subprocesses tests start;
and they never download: ``$RPBENCH_DATA_MIRROR`` (unless set) is a local port that refuses.
``RPBENCH_TEST_CACHE=DIR`` keeps one instead, so that repeated runs reuse its all-pairs tables and
prediction structures.
"""

from __future__ import annotations

import gzip
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

from rpbench.paths import find_data_dir, shared_data_candidates

# Let test modules in sub-folders import tests/helpers.py as `helpers`.
sys.path.insert(0, str(Path(__file__).parent))

from helpers import write_fake_haikou, write_gz

_SESSION_CACHE: str | None = None


def pytest_configure(config: pytest.Config) -> None:
    global _SESSION_CACHE
    # A test that lets rpbench fetch the data (a first run) reaches no real server: a mirror that refuses.
    os.environ.setdefault("RPBENCH_DATA_MIRROR", "http://127.0.0.1:9/")
    kept = os.environ.get("RPBENCH_TEST_CACHE")
    if kept:
        os.environ["RPBENCH_CACHE"] = kept
    else:
        _SESSION_CACHE = tempfile.mkdtemp(prefix="rpbench-test-cache-")
        os.environ["RPBENCH_CACHE"] = _SESSION_CACHE


def pytest_unconfigure(config: pytest.Config) -> None:
    if _SESSION_CACHE is not None:
        shutil.rmtree(_SESSION_CACHE, ignore_errors=True)


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The Haikou data folder; tests needing it are skipped when it is absent."""
    folder = find_data_dir()
    if folder is None:
        pytest.skip("Haikou data folder not found (set RPBENCH_DATA)")
    return folder


@pytest.fixture(scope="session")
def manhattan_data_dir() -> Path:
    """The Manhattan data folder, ``../shared/data/manhattan`` beside the current folder or the checkout; tests
    needing it (marked ``manhattan``) are skipped when it is absent.  Only those two places are looked at: no
    ``RPBENCH_*`` variable of the machine decides what the tests read."""
    for folder in shared_data_candidates("manhattan"):
        if folder.is_dir():
            return folder.resolve()
    pytest.skip("Manhattan data folder not found (../shared/data/manhattan beside the checkout)")


@pytest.fixture
def fake_data(tmp_path: Path) -> Path:
    """A tiny data folder in the Haikou format: a 3x3 two-way grid, one peak-hour order file,
    a month OD table and hourly counts.  Tests damage copies of it to provoke errors."""
    return write_fake_haikou(tmp_path / "haikou")


@pytest.fixture
def two_day_data(fake_data: Path) -> Path:
    """The fake data folder with a second peak-hour day: the first day's orders moved to 2017-05-02."""
    folder = fake_data / "demand_0800_0900" / "orders"
    with gzip.open(folder / "2017-05-01.csv.gz", "rt") as fh:
        text = fh.read().replace("2017-05-01 08:", "2017-05-02 08:")
    write_gz(folder / "2017-05-02.csv.gz", text)
    return fake_data
