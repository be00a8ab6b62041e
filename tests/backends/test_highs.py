"""The HiGHS adapter's kept instance (rpbench.backends.highs.kept_instance): reuse must not change answers."""

from __future__ import annotations

import os

import numpy as np
import pytest

from rpbench.backends import SolveOptions, get_backend
from rpbench.backends.highs import highs_settings, kept_instance
from rpbench.bench import synthetic
from rpbench.exceptions import SolverError


def _models():
    return [
        synthetic.assignment(20, 15, seed=1),
        synthetic.trip_packing(12, 6, seed=2),
        synthetic.assignment(8, 30, seed=3),
        synthetic.trip_packing(10, 10, seed=4),
    ]


def test_a_kept_instance_answers_as_a_fresh_one(monkeypatch):
    # Solve a mix of LPs and MIPs on the kept instance, then each on a new instance: the same columns.
    from rpbench.backends import highs

    backend, options = get_backend("highs"), SolveOptions(threads=1)
    kept = [backend.solve(m, options).chosen for m in _models()]
    fresh = []
    for m in _models():
        monkeypatch.setattr(highs, "_kept", highs._Kept())
        fresh.append(backend.solve(m, options).chosen)
    assert all(np.array_equal(a, b) for a, b in zip(kept, fresh, strict=True))


def test_options_of_a_previous_solve_do_not_leak():
    lp = highs_settings(SolveOptions(), None, relax=True)
    h = kept_instance(lp)
    assert h.getOptionValue("presolve")[1] == "off"
    h = kept_instance(highs_settings(SolveOptions(), None, relax=False))
    assert h.getOptionValue("presolve")[1] == "choose"  # HiGHS's default again


def test_a_rejected_option_is_an_error_and_the_next_solve_starts_clean():
    with pytest.raises(SolverError, match="rejected option"):
        kept_instance({"output_flag": False, "no_such_option": 1})
    h = kept_instance({"output_flag": False})
    assert h.getNumCol() == 0


class _Alarm(Exception):
    pass


def test_a_signal_handler_ends_a_long_solve_and_the_interrupted_instance_is_dropped():
    """HiGHS calls into Python at its interrupt checks, so a handler's exception ends ``run()`` mid-solve."""
    import signal

    from rpbench.backends import highs

    backend = get_backend("highs")
    backend.solve(synthetic.pairing(20, seed=1), SolveOptions())
    h = highs._kept.highs["solve"]

    def alarm(signum, frame):
        raise _Alarm

    sent: list[bool] = []

    def signal_mid_solve(event):  # the signal arrives while run() is solving, at its first check
        if not sent:
            sent.append(True)
            os.kill(os.getpid(), signal.SIGALRM)

    for event in (h.cbSimplexInterrupt, h.cbIpmInterrupt, h.cbMipInterrupt):
        event.subscribe(signal_mid_solve)
    previous = signal.signal(signal.SIGALRM, alarm)
    try:
        with pytest.raises(_Alarm):
            backend.solve(synthetic.pairing(1000, seed=1), SolveOptions())  # a MIP of about a second
    finally:
        signal.signal(signal.SIGALRM, previous)
    assert sent
    assert h.getModelStatus().name != "kOptimal"  # stopped inside run(), not after it
    assert highs._kept.highs.get("solve") is not h  # its state after the exception is not trusted
    model = synthetic.pairing(40, seed=2)
    want = get_backend("matching").solve(model, SolveOptions()).objective
    assert backend.solve(model, SolveOptions()).objective == want


def test_a_kept_instance_gives_every_solve_its_whole_time_limit():
    """HiGHS measures time_limit against its instance's run time summed over all runs; the kept instance of
    the highs backend moves the limit on, so solves after the first ``time_limit`` seconds still run."""
    import dataclasses

    from rpbench.backends import highs, load_preset, solve

    preset = load_preset("highs")
    preset = dataclasses.replace(preset, options=dataclasses.replace(preset.options, time_limit_s=0.5))
    model = synthetic.assignment(400, 1500, seed=1)  # about 0.1 s a solve
    first = solve(model, preset)
    assert first.status.value == "optimal"
    h = highs._kept.highs["solve"]
    while h.getRunTime() < 1.5:  # three limits' worth of solving on the one instance
        assert solve(model, preset).objective == first.objective
    # a MIP on the same instance still stops at its own limit (HiGHS's MIP solver times each run itself)
    hard = synthetic.pairing(300, seed=1, objective="cardinality_then_weight")  # about 0.5 s with no limit
    short = dataclasses.replace(preset, options=dataclasses.replace(preset.options, time_limit_s=0.02))
    assert solve(hard, short).status.value == "time_limit"
