"""Reading the files a user hands rpbench (JSON, TOML, data files) and writing text that may hold their paths.

Beside it: :mod:`.digests` (SHA-256 of files, contents and arrays) and :mod:`.paths` (the data folder, the
cache and their temporaries).

Every fault is one line naming the file, raised as the caller's
:class:`~rpbench.exceptions.RpbenchError` subclass: a path that is a folder,
a FIFO or a symbolic link loop is named as such (not as "missing"); a JSON
or TOML file nested too deeply for the parser (Python's parsers recurse) is
malformed like any other; a record missing a key or holding a value of the
wrong type is refused by :func:`check_schema` before anything indexes it.

Paths are shown with ``!r``, which writes the bytes of a non-UTF-8 name
(decoded by Python as lone surrogates) as escapes; :func:`printable` does the
same for text written to a file (a report quoting such a path or command line),
which UTF-8 could not encode otherwise.
"""

from __future__ import annotations

import errno
import json
import os
import stat
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rpbench.exceptions import RpbenchError, one_line

#: What a file that is not a regular file is, by its mode.
_KINDS = (
    (stat.S_ISDIR, "is a folder, not a file"),
    (stat.S_ISFIFO, "is not a regular file (a FIFO)"),
    (stat.S_ISSOCK, "is not a regular file (a socket)"),
    (stat.S_ISCHR, "is not a regular file (a character device)"),
    (stat.S_ISBLK, "is not a regular file (a block device)"),
)


def file_problem(path: str | os.PathLike) -> str | None:
    """Why ``path`` cannot be read as a regular file ("does not exist", "is a folder, not a file", "is a
    symbolic link loop", ...), or None when it can be opened as one."""
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop"
        if exc.errno == errno.ENOENT and os.path.islink(path):
            return f"is a dangling symbolic link (to {os.readlink(os.fspath(path))!r})"
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return "does not exist"
        if exc.errno == errno.ENAMETOOLONG:
            return "is a name too long for the file system"
        return f"cannot be read ({(exc.strerror or type(exc).__name__).lower()})"
    for test, what in _KINDS:
        if test(mode):
            return what
    return None


def is_missing(problem: str | None) -> bool:
    """Whether a :func:`file_problem` answer means nothing is there (as opposed to the wrong kind of thing)."""
    return problem == "does not exist" or (problem or "").startswith("is a dangling")


def require_regular(path: str | os.PathLike, what: str, error: type[RpbenchError], missing=None) -> Path:
    """``path`` if it is a regular file, else one ``error`` line (``missing``: the class for a path where
    nothing is, default ``error``)."""
    problem = file_problem(path)
    if problem is not None:
        cls = (missing or error) if is_missing(problem) else error
        raise cls(f"{what} {str(path)!r} {problem}")
    return Path(path)


def read_text(path: str | os.PathLike, what: str, error: type[RpbenchError]) -> str:
    """A UTF-8 text file's content; any other kind of file, bytes that are not UTF-8, or a read error is one
    ``error`` line naming the file."""
    require_regular(path, what, error)
    try:
        return Path(path).read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {str(path)!r} is not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise error(f"{what} {str(path)!r} cannot be read: {one_line(exc)}") from None


def parse_json(text: str, where: str, error: type[RpbenchError]) -> Any:
    """``text`` parsed as JSON; malformed or too deeply nested for the parser is one ``error`` line."""
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{where} is not valid JSON: {one_line(exc)}") from None
    except RecursionError:
        raise error(f"{where} is not valid JSON: nested too deeply to parse") from None


def load_json(path: str | os.PathLike, what: str, error: type[RpbenchError]) -> Any:
    """A JSON file's value (see :func:`read_text` and :func:`parse_json`)."""
    return parse_json(read_text(path, what, error), f"{what} {str(path)!r}", error)


def load_json_object(path: str | os.PathLike, what: str, error: type[RpbenchError]) -> dict[str, Any]:
    """A JSON file that must hold an object."""
    value = load_json(path, what, error)
    if not isinstance(value, dict):
        raise error(f"{what} {str(path)!r} does not hold a JSON object (it holds a {_kind(value)})")
    return value


def parse_toml(text: str, where: str, error: type[RpbenchError]) -> dict[str, Any]:
    """``text`` parsed as TOML; malformed or too deeply nested for the parser is one ``error`` line."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{where} is not valid TOML: {one_line(exc)}") from None
    except RecursionError:
        raise error(f"{where} is not valid TOML: nested too deeply to parse") from None


#: A schema: key -> the type(s) its value must have, or a nested schema for a JSON object.
Schema = Mapping[str, "type | tuple[type, ...] | Schema"]


def check_schema(record: Any, schema: Schema, where: str, error: type[RpbenchError], *, at: str = "") -> None:
    """Every key of ``schema`` is in ``record`` with a value of its type (nested schemas: objects checked
    in turn); the first fault is one ``error`` line: ``WHERE lacks 'scenario'`` or ``WHERE:
    scenario.seed is a string, not an integer``.  Keys the schema does not name are left alone."""
    for key, want in schema.items():
        name = f"{at}{key}"
        if not isinstance(record, Mapping) or key not in record:
            raise error(f"{where} lacks {name!r}")
        value = record[key]
        if isinstance(want, Mapping):
            if not isinstance(value, Mapping):
                raise error(f"{where}: {name} is {_article(value)}, not an object")
            check_schema(value, want, where, error, at=f"{name}.")
        elif not _is(value, want):
            raise error(f"{where}: {name} = {_short(value)} is {_article(value)}, not {_expected(want)}")


def _is(value: Any, want: type | tuple[type, ...]) -> bool:
    wanted = want if isinstance(want, tuple) else (want,)
    if isinstance(value, bool) and bool not in wanted:  # JSON true is no number
        return False
    if isinstance(value, int) and float in wanted:
        return True
    return isinstance(value, wanted)


_NAMES = {
    type(None): "null",
    dict: "an object",
    list: "a list",
    str: "a string",
    int: "an integer",
    float: "a number",
    bool: "a boolean",
}


def _short(value: Any) -> str:
    text = " ".join(repr(value).split())
    return text if len(text) <= 40 else text[:37] + "..."


def _kind(value: Any) -> str:
    return {dict: "object", list: "list", str: "string", bool: "boolean", type(None): "null"}.get(
        type(value), type(value).__name__
    )


def _article(value: Any) -> str:
    return "null" if value is None else _NAMES.get(type(value), f"a {type(value).__name__}")


def _expected(want: type | tuple[type, ...]) -> str:
    return " or ".join(_NAMES.get(t, t.__name__) for t in (want if isinstance(want, tuple) else (want,)))


def printable(text: str) -> str:
    """``text`` with the bytes of non-UTF-8 file names and arguments (lone surrogates, as Python decodes
    them) written as ``\\xNN`` escapes, so that it can be written as UTF-8."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        pass
    try:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate no byte decodes to (from a JSON "\\ud800")
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def write_text(path: Path, text: str) -> None:
    """Write ``text`` as UTF-8, non-UTF-8 bytes it quotes escaped (:func:`printable`)."""
    path.write_text(printable(text), encoding="utf-8")
