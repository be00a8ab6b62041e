"""The committed example instances are exactly what `python -m rpbench.bench.examples` writes today."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rpbench.bench.examples import write_examples
from rpbench.model.instances import load_instance

COMMITTED = Path(__file__).resolve().parents[2] / "instances" / "examples"


@pytest.mark.slow
def test_committed_examples_are_current(tmp_path):
    fresh = {p.name: p for p in write_examples(tmp_path)}
    assert sorted(fresh) == sorted(p.name for p in COMMITTED.glob("*.npz"))
    for name, path in fresh.items():
        (new, new_meta), (old, old_meta) = load_instance(path), load_instance(COMMITTED / name)
        assert type(new) is type(old) and new_meta == old_meta
        arrays = [f for f in vars(new) if isinstance(getattr(new, f), np.ndarray)]
        assert all(np.array_equal(getattr(new, f), getattr(old, f)) for f in arrays), name
