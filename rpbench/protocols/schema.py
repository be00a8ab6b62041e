"""A protocol file's fields, each read with its exact type and range: nothing is coerced.

A list of seeds is a TOML array of distinct non-negative integers, not the string ``"012"``; a bool is not
a number (``sample = true`` is refused, not 1.0); a version is an integer (``1.9`` is refused, not 1); a
name is one plain file-name word, since it names the evaluation's default folder.  Every refusal is one
:class:`~rpbench.exceptions.ParameterError` line naming the protocol and the field.
"""

from __future__ import annotations

import math
import re
from typing import Any

from rpbench.exceptions import ParameterError

#: A protocol's name: a plain word of letters, digits, ``.``, ``_`` and ``-``, not starting with a dot.
SAFE_NAME = re.compile(r"^[A-Za-z0-9_-][A-Za-z0-9._-]{0,99}$")


class Fields:
    """The raw TOML table of one protocol (or its ``[bootstrap]`` table), read field by field."""

    def __init__(self, raw: dict[str, Any], where: str, prefix: str = ""):
        self.raw, self.where, self.prefix = raw, where, prefix

    def fail(self, key: str, what: str) -> ParameterError:
        return ParameterError(f"protocol {self.where!r}: {self.prefix}{key} {what}")

    def _get(self, key: str, default: Any) -> Any:
        return self.raw.get(key, default)

    def integer(self, key: str, default: int | None = None, *, lo: int, hi: int | None = None) -> int:
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"must be a whole number, not {value!r}")
        if value < lo or (hi is not None and value > hi):
            raise self.fail(key, f"must be in {lo}..{hi if hi is not None else ''}, not {value}")
        return value

    def number(self, key: str, default: float | None, *, lo: float, hi: float, lo_open: bool, hi_open: bool) -> float:
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(key, f"must be a finite number, not {value!r}")
        low_ok = value > lo if lo_open else value >= lo
        high_ok = value < hi if hi_open else value <= hi
        if not (low_ok and high_ok):
            bounds = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
            raise self.fail(key, f"must be in {bounds}, not {value:g}")
        return float(value)

    def text(self, key: str, default: str | None = None, *, pattern: re.Pattern[str] | None = None) -> str:
        value = self._get(key, default)
        if not isinstance(value, str):
            raise self.fail(key, f"must be a string, not {value!r}")
        if pattern is not None and not pattern.match(value):
            raise self.fail(key, f"{value!r} is not a plain name: letters, digits, '.', '_', '-', no leading dot")
        return value

    def optional_text(self, key: str) -> str | None:
        return None if self._get(key, None) is None else self.text(key)

    def optional_number(self, key: str, *, lo: float, hi: float, lo_open: bool, hi_open: bool) -> float | None:
        if self._get(key, None) is None:
            return None
        return self.number(key, None, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)

    def integers(self, key: str, *, lo: int) -> tuple[int, ...]:
        """A non-empty TOML array of distinct whole numbers >= ``lo``."""
        values = self._list(key)
        if any(isinstance(v, bool) or not isinstance(v, int) for v in values):
            raise self.fail(key, f"must be whole numbers, not {values!r}")
        if min(values) < lo:
            raise self.fail(key, f"must be >= {lo}, not {min(values)}")
        return tuple(self._distinct(key, values))

    def texts(self, key: str) -> tuple[str, ...]:
        """A non-empty TOML array of distinct non-empty strings."""
        values = self._list(key)
        if any(not isinstance(v, str) or not v.strip() for v in values):
            raise self.fail(key, f"must be non-empty strings, not {values!r}")
        return tuple(self._distinct(key, values))

    def _list(self, key: str) -> list[Any]:
        value = self._get(key, None)
        if not isinstance(value, list):
            raise self.fail(key, f"must be an array ([...]), not {value!r}")
        if not value:
            raise self.fail(key, "must not be empty")
        return value

    def _distinct(self, key: str, values: list[Any]) -> list[Any]:
        twice = sorted({str(v) for v in values if values.count(v) > 1})
        if twice:
            raise self.fail(key, f"must be distinct: {', '.join(twice)} appears more than once")
        return values
