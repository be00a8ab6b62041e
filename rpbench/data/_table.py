"""Validated CSV reading shared by every reader in :mod:`rpbench.data`.

Each reader names the columns it needs and their kinds; this module turns a
missing file, a missing column or a non-numeric value into one clear
:class:`~rpbench.exceptions.DataError` naming the file, the column and (for
bad values) the first offending row.  A damaged gzip stream is a
``DataError`` too, and so is an integer that does not fit an int64 exactly
(a 20-digit id, or ``1e30``): numpy would wrap it around silently.

A path that is not a regular file is named for what it is (a folder, a FIFO, a
symbolic link loop), not as missing.  A ``.gz`` file is inflated through :func:`open_csv`, which refuses it (a
gzip bomb) as soon as it inflates past :data:`INFLATE_RATIO` times its own
size, or :data:`INFLATE_FLOOR` bytes for a small one: never inflated whole.
"""

from __future__ import annotations

import contextlib
import gzip
import io
import zlib
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench.exceptions import DataError, DataNotFoundError, RpbenchError, one_line
from rpbench.files import file_problem, is_missing

#: Column kinds understood by :func:`read_table`.
INT, FLOAT, TEXT, DATETIME = "int", "float", "text", "datetime"
#: Integers written as floats (``1078.0``, ``1e3``) are exact only up to 2**53.
_EXACT_FLOAT_INT = 2.0**53
_INT64 = np.iinfo(np.int64)
#: What a truncated or corrupt ``.gz`` raises while pandas streams it.
_GZIP_ERRORS = (gzip.BadGzipFile, EOFError, zlib.error)
#: The most a ``.gz`` data file may inflate to: this many times its size (the Haikou files inflate 3 to 7
#: times, gzip at best about 1000 times), and at least INFLATE_FLOOR bytes.
INFLATE_RATIO = 100
INFLATE_FLOOR = 64 << 20


#: What to do about a missing or damaged file of a data folder (a user's own file names its own remedy).
DATA_FOLDER_REMEDY = "check the data folder (--data) and its SOURCE.md layout"
DAMAGED_REMEDY = "fetch it again (`rpbench data fetch` replaces damaged files)"


def require_file(path: Path, what: str, remedy: str = DATA_FOLDER_REMEDY) -> Path:
    """Return ``path`` if it is a regular file; else a :class:`DataNotFoundError` when nothing is there, a
    :class:`DataError` naming what is there instead (a folder, a FIFO, a symbolic link loop)."""
    problem = file_problem(path)
    if problem is None:
        return path
    cls = DataNotFoundError if is_missing(problem) else DataError
    raise cls(f"{what} file {str(path)!r} {problem}; {remedy}")


class _BoundedReader(io.RawIOBase):
    """The inflated bytes of the gzip file ``gz`` (read from ``path``), refused with a :class:`DataError` past
    ``limit``."""

    def __init__(self, gz: gzip.GzipFile, path: Path, what: str, limit: int, remedy: str = DAMAGED_REMEDY) -> None:
        self._gz, self._path, self._what, self._limit, self._seen = gz, path, what, limit, 0
        self._remedy = remedy

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        n = self._gz.readinto(memoryview(buffer)[: self._limit - self._seen + 1])
        self._seen += n
        if self._seen > self._limit:
            raise DataError(
                f"{self._what} file {str(self._path)!r} inflates to more than {self._limit:,} bytes (the bound: "
                f"{INFLATE_RATIO} times its size, at least {INFLATE_FLOOR:,} bytes): refused as a gzip bomb; "
                f"{self._remedy}"
            )
        return n


@contextlib.contextmanager
def open_csv(path: Path, what: str, remedy: str | None = None) -> Iterator[io.BufferedIOBase | Path]:
    """What to hand ``pd.read_csv``: ``path`` itself, or for a ``.gz`` a stream bounded as the module says.
    Anything but a regular file at ``path`` is refused first (:func:`require_file`): a FIFO would block.
    ``remedy``: what the error lines tell the user to do (default: the data folder's)."""
    require_file(path, what, remedy or DATA_FOLDER_REMEDY)
    if path.suffix != ".gz":
        yield path
        return
    limit = max(INFLATE_FLOOR, INFLATE_RATIO * path.stat().st_size)
    remedy = remedy or DAMAGED_REMEDY
    with gzip.open(path, "rb") as gz, io.BufferedReader(_BoundedReader(gz, path, what, limit, remedy)) as stream:
        yield stream


