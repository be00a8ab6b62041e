"""Error classes.

Every error a user can cause (bad file, bad parameter, missing solver) is an
``RpbenchError``; the CLI prints its message on one line and exits with
status 2.  Each class also subclasses the matching built-in so callers that
catch ``ValueError`` or ``FileNotFoundError`` keep working.  Messages say what
is wrong, the offending value, and what to do.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from contextvars import ContextVar


class RpbenchError(Exception):
    """Base class of every user-facing rpbench error."""


class DataError(RpbenchError, ValueError):
    """A data file is malformed: missing column, bad value, unknown node."""


class DataNotFoundError(RpbenchError, FileNotFoundError):
    """A data folder or data file does not exist."""


class ParameterError(RpbenchError, ValueError):
    """A parameter is out of its valid range or of the wrong kind."""


class ModelError(RpbenchError, ValueError):
    """A solver-agnostic model is malformed (NaN value, index out of range...)."""


class SolverNotInstalledError(RpbenchError, ImportError):
    """The library behind a backend is not importable."""


class SolverError(RpbenchError, RuntimeError):
    """A solver failed or returned something that is not a valid solution."""


class PresetError(RpbenchError, ValueError):
    """A solver preset is unknown or its TOML file is malformed."""


class ResultsError(RpbenchError, ValueError):
    """A results folder is missing, empty or inconsistent."""


class DownloadError(RpbenchError, OSError):
    """A data file could not be downloaded (network down, HTTP error, connection cut)."""


class ChecksumError(DataError):
    """A data file's content does not match the SHA-256 the registry pins for it."""


class CacheError(RpbenchError, OSError):
    """The cache folder cannot be used: it is a file, cannot be created or is not writable."""


class NoOrdersError(RpbenchError, ValueError):
    """A scenario would hold no order at all (empty data, or a sample keeping none), so a run would
    only write an empty results folder."""


class LookaheadError(RpbenchError, AttributeError):
    """An online strategy reached for what a dispatcher cannot know before the day: the scenario's realised
    orders (:class:`rpbench.scenarios.base.OnlineView`).  An ``AttributeError`` too, so ``hasattr`` and
    ``getattr(view, "orders", None)`` answer that the view has none."""


def one_line(exc: BaseException) -> str:
    """``exc`` as one line of text, for embedding a library's message in an rpbench error.

    Library messages (pandas, zlib, tomllib) may span several lines, which
    would break the CLI's one-line error contract; an empty message falls
    back to the exception's class name.
    """
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


class DispatcherError(RpbenchError, RuntimeError):
    """A dispatcher outside rpbench failed: a program of the round protocol crashed, hung past its time limit
    or answered garbage, or an agent's answer is not a decision of the round."""


#: How the caller names the results folder of a harness call: ``out`` in Python; the command line sets
#: ``--out`` (:func:`naming_out_as`), so that a message names the parameter its reader typed.
_OUT_PARAMETER: ContextVar[str] = ContextVar("rpbench_out_parameter", default="out")


@contextlib.contextmanager
def naming_out_as(name: str) -> Iterator[None]:
    """Within the block, messages about the results folder call its parameter ``name`` (the CLI: ``--out``)."""
    token = _OUT_PARAMETER.set(name)
    try:
        yield
    finally:
        _OUT_PARAMETER.reset(token)


def out_parameter() -> str:
    """The results folder's parameter as the caller names it: ``out`` (Python) or ``--out`` (the CLI)."""
    return _OUT_PARAMETER.get()


def out_named(value: str | os.PathLike) -> str:
    """The results folder's parameter with its value, as the caller wrote it: ``out='x'`` or ``--out 'x'``."""
    name = out_parameter()
    return f"{name} {str(value)!r}" if name.startswith("-") else f"{name}={str(value)!r}"
