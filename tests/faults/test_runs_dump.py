"""The failed-round dump: a private, unpredictable file in the cache, never a planted link in /tmp.

A round the solver fails on is saved for ``rpbench bench``; the file used to
be ``/tmp/rpbench-failed-<strategy>-roundNNNNN.npz``, a name anyone could
plant a symbolic link at (the run then overwrote the link's target) and
that concurrent runs clobbered.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
from pathlib import Path

import pytest
from helpers import line_network, scenario_of

from faults.test_runs_helpers import TOY, assert_nothing_written, assert_one_error, run_cli
from rpbench.backends import load_preset
from rpbench.backends.highs import HighsBackend
from rpbench.exceptions import SolverError
from rpbench.harness.comparison import simulate_strategy
from rpbench.model.instances import load_instance


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("RPBENCH_CACHE", str(folder))
    return folder


@pytest.fixture
def broken_highs(monkeypatch):
    def broken(self, model, options, **kw):
        raise SolverError("HiGHS failed with model status kUnknown")

    monkeypatch.setattr(HighsBackend, "solve", broken)


def fail_a_round(strategy: str = "mb") -> str:
    """Simulate ``strategy`` with the broken solver; return the error message."""
    sc = scenario_of(line_network(6), [(0.0, 0, 3), (10.0, 1, 5)], vehicles=[0])
    with pytest.raises(SolverError) as info:
        simulate_strategy(sc, strategy, load_preset("highs"), progress=False)
    return str(info.value)


def saved_as(message: str) -> Path:
    return Path(re.search(r"saved as (\S+) \(reproduce", message).group(1))


def test_a_link_planted_at_the_old_predictable_name_is_untouched(cache, broken_highs, tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    planted = Path(tempfile.gettempdir()) / "rpbench-failed-mb-round00000.npz"
    if os.path.lexists(planted):
        pytest.skip(f"{planted} exists already on this machine")
    planted.symlink_to(victim)
    try:
        dump = saved_as(fail_a_round())
        assert planted.is_symlink() and os.readlink(planted) == str(victim)
        assert victim.read_text() == "precious\n"
        assert dump.parent == cache / "failed-rounds"
    finally:
        planted.unlink()


def test_the_dump_is_a_private_regular_file_that_rpbench_bench_reads(cache, broken_highs):
    dump = saved_as(fail_a_round())
    st = os.lstat(dump)
    assert stat.S_ISREG(st.st_mode)
    assert stat.S_IMODE(os.stat(dump.parent).st_mode) == 0o700
    model, meta = load_instance(dump)
    assert meta["strategy"] == "mb" and meta["round"] == 0 and model.n_cols > 0


def test_two_failures_of_the_same_round_never_clobber_each_other(cache, broken_highs):
    first, second = saved_as(fail_a_round()), saved_as(fail_a_round())
    assert first != second and first.is_file() and second.is_file()


def test_a_link_planted_as_the_dump_folder_is_not_followed(cache, broken_highs, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    cache.mkdir()
    (cache / "failed-rounds").symlink_to(elsewhere)
    message = fail_a_round()
    assert "saved as" not in message and "HiGHS failed" in message
    assert list(elsewhere.iterdir()) == []


def test_no_room_for_the_dump_still_gives_the_solver_error(cache, broken_highs):
    cache.mkdir()
    (cache / "failed-rounds").write_text("a file in the way\n")
    message = fail_a_round()
    assert message.startswith("mb round 0 (t=0 s): solver preset 'highs': HiGHS failed") and "saved as" not in message


def test_a_plug_in_name_makes_a_safe_file_name(cache, broken_highs, monkeypatch):
    from rpbench.sim.simulator import _new_dump_file

    path = _new_dump_file("mypkg.rules:Greedy/../x-round00003")
    assert path.parent == cache / "failed-rounds" and "/" not in path.name and ":" not in path.name


def test_a_failed_round_on_the_command_line_is_one_line_and_writes_nothing(capsys, cache, broken_highs, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = run_cli(capsys, "run", *TOY, "--strategies", "mb", "--out", out)
    line = assert_one_error(code, err, "mb round", "HiGHS failed", "rpbench bench")
    assert saved_as(line).is_file() and stdout == ""
    assert_nothing_written(tmp_path, out)
