"""A set's manifest: what each instance file holds, where it comes from, and its digests.

``manifests/SET.json`` (packaged) is the reference a built or downloaded set is verified against. Per
instance: the file name, structure, size (rows, columns, non-zeros), tags, provenance (scenario, date,
sample, seed, run, round, generator), ``sha256`` (the file's bytes) and ``content_sha256`` (the arrays:
each one's name, dtype, shape and bytes, in name order).  Instance files are written with fixed zip
member times, so a build reproduces the file digests where the zlib library is the same; the content
digest is independent of the compressor and is what :func:`verify_folder` requires.
"""

from __future__ import annotations

import json
import zipfile
from importlib import resources
from pathlib import Path
from typing import Any

from rpbench.exceptions import ParameterError
from rpbench.files import load_json_object
from rpbench.files.digests import arrays_sha256, file_sha256

SET_FORMAT = "rpbench-instance-set-1"
MANIFEST = "manifest.json"


def packaged_manifest(name: str) -> dict[str, Any] | None:
    """The reference manifest of set ``name`` shipped with rpbench (None: none recorded yet)."""
    ref = resources.files(__package__).joinpath("manifests", f"{name}.json")
    if not ref.is_file():
        return None
    return json.loads(ref.read_text(encoding="utf-8"))


def library_names() -> set[str]:
    """The name of every instance of every set whose reference manifest ships with rpbench."""
    names: set[str] = set()
    for ref in resources.files(__package__).joinpath("manifests").iterdir():
        if ref.name.endswith(".json"):
            names |= {str(i["name"]) for i in json.loads(ref.read_text(encoding="utf-8"))["instances"]}
    return names


def read_manifest(folder: Path) -> dict[str, Any]:
    return load_json_object(folder / MANIFEST, "instance set manifest", ParameterError)


def write_manifest(path: Path, manifest: dict[str, Any]) -> None:
    path.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n", encoding="utf-8")


def verify_folder(folder: Path, reference: dict[str, Any]) -> list[str]:
    """What differs between the instance files in ``folder`` and ``reference`` (empty: every file is there
    and holds what the manifest says; a file the manifest does not list is a difference too)."""
    problems = []
    listed = {e["file"]: e for e in reference.get("instances", [])}
    present = {p.name for p in folder.glob("*.npz")}
    for name in sorted(present - set(listed)):
        problems.append(f"{name}: not in the manifest")
    for name, entry in listed.items():
        path = folder / name
        if not path.is_file():
            problems.append(f"{name}: missing")
            continue
        try:
            digest = arrays_sha256(path)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:  # a flipped byte, a truncated file
            problems.append(f"{name}: unreadable ({type(exc).__name__}: {exc})")
            continue
        if digest != entry["content_sha256"]:
            problems.append(f"{name}: its arrays differ from the manifest's (content SHA-256)")
    return problems


def same_files(folder: Path, reference: dict[str, Any]) -> tuple[int, int]:
    """How many of the manifest's files have its exact file SHA-256 too, of how many."""
    entries = reference.get("instances", [])
    same = sum(1 for e in entries if (folder / e["file"]).is_file() and file_sha256(folder / e["file"]) == e["sha256"])
    return same, len(entries)
