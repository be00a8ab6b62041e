"""Helpers of the plug-in tests (tests/strategies/test_plugins.py, tests/backends/test_plugins.py)."""

from __future__ import annotations

import sys
from pathlib import Path

#: The example plug-in package (a strategy and a backend outside rpbench).
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rpbench-greedy"


def forget(*packages: str) -> None:
    """Drop ``packages`` and their submodules from ``sys.modules`` (the next import reads the files again)."""
    for name in [m for m in sys.modules if m.split(".")[0] in packages]:
        del sys.modules[name]


def declare_entry_points(folder: Path, dist: str, group: str, entries: dict[str, str]) -> None:
    """What pip writes for a distribution declaring ``entries`` in ``group``: a .dist-info folder in ``folder``."""
    info = folder / f"{dist}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in entries.items()))
