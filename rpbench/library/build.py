"""Building a set: simulate its recipes, freeze the chosen models, write the files and their manifest.

Each :class:`~rpbench.library.sets.Source` is a snapshot (:func:`rpbench.bench.snapshot.take_snapshots`):
the scenario is simulated under each strategy with the ``highs`` preset and the largest round frozen, and
each offline run's pairing model is built over all orders.  Every file is then rewritten with the set's
name, tier, tags and the library version in its metadata, deterministically (fixed zip times, sorted
JSON), so that two builds give the same bytes.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rpbench.bench import synthetic
from rpbench.bench.snapshot import take_snapshots
from rpbench.files.digests import arrays_sha256, file_sha256
from rpbench.library.manifest import SET_FORMAT
from rpbench.library.sets import LIBRARY_VERSION, InstanceSet, Source, Synthetic
from rpbench.model import Model
from rpbench.model.instances import load_instance, save_instance
from rpbench.scenarios import ScenarioRequest
from rpbench.spec import RunSpec

PRESET = "highs"


def build_set(
    spec: InstanceSet, folder: Path, *, data_dir: str | None = None, progress: Callable[[str], None] | None = None
) -> dict[str, Any]:
    """Write every instance of ``spec`` into the existing, empty ``folder``; return the set's manifest."""
    entries: list[dict[str, Any]] = []
    for k, source in enumerate(spec.sources):
        if progress:
            progress(f"{spec.name}: {source.label} ({k + 1}/{len(spec.sources)})")
        entries += _build_source(spec, source, folder, data_dir)
    for model_spec in spec.synthetic:
        entries.append(_build_synthetic(spec, model_spec, folder))
    return {
        "format": SET_FORMAT,
        "set": spec.name,
        "tier": spec.tier,
        "description": spec.description,
        "library_version": LIBRARY_VERSION,
        "preset": PRESET,
        "instances": sorted(entries, key=lambda e: e["file"]),
    }


def _build_source(spec: InstanceSet, source: Source, folder: Path, data_dir: str | None) -> list[dict[str, Any]]:
    request = ScenarioRequest(
        source.scenario, date=source.date, sample=source.sample, seed=source.seed, data_dir=data_dir
    )
    run = RunSpec.of(request, list(source.runs), preset=PRESET)
    with tempfile.TemporaryDirectory(dir=folder.parent) as tmp:
        snaps, found = take_snapshots(run, Path(tmp) / "snap", largest=source.largest)
        out = []
        for entry in found:
            stem = entry["file"][: -len(".npz")].replace(f"{source.scenario}_", f"{source.label}_", 1)
            model, meta = load_instance(snaps / entry["file"])
            provenance = {
                **meta,
                "date": source.date,
                "sample": source.sample,
                "set": spec.name,
                "tier": spec.tier,
                "tags": list(source.tags),
                "library_version": LIBRARY_VERSION,
            }
            out.append(_write(folder / f"{stem}.npz", model, provenance, source.tags))
        shutil.rmtree(snaps, ignore_errors=True)
    return out


def _build_synthetic(spec: InstanceSet, model_spec: Synthetic, folder: Path) -> dict[str, Any]:
    make = getattr(synthetic, model_spec.kind)
    kwargs: dict[str, Any] = {"seed": model_spec.seed}
    if model_spec.objective is not None:
        kwargs["objective"] = model_spec.objective
    model = make(*model_spec.args, **kwargs)
    provenance = {
        "generator": f"rpbench.bench.synthetic.{model_spec.kind}",
        "args": list(model_spec.args),
        "seed": model_spec.seed,
        "objective": None,
        "set": spec.name,
        "tier": spec.tier,
        "tags": list(model_spec.tags),
        "library_version": LIBRARY_VERSION,
    }
    return _write(folder / f"synthetic_{model.name}.npz", model, provenance, model_spec.tags)


def _write(path: Path, model: Model, provenance: dict[str, Any], tags: tuple[str, ...]) -> dict[str, Any]:
    model = model.renamed(path.stem)  # the name a benchmark table and the .solu file use
    save_instance(path, model, provenance)
    size = model.size
    return {
        "file": path.name,
        "name": model.name,
        "structure": model.structure.value,
        "rows": size["rows"],
        "cols": size["cols"],
        "nonzeros": size["nonzeros"],
        "tags": sorted(tags),
        "provenance": {
            k: provenance.get(k)
            for k in ("scenario_name", "date", "sample", "seed", "strategy", "round", "generator", "args")
        },
        "sha256": file_sha256(path),
        "content_sha256": arrays_sha256(path),
    }
