"""What a comparison folder's ``meta.json`` pins (``inputs_digest``), so that later edits are caught.

The writer records it (:mod:`rpbench.results.folder`); ``rpbench check`` recomputes it from the files
(:mod:`rpbench.check.folder`); ``rpbench report A B`` compares it across folders
(:mod:`rpbench.report.combine`).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from rpbench.digests import file_sha256
from rpbench.results.layout import FLEET, NETWORK, ORDERS
from rpbench.results.store import to_jsonable

#: Input files whose bytes meta.json's ``inputs_digest`` pins.
DIGEST_FILES = (ORDERS, FLEET, NETWORK)
#: The fields of a run's meta.json record that decide what the checker checks (digested per run).
RUN_SPEC_FIELDS = ("kind", "options", "variant", "rules", "status", "unit_m", "artefacts")


def inputs_digest(folder: str | Path, params: dict, runs: dict) -> dict:
    """The SHA-256 of the input files' bytes, of the parameters and of each run's options and rules (canonical
    JSON), as meta.json records it."""
    return {
        "algorithm": "sha256",
        "files": {name: file_sha256(Path(folder) / name) for name in DIGEST_FILES},
        "params": json_sha256(params),
        "runs": {name: json_sha256(recorded_spec(record)) for name, record in runs.items()},
    }


def json_sha256(obj: Any) -> str:
    """SHA-256 of ``obj`` as canonical JSON (sorted keys; what meta.json holds reads back to the same text)."""
    text = json.dumps(to_jsonable(obj), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def recorded_spec(record: dict) -> dict:
    """The fields of a run's meta.json record that decide what is checked (options, rules, status)."""
    return {k: record[k] for k in RUN_SPEC_FIELDS if k in record}
