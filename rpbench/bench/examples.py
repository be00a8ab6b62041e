"""Regenerate the small instances committed under ``instances/examples``.

``python -m rpbench.bench.examples instances/examples`` writes, deterministically:

* synthetic models of each structure shaped like the real ones
  (:mod:`rpbench.bench.synthetic`): a 20x100 round assignment, a 12-request
  trip packing, 300-order pairings for both oracle objectives;
* the largest round of MB, RTV and FL on the toy city (30 % of its orders),
  frozen by :func:`rpbench.bench.snapshot.take_snapshots`.

Each file is a few kilobytes; ``rpbench bench instances/examples`` solves
them with every installed preset.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

from rpbench.bench import synthetic
from rpbench.bench.snapshot import take_snapshots
from rpbench.model.instances import save_instance
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec


def write_examples(folder: str | Path) -> list[Path]:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for model in (
        synthetic.assignment(20, 100, seed=1),
        synthetic.trip_packing(12, 20, seed=1),
        synthetic.pairing(300, seed=1),
        synthetic.pairing(300, seed=1, objective="cardinality_then_weight"),
    ):
        written.append(
            save_instance(
                folder / f"synthetic_{model.name}.npz", model, {"source": "rpbench.bench.synthetic", "seed": 1}
            )
        )
    with tempfile.TemporaryDirectory() as tmp:
        spec = RunSpec.of(ScenarioRequest("toy", sample=0.3, seed=1), ["mb", "rtv", "fl"])
        snaps, entries = take_snapshots(spec, Path(tmp) / "toy", largest=1)
        for e in entries:
            target = folder / e["file"]
            shutil.copy(snaps / e["file"], target)
            written.append(target)
    return written


if __name__ == "__main__":  # pragma: no cover
    for path in write_examples(sys.argv[1] if len(sys.argv) > 1 else "instances/examples"):
        print(path)
