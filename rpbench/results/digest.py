"""What a folder's ``meta.json`` pins, so that later edits are caught: a comparison's ``inputs_digest``, an
evaluation's protocol digest, and a published parent's record of what its light children keep.

The writers record them (:mod:`rpbench.results.folder`, ``rpbench evaluate``, ``rpbench publish``); ``rpbench
check`` recomputes them from the files (:mod:`rpbench.check`); ``rpbench report A B`` compares the inputs
digest across folders (:mod:`rpbench.report.combine`).  A digest detects an edit; it is no signature.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from rpbench.files.digests import file_sha256
from rpbench.results.layout import CHECK, FLEET, KPIS, META, NETWORK, ORDERS
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


#: The field of an evaluation's protocol record that holds the digest of the record's other fields.
PROTOCOL_DIGEST = "digest"
#: How many hex digits of the SHA-256 the protocol digest keeps (a name for the experiment, not a signature).
PROTOCOL_DIGEST_CHARS = 16


def protocol_digest(record: Mapping[str, Any]) -> str:
    """The digest of an evaluation's protocol record (``meta.json``'s ``protocol``): the SHA-256 of its other
    fields as JSON with sorted keys, cut to :data:`PROTOCOL_DIGEST_CHARS` hex digits.  The protocol computes it
    when it is written (``rpbench.protocols.Protocol.record``); the checker recomputes it from meta.json alone,
    so both must hash the same text: the tests hold every built-in protocol to it."""
    fields = {k: v for k, v in record.items() if k != PROTOCOL_DIGEST}
    return hashlib.sha256(json.dumps(fields, sort_keys=True).encode()).hexdigest()[:PROTOCOL_DIGEST_CHARS]


#: The field of a published parent's meta.json that records what its light children keep (``rpbench publish``).
LIGHT_COPY = "light_copy"
#: The format of that record: the checker holds a copy claiming it to every file it lists.
LIGHT_COPY_FORMAT = 1
#: The files of a light child the parent's tables and the checker read: its KPIs, its record (scenario, runs,
#: flags) and the checker's verdict on the full folder.
LIGHT_CHILD_FILES = (KPIS, META, CHECK)


def light_copy_record(parent: Path, children: Iterable[str]) -> dict[str, Any]:
    """The record a published parent keeps of its light ``children`` (paths relative to ``parent``): the SHA-256
    of each one's :data:`LIGHT_CHILD_FILES` as published, so that an edit of a child's KPIs, made after its
    event logs were left behind, is caught by ``rpbench check`` of the copy."""
    return {
        "format": LIGHT_COPY_FORMAT,
        "algorithm": "sha256",
        "children": {
            name: {file: file_sha256(parent / name / file) for file in LIGHT_CHILD_FILES} for name in children
        },
    }
