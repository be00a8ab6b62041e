"""examples/gym/cem.py, short: it trains, grades the learnt rule beside NP, MB and FL, and every graded
episode passes the checker."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

CEM = Path(__file__).resolve().parents[2] / "examples" / "gym" / "cem.py"


def test_the_cross_entropy_example_learns_and_grades(tmp_path):
    out = tmp_path / "cem"
    args = ["--sample", "0.2", "--iterations", "1", "--population", "2", "--train-seeds", "1", "--test-seeds", "0"]
    done = subprocess.run(
        [sys.executable, str(CEM), *args, "--out", str(out)], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    row = next(line for line in done.stdout.splitlines() if line.split()[:1] == ["0"])
    assert row.split()[-1] == "OK"
    assert (out / "toy" / "episode-0001" / "runs" / "cem" / "events.csv.gz").is_file()
    again = subprocess.run([sys.executable, str(CEM), "--out", str(out)], capture_output=True, text=True, timeout=60)
    assert again.returncode == 1 and "already exists" in again.stderr


def test_the_documented_minimal_example_runs_as_written(tmp_path, monkeypatch):
    """docs/gym.md's first Python example, pasted, plays MB's rule and prints a checked episode."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "gym.md").read_text()
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(tmp_path)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    saving, verdict, ratio, folder = done.stdout.split()
    assert round(float(saving)) == 142 and verdict == "OK" and f"{float(ratio):.3f}" == "0.490"
    assert (tmp_path / folder / "report.html").is_file()
