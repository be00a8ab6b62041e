"""Shared helpers of the bad-input fault tests tests/faults/test_inputs_*.py (this module holds no test).

Every fault ends one of two ways: one clear line on stderr with exit status
2 and nothing half-written (:func:`cli_error`), or a correct rebuild whose
result equals a fresh build (:func:`cli_ok`).
"""

from __future__ import annotations

import csv
import gzip
import io
import json
from pathlib import Path

from rpbench.cli import main

#: Orders file of the fake data folder (tests/conftest.py ``fake_data``).
PEAK = Path("demand_0800_0900") / "orders" / "2017-05-01.csv.gz"
#: The cheapest complete run: one strategy on a tenth of the toy city.
TOY_RUN = ("run", "--scenario", "toy", "--sample", "0.1", "--strategies", "np", "--no-progress")


def cli_error(capsys, *argv: str) -> str:
    """Run the CLI expecting a user error: exit 2, exactly one non-empty stderr line, no traceback.

    Returns that line (without the ``rpbench: error:`` prefix).
    """
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, (code, out, err)
    assert len(lines) == 1, err
    assert "Traceback" not in err and "Traceback" not in out
    assert lines[0].startswith("rpbench: error: "), lines[0]
    return lines[0].removeprefix("rpbench: error: ")


def cli_ok(capsys, *argv: str) -> tuple[str, str]:
    """Run the CLI expecting success; returns (stdout, stderr)."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, (code, out, err)
    assert "Traceback" not in err
    return out, err


def scenario_json(capsys, *argv: str) -> dict:
    """``rpbench scenario ... --json`` as a dict, without its timing (which differs between runs)."""
    out, _ = cli_ok(capsys, "scenario", *argv, "--json")
    summary = json.loads(out)
    summary.pop("build_s", None)
    return summary


def read_gz(path: Path) -> str:
    with gzip.open(path, "rt") as fh:
        return fh.read()


def write_gz(path: Path, text: str) -> None:
    with gzip.open(path, "wt") as fh:
        fh.write(text)


def edit_gz(path: Path, edit) -> None:
    """Rewrite a gzipped text file through ``edit(text) -> text``."""
    write_gz(path, edit(read_gz(path)))


def edit_csv_cell(path: Path, row: int, column: str, value: str) -> None:
    """Set one cell of a (gzipped or plain) CSV; ``row`` counts data rows from 0."""
    text = read_gz(path) if path.suffix == ".gz" else path.read_text()
    rows = list(csv.reader(io.StringIO(text)))
    rows[row + 1][rows[0].index(column)] = value
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    write_gz(path, buffer.getvalue()) if path.suffix == ".gz" else path.write_text(buffer.getvalue())


def flip_byte(path: Path, offset: int) -> None:
    """Invert one byte of a file (a negative offset counts from the end)."""
    data = bytearray(path.read_bytes())
    data[offset] ^= 0xFF
    path.write_bytes(bytes(data))


def truncate(path: Path, keep: float = 0.5) -> None:
    """Keep the first ``keep`` fraction of a file's bytes."""
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])


def leftovers(folder: Path) -> list[Path]:
    """Temporary files a failed write left behind."""
    return sorted(p for p in folder.rglob("*") if p.name.endswith(".tmp") or ".part" in p.name)
