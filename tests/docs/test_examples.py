"""The documentation's examples run as written: every Python block of docs/getting-started.md and the
README's Python snippet, pasted into a fresh folder (as tests/env/test_examples.py runs docs/gym.md's).

They use the toy city, so they need no data folder; the session's isolated environment (tests/conftest.py)
is what their subprocesses inherit.  A block opening with a ``# NAME.py`` comment is a module the page asks
the reader to save: it is written to that file and imported by the blocks after it.  The page's shell
commands are parsed by rpbench's own argument parser, so a renamed or misspelt option fails here.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from rpbench.check import check_folder
from rpbench.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
GETTING_STARTED = ROOT / "docs" / "getting-started.md"
README = ROOT / "README.md"
FENCE_RE = re.compile(r"^```(?P<lang>\w*)\n(?P<code>.*?)^```", re.M | re.S)
#: A block that is a file to save: its first line names it.
FILE_RE = re.compile(r"#\s*(?P<name>[\w.-]+\.py)\s*$")


def blocks(path: Path, lang: str) -> list[str]:
    """The fenced code blocks of ``path`` in language ``lang``, in page order."""
    return [m["code"] for m in FENCE_RE.finditer(path.read_text(encoding="utf-8")) if m["lang"] == lang]


def run_blocks(codes: list[str], folder: Path) -> list[str]:
    """Each block in ``folder``: saved when it names its file, else run by Python there; their outputs."""
    outputs = []
    for code in codes:
        named = FILE_RE.match(code.splitlines()[0])
        if named:
            (folder / named["name"]).write_text(code, encoding="utf-8")
            continue
        done = subprocess.run([sys.executable, "-c", code], cwd=folder, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, f"{code}\n{done.stderr}"
        outputs.append(done.stdout)
    return outputs


def test_the_getting_started_python_examples_run_as_written(tmp_path):
    codes = blocks(GETTING_STARTED, "python")
    assert len(codes) == 3 and FILE_RE.match(codes[1].splitlines()[0])
    first, nearest = run_blocks(codes, tmp_path)
    assert first.splitlines()[0] == "runs/from-python"
    for folder in ("runs/from-python", "runs/nearest-from-python"):
        assert (tmp_path / folder / "report.html").is_file()
        checks = check_folder(tmp_path / folder)
        assert checks and all(c.ok for c in checks), [c for c in checks if not c.ok]
    assert float(nearest) > 0  # the strategy of one's own pools passengers
    assert (tmp_path / "runs" / "nearest-from-python" / "runs" / "nearest").is_dir()


def test_the_readme_python_snippet_runs_as_written(tmp_path):
    (code,) = blocks(README, "python")
    assert 'ScenarioRequest("toy"' in code  # the toy city: no data needed
    run_blocks([code], tmp_path)
    written = [kpis.parent for kpis in tmp_path.rglob("kpis.csv")]  # where the snippet chose to write
    assert len(written) == 1, written
    checks = check_folder(written[0])
    assert checks and all(c.ok for c in checks), [c for c in checks if not c.ok]


def shell_commands(path: Path) -> list[list[str]]:
    """The ``rpbench`` command lines of ``path``'s bash blocks, as argument lists (environment settings
    before the command dropped)."""
    commands = []
    for block in blocks(path, "bash"):
        for line in block.replace("\\\n", " ").splitlines():
            for part in line.split("&&"):
                words = shlex.split(part, comments=True)
                while words and re.fullmatch(r"\w+=.*", words[0]):
                    words = words[1:]
                if words[:1] == ["rpbench"]:
                    commands.append(words[1:])
    return commands


def test_the_getting_started_commands_are_valid(capsys):
    commands = shell_commands(GETTING_STARTED)
    assert {c[0] for c in commands} >= {"list", "run", "check", "evaluate", "bench"}
    parser = build_parser()
    for args in commands:
        try:
            parsed = parser.parse_args(args)
        except SystemExit:
            pytest.fail(f"rpbench {shlex.join(args)}: {capsys.readouterr().err}")
        assert parsed.command == args[0]
        if args[0] == "run":
            assert parsed.scenario == "toy", "the page's runs use the toy city (no data needed)"
