"""Validated CSV reading shared by every reader in :mod:`rpbench.data`.

Each reader names the columns it needs and their kinds; this module turns a
missing file, a missing column or a non-numeric value into one clear
:class:`~rpbench.exceptions.DataError` naming the file, the column and (for
bad values) the first offending row.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Mapping

import numpy as np
import pandas as pd

from rpbench.exceptions import DataError, DataNotFoundError

#: Column kinds understood by :func:`read_table`.
INT, FLOAT, TEXT, DATETIME = "int", "float", "text", "datetime"


def require_file(path: Path, what: str) -> Path:
    """Return ``path`` if it is a file, else raise a :class:`DataNotFoundError`."""
    if not path.is_file():
        raise DataNotFoundError(f"{what} file {str(path)!r} does not exist; "
                                "check the data folder (--data) and its SOURCE.md layout")
    return path


def read_table(path: Path, what: str, columns: Mapping[str, str], *,
               rename: Mapping[str, str] | None = None,
               optional: Iterable[str] = ()) -> pd.DataFrame:
    """Read a CSV (plain or gzip) and validate the named columns.

    ``columns`` maps the column name in the file to its kind (``INT``,
    ``FLOAT``, ``TEXT``, ``DATETIME``).  Integers may be written as floats
    (``1078.0``) as long as they are whole.  Returns a frame holding only
    those columns, converted, renamed by ``rename``.  Columns listed in
    ``optional`` may be absent.
    """
    require_file(path, what)
    try:
        frame = pd.read_csv(path, usecols=lambda c: c in columns, low_memory=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError, OSError, EOFError) as exc:
        raise DataError(f"{what} file {str(path)!r} cannot be parsed as CSV: {exc}") from None
    optional = set(optional)
    missing = [c for c in columns if c not in frame.columns and c not in optional]
    if missing:
        raise DataError(f"{what} file {str(path)!r} lacks column(s) {', '.join(map(repr, missing))}; "
                        f"expected columns {', '.join(columns)}")
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
    _fail_on_bad(numeric.isna() | ~np.isfinite(numeric.to_numpy(dtype=float, na_value=np.nan)),
                 series, path, what, name, "a finite number")
    if kind == INT:
        values = numeric.to_numpy(dtype=float)
        whole = values == np.round(values)
        _fail_on_bad(pd.Series(~whole, index=series.index), series, path, what, name, "a whole number")
        return pd.Series(values.astype(np.int64), index=series.index)
    if kind == FLOAT:
        return numeric.astype(np.float64)
    raise ValueError(f"unknown column kind {kind!r}")


def _fail_on_bad(bad: pd.Series, raw: pd.Series, path: Path, what: str, name: str, expected: str) -> None:
    if bool(bad.any()):
        row = int(np.flatnonzero(bad.to_numpy())[0])
        raise DataError(f"{what} file {str(path)!r}, column {name!r}, data row {row + 1}: "
                        f"value {raw.iloc[row]!r} is not {expected}")
