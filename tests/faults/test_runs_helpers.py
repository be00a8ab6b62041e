"""Shared helpers of the fault-injection tests tests/faults/test_runs_*.py (this module holds no test).

The ``Unproven*`` backends are HiGHS answering every (or every other) model
correctly but without proving it, as a solver stopped by its time limit
does: a deterministic stand-in for a preset whose ``time_limit_s`` is too
small.  Presets name them as ``faults.test_runs_helpers:UnprovenHighs``
(``tests/`` is on ``sys.path``, see tests/conftest.py).
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rpbench.backends.highs import HighsBackend
from rpbench.cli import main
from rpbench.model import Status

#: The toy city with a tenth of its orders: each run takes well under a second.
TOY = ("--scenario", "toy", "--sample", "0.1")
TESTS = Path(__file__).resolve().parents[1]


class UnprovenHighs(HighsBackend):
    """Every answer right but unproven, status ``time_limit`` (no bound, no gap)."""

    name = "unproven-highs"

    def solve(self, model, options, **kw):
        solution = super().solve(model, options, **kw)
        return dataclasses.replace(solution, status=Status.TIME_LIMIT, bound=None, gap=None)


class HalfProvenHighs(HighsBackend):
    """Models with an odd number of columns end ``feasible`` (a gap left), the others ``optimal``."""

    name = "half-proven-highs"

    def solve(self, model, options, **kw):
        solution = super().solve(model, options, **kw)
        if model.n_cols % 2:
            return dataclasses.replace(solution, status=Status.FEASIBLE)
        return solution


def preset_file(folder: Path, backend_class: str, **options) -> str:
    """A solver preset TOML in ``folder`` for a backend class of this module; returns its path."""
    path = folder / f"{backend_class.lower()}.toml"
    lines = [f'backend = "faults.test_runs_helpers:{backend_class}"', "[options]"]
    lines += [f"{k} = {v!r}" for k, v in options.items()]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    """``rpbench ARGV`` in this process: (exit status, stdout, stderr)."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def error_lines(err: str) -> list[str]:
    """The lines of stderr that are not notes (the scenario label, "sweep ..." progress notes)."""
    return [line for line in err.splitlines() if line.startswith("rpbench: error:")]


def assert_one_error(code: int, err: str, *fragments: str) -> str:
    """Exit status 2 and exactly one ``rpbench: error:`` line (no traceback) holding every fragment."""
    assert code == 2, err
    assert "Traceback" not in err, err
    lines = error_lines(err)
    assert len(lines) == 1, err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def leftovers(folder: Path) -> list[str]:
    """Partial folders and staging/probe/temporary files anywhere below ``folder``."""
    marks = (".partial", ".rpbench-probe-")
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if any(m in p.name for m in marks))


def assert_nothing_written(folder: Path, *paths: Path) -> None:
    """None of ``paths`` exists (not even as a dangling link) and no partial is left below ``folder``."""
    for path in paths:
        assert not os.path.lexists(path), f"{path} was written"
    assert leftovers(folder) == []


def read_only_folder(folder: Path) -> Path:
    """``folder`` made read-only, or skip when chmod does not stop writes (root in CI)."""
    folder.mkdir(parents=True, exist_ok=True)
    folder.chmod(0o555)
    probe = folder / "probe"
    try:
        probe.mkdir()
    except PermissionError:
        return folder
    probe.rmdir()
    folder.chmod(0o755)
    pytest.skip("chmod does not stop writes here (running as root): no read-only folder to test with")


def rpbench_process(*argv, cwd: Path, env: dict | None = None) -> subprocess.Popen:
    """``rpbench ARGV`` as a child process (stdout/stderr piped)."""
    environ = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")]),
        **(env or {}),
    }
    return subprocess.Popen(
        [sys.executable, "-m", "rpbench.cli", *map(str, argv)],
        cwd=cwd,
        env=environ,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