def read_table(
    path: Path,
    what: str,
    columns: Mapping[str, str],
    *,
    rename: Mapping[str, str] | None = None,
    optional: Iterable[str] = (),
    remedy: str | None = None,
) -> pd.DataFrame:
    """Read a CSV (plain or gzip) and validate the named columns.

    ``columns`` maps the column name in the file to its kind (``INT``,
    ``FLOAT``, ``TEXT``, ``DATETIME``).  Integers may be written as floats
    (``1078.0``) as long as they are whole.  Returns a frame holding only
    those columns, converted, renamed by ``rename``.  Columns listed in
    ``optional`` may be absent.  ``remedy``: what an error line tells the user to do about a missing or
    damaged file (default: the data folder's; a user's own file names its own).
    """
    try:
        with open_csv(path, what, remedy) as source:
            frame = pd.read_csv(source, usecols=lambda c: c in columns, low_memory=False, compression=None)
    except RpbenchError:  # open_csv's own one line (a missing file is a FileNotFoundError too)
        raise
    except _GZIP_ERRORS as exc:
        raise DataError(
            f"{what} file {str(path)!r} is not a valid gzip stream (truncated or corrupt: "
            f"{one_line(exc)}); {remedy or DAMAGED_REMEDY}"
        ) from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, OSError) as exc:
        raise DataError(f"{what} file {str(path)!r} cannot be parsed as CSV: {one_line(exc)}") from None
    optional = set(optional)
    missing = [c for c in columns if c not in frame.columns and c not in optional]
    if missing:
        raise DataError(
            f"{what} file {str(path)!r} lacks column(s) {', '.join(map(repr, missing))}; "
            f"expected columns {', '.join(columns)}"
        )
    out = {}
    for name, kind in columns.items():
        if name not in frame.columns:
            continue
        out[name] = _convert(frame[name], kind, path, what, name)
    result = pd.DataFrame(out)
    if rename:
        result = result.rename(columns=dict(rename))
    return result


def _convert(series: pd.Series, kind: str, path: Path, what: str, name: str) -> pd.Series:
    if kind == TEXT:
        return series.astype("string")
    if kind == DATETIME:
        converted = pd.to_datetime(series, errors="coerce", format="%Y-%m-%d %H:%M:%S")
        # Some files write minutes only ("2017-07-01 00:03").
        retry = converted.isna() & series.notna()
        if retry.any():
            converted[retry] = pd.to_datetime(series[retry], errors="coerce", format="%Y-%m-%d %H:%M")
        _fail_on_bad(converted.isna(), series, path, what, name, "a date-time (YYYY-MM-DD HH:MM:SS)")
        return converted
    numeric = pd.to_numeric(series, errors="coerce")
    _fail_on_bad(
        numeric.isna() | ~np.isfinite(numeric.to_numpy(dtype=float, na_value=np.nan)),
        series,
        path,
        what,
        name,
        "a finite number",
    )
    if kind == INT:
        return _to_int64(numeric, series, path, what, name)
    if kind == FLOAT:
        return numeric.astype(np.float64)
    raise ValueError(f"unknown column kind {kind!r}")


def _to_int64(numeric: pd.Series, raw: pd.Series, path: Path, what: str, name: str) -> pd.Series:
    """Whole numbers as int64, refusing any value that would not convert exactly.

    pandas reads integers beyond int64 as uint64 or floats; ``astype(int64)``
    would wrap them around (an id of 1e30 became -9223372036854775808, then
    "not a node of the network"), and a float above 2**53 no longer holds the
    integer that was written.
    """
    if pd.api.types.is_signed_integer_dtype(numeric.dtype):
        return numeric.astype(np.int64)
    if pd.api.types.is_unsigned_integer_dtype(numeric.dtype):
        too_big = numeric.to_numpy() > np.uint64(_INT64.max)
        _fail_on_bad(
            pd.Series(too_big, index=raw.index),
            raw,
            path,
            what,
            name,
            f"an integer within the 64-bit range (at most {_INT64.max})",
        )
        return numeric.astype(np.int64)
    values = numeric.to_numpy(dtype=float)
    _fail_on_bad(pd.Series(values != np.round(values), index=raw.index), raw, path, what, name, "a whole number")
    _fail_on_bad(
        pd.Series(np.abs(values) > _EXACT_FLOAT_INT, index=raw.index),
        raw,
        path,
        what,
        name,
        "an exact integer (beyond the 64-bit range, or written as a float beyond ±2^53; "
        "write integers in plain digits)",
    )
    return pd.Series(values.astype(np.int64), index=raw.index)


def _fail_on_bad(bad: pd.Series, raw: pd.Series, path: Path, what: str, name: str, expected: str) -> None:
    if bool(bad.any()):
        row = int(np.flatnonzero(bad.to_numpy())[0])
        value = raw.iloc[row]
        value = value.item() if isinstance(value, np.generic) else value  # 1e+30, not np.float64(1e+30)
        raise DataError(
            f"{what} file {str(path)!r}, column {name!r}, data row {row + 1}: value {value!r} is not {expected}"
        )
