"""SHA-256 digests of files, in the three senses rpbench pins files by.

* :func:`file_sha256`: a file's bytes (results folders' inputs, artefacts, downloaded data);
* :func:`content_sha256`: a file's content, a gzip file's uncompressed bytes (two copies of one table
  compressed at different times differ in their gzip header, not in their content);
* :func:`arrays_sha256`: an instance file's arrays (name, dtype, shape, bytes), not its zip bytes.
"""

from __future__ import annotations

import gzip
import hashlib
import json
import os

import numpy as np

_CHUNK = 1 << 20


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, read in chunks."""
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def content_sha256(path: str | os.PathLike) -> str:
    """SHA-256 of a file's content: a ``.gz`` file's uncompressed bytes (a damaged one's bytes), else its bytes."""
    if not str(path).endswith(".gz"):
        return file_sha256(path)
    h = hashlib.sha256()
    try:
        with gzip.open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(_CHUNK), b""):
                h.update(chunk)
    except (OSError, EOFError):  # `rpbench check` says what is wrong with it; here it only differs
        return file_sha256(path)
    return h.hexdigest()


def arrays_sha256(path: str | os.PathLike, *, skip: tuple[str, ...] = ()) -> str:
    """SHA-256 of an ``.npz`` file's arrays (name, dtype, shape, bytes; by name), not of its zip bytes;
    ``skip``: members left out (``meta_json``: the model alone, whatever tier or run it is recorded from)."""
    h = hashlib.sha256()
    with np.load(path, allow_pickle=False) as z:
        for name in sorted(set(z.files) - set(skip)):
            arr = np.ascontiguousarray(z[name])
            h.update(json.dumps([name, arr.dtype.str, list(arr.shape)]).encode())
            h.update(arr.tobytes())
    return h.hexdigest()
