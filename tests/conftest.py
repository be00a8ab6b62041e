"""Shared fixtures: the real data folders (tests skip without them) and a tiny fake Haikou one in its format.

The tests never see the machine's settings, data or caches: the session starts with every ``RPBENCH_*``
and ``XDG_*`` variable removed, its own empty data home (``$RPBENCH_DATA_HOME``), cache (``$RPBENCH_CACHE``)
and XDG folders in a temporary folder (removed at the end), all inherited by the worker processes and
subprocesses tests start; and they never download: ``$RPBENCH_DATA_MIRROR`` is a local port that refuses.
So a test reads real data only from ``../shared/data/<city>`` beside the checkout, and passes the same
after ``rpbench data fetch`` filled the user's data folder.  ``RPBENCH_TEST_CACHE=DIR`` keeps one cache
instead, so that repeated runs reuse its all-pairs tables and prediction structures.
"""

from __future__ import annotations

import gzip
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

from rpbench.files.paths import find_data_dir, shared_data_candidates

# Let test modules in sub-folders import tests/helpers.py as `helpers`.
sys.path.insert(0, str(Path(__file__).parent))

from helpers import write_fake_haikou, write_gz

_SESSION_ROOT: str | None = None
#: The machine's variables the tests must not see: rpbench's own and the XDG folders platformdirs reads.
_MACHINE_PREFIXES = ("RPBENCH_", "XDG_")


def pytest_configure(config: pytest.Config) -> None:
    global _SESSION_ROOT
    kept = os.environ.get("RPBENCH_TEST_CACHE")
    for name in [n for n in os.environ if n.startswith(_MACHINE_PREFIXES)]:
        del os.environ[name]
    _SESSION_ROOT = tempfile.mkdtemp(prefix="rpbench-test-")
    root = Path(_SESSION_ROOT)
    os.environ["RPBENCH_CACHE"] = kept or str(root / "cache")
    os.environ["RPBENCH_DATA_HOME"] = str(root / "data-home")
    # A test that lets rpbench fetch the data (a first run) reaches no real server: a mirror that refuses.
    os.environ["RPBENCH_DATA_MIRROR"] = "http://127.0.0.1:9/"
    for xdg in ("XDG_DATA_HOME", "XDG_CACHE_HOME", "XDG_CONFIG_HOME", "XDG_STATE_HOME"):
        os.environ[xdg] = str(root / xdg.lower())


def pytest_unconfigure(config: pytest.Config) -> None:
    if _SESSION_ROOT is not None:
        shutil.rmtree(_SESSION_ROOT, ignore_errors=True)


@pytest.fixture(scope="session")
def data_dir() -> Path:
    """The Haikou data folder, ``../shared/data/haikou`` beside the current folder or the checkout; tests
    needing it (marked ``haikou``) are skipped when it is absent."""
    folder = find_data_dir()
    if folder is None:
        pytest.skip("Haikou data folder not found (../shared/data/haikou beside the checkout)")
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
