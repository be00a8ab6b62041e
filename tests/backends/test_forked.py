"""Forked children (rpbench.backends._forked): a stop signal arriving while a child is forked is not lost."""

from __future__ import annotations

import subprocess
import sys
import textwrap

#: A process that signals itself from inside a fork (an at-fork callback, where Python drops a handler's
#: exception) and reports where the signal's exception surfaced.
_SIGNAL_DURING_THE_FORK = textwrap.dedent(
    """
    import os, signal, sys, time
    from rpbench.backends._forked import start_forked

    class Stop(BaseException):
        pass

    def stop(signum, frame):
        raise Stop()

    def child_main():
        time.sleep(60)

    signal.signal(signal.{name}, stop)
    os.register_at_fork(after_in_parent=lambda: os.kill(os.getpid(), signal.{name}))
    try:
        child = start_forked(child_main, ())
    except Stop:
        os.register_at_fork(after_in_parent=lambda: None)
        print("stopped at the fork's end")
        sys.exit(0)
    print("the fork went on; child alive:", child.is_alive())
    child.kill()
    """
)


def _signalled_during_a_fork(name: str) -> subprocess.CompletedProcess:
    code = _SIGNAL_DURING_THE_FORK.format(name=name)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)


def test_a_sigterm_during_the_fork_is_raised_once_it_is_done():
    done = _signalled_during_a_fork("SIGTERM")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "stopped at the fork's end", done.stdout + done.stderr
    assert "Exception ignored" not in done.stderr


def test_a_ctrl_c_during_the_fork_is_raised_once_it_is_done():
    done = _signalled_during_a_fork("SIGINT")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "stopped at the fork's end", done.stdout + done.stderr
