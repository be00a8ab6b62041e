"""Progress on stderr: the structure build's and the fixed point's bars when stderr is a terminal, none
otherwise; the build's announcing line either way."""

from __future__ import annotations

import io
import sys

import pytest

import rpbench.predict.list_cache as list_cache
import rpbench.predict.prediction as prediction
from rpbench.predict import solve_prediction_model

from .conftest import make_instance


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def solve_fresh(cache, monkeypatch, stderr) -> str:
    monkeypatch.setenv("RPBENCH_CACHE", str(cache))
    monkeypatch.setattr(sys, "stderr", stderr)
    list_cache._RECENT.clear()
    inst = make_instance(seed=2, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    solve_prediction_model(inst.model())
    list_cache._RECENT.clear()
    return stderr.getvalue()


def test_a_terminal_shows_the_build_and_the_sweeps(tmp_path, monkeypatch):
    monkeypatch.setattr(prediction, "PROGRESS_DELAY_S", 0.0)  # the toy solve takes less than the delay
    err = solve_fresh(tmp_path / "cache", monkeypatch, Terminal())
    assert "building the seeker/taker prediction structure" in err
    assert "prediction structure:" in err and "OD" in err  # the build's bar
    assert "prediction fixed point" in err and "sweep" in err and "residual" in err


def test_not_a_terminal_gets_the_announcing_line_only(tmp_path, monkeypatch):
    monkeypatch.setattr(prediction, "PROGRESS_DELAY_S", 0.0)
    err = solve_fresh(tmp_path / "cache", monkeypatch, io.StringIO())
    assert err.count("\n") == 1 and err.startswith("rpbench: building the seeker/taker prediction structure")


def test_a_quick_solve_shows_no_bar_of_its_sweeps(tmp_path, monkeypatch):
    err = solve_fresh(tmp_path / "cache", monkeypatch, Terminal())
    assert "prediction fixed point" not in err


@pytest.mark.parametrize("cached", [False, True])
def test_a_progress_callback_gets_every_sweep_and_no_bar_is_shown(tmp_path, monkeypatch, cached):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(prediction, "PROGRESS_DELAY_S", 0.0)
    inst = make_instance(seed=2, size=6, n_od=40, max_pickup_m=3000, max_detour_m=3000)
    if cached:
        inst.model()  # the structure is built before stderr is a terminal
    monkeypatch.setattr(sys, "stderr", Terminal())
    seen: list[tuple[int, float]] = []
    result = solve_prediction_model(inst.model(), progress=lambda it, res: seen.append((it, res)))
    assert [it for it, _ in seen] == list(range(1, result.info["iterations"] + 1))
    assert seen[-1][1] == result.info["residual"]
    assert "prediction fixed point" not in sys.stderr.getvalue()
