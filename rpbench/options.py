"""Typed run options: every strategy (and oracle) declares its options once.

A run's options are a frozen dataclass whose fields carry a type, a default
and a help line (:func:`option`).  :meth:`RunOptions.parse` is the one way
in: it rejects names the class does not declare and values of the wrong
type with one :class:`~rpbench.exceptions.ParameterError` line naming the
option and the known ones, and accepts both Python values (from the
harness) and command-line text (``--opt rtv.rebalance=true``), which it
converts by the declared type rather than by guessing.  A numeric option
declares its sane :class:`Range` (``option(..., range=Range(0, 86400, "s"))``):
a value outside it is refused the same way, before anything runs.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from dataclasses import dataclass
from typing import Any, Self, Union

from rpbench.exceptions import ParameterError


@dataclass(frozen=True)
class Range:
    """The sane range of a number: ``low <= value <= high`` (``low < value`` when ``low_open``), in ``unit``.

    Beyond it a value is a typo or overflows what is derived from it (a time limit of 1e300 s, an array
    sized by it); :meth:`check` gives the one error line.  ``integer`` also requires a whole number.
    """

    low: float
    high: float
    unit: str = ""
    low_open: bool = False
    integer: bool = False

    def describe(self) -> str:
        """``0 < value <= 86400 s``."""
        unit = f" {self.unit}" if self.unit else ""
        low, high = (f"{int(self.low)}", f"{int(self.high)}") if self.integer else (f"{self.low:g}", f"{self.high:g}")
        kind = "an integer " if self.integer else ""
        return f"{kind}{low} {'<' if self.low_open else '<='} value <= {high}{unit}"

    def contains(self, value: float) -> bool:
        if not math.isfinite(value) or value > self.high:
            return False
        if self.integer and value != int(value):
            return False
        return value > self.low if self.low_open else value >= self.low

    def check(self, what: str, value: Any, text: str | None = None) -> Any:
        """``value`` (a number, or text to convert) when it lies in the range, else one ParameterError line
        ``WHAT TEXT is out of range (RANGE)``; ``text`` is the value as the user typed it."""
        shown = text if text is not None else (value if isinstance(value, str) else repr(value))
        number = _number(value)
        if number is None:
            raise ParameterError(f"{what} {shown} is not a number ({self.describe()})")
        if not self.contains(number):
            raise ParameterError(f"{what} {shown} is out of range ({self.describe()})")
        return int(number) if self.integer else number


def _number(value: Any) -> float | None:
    """``value`` as a float (text "1e3", an int, a float), or None when it is no number at all."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        try:
            return float(value)
        except OverflowError:  # an int beyond float: out of any range
            return math.inf
    if isinstance(value, str):
        try:
            return float(value.strip())
        except ValueError:
            return None
    return None


def option(default: Any, help: str, *, choices: tuple[str, ...] | None = None, range: Range | None = None) -> Any:
    """A declared option: its default, one help line, for text options the allowed values and for numeric
    options (every one must declare it) the sane :class:`Range`."""
    return dataclasses.field(default=default, metadata={"help": help, "choices": choices, "range": range})


@dataclass(frozen=True)
class RunOptions:
    """Base of every options class (a strategy without options uses it as is)."""

    @classmethod
    def parse(cls, owner: str, raw: dict[str, Any] | None = None) -> Self:
        """The options named in ``raw`` (Python values or text), the rest at their defaults."""
        raw = dict(raw or {})
        declared = {f.name: f for f in dataclasses.fields(cls)}
        unknown = sorted(set(raw) - set(declared))
        if unknown:
            known = ", ".join(declared) or "none"
            raise ParameterError(f"{owner}: unknown option {unknown[0]!r}; known options: {known}")
        hints = typing.get_type_hints(cls)
        values = {
            name: _convert(owner, name, hints[name], declared[name].metadata.get("choices"), value)
            for name, value in raw.items()
        }
        for name, value in values.items():
            _check_range(owner, name, declared[name].metadata.get("range"), value)
        return cls(**values)

    @classmethod
    def help(cls) -> dict[str, str]:
        """Option name -> help line with its default (for ``rpbench list``)."""
        out = {}
        for f in dataclasses.fields(cls):
            text = f.metadata.get("help", "")
            text = text if "default" in text else f"{text} (default {f.default!r})"
            bounds = f.metadata.get("range")
            out[f.name] = f"{text}; {bounds.describe()}" if bounds is not None else text
        return out

    def as_dict(self) -> dict[str, Any]:
        """Every option, defaults included (as recorded in meta.json)."""
        return {f.name: _plain(getattr(self, f.name)) for f in dataclasses.fields(self)}

    def replace(self, **changes: Any) -> Self:
        return dataclasses.replace(self, **changes)


def _check_range(owner: str, name: str, bounds: Range | None, value: Any) -> None:
    """Every number of ``value`` (one, or each of a per-hour list) inside the option's declared range."""
    if bounds is None or value is None or isinstance(value, (bool, str)):
        return
    for number in value if isinstance(value, tuple) else (value,):
        if isinstance(number, (int, float)) and not isinstance(number, bool):
            bounds.check(f"{owner}: option {name} =", number, f"{number!r}")


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


_TRUE, _FALSE, _NONE = ("true", "yes", "1", "on"), ("false", "no", "0", "off"), ("none", "null", "")


def _convert(owner: str, name: str, kind: Any, choices: tuple[str, ...] | None, value: Any) -> Any:
    """``value`` as the declared ``kind`` (a union tries its members in order), or one clear error."""
    members = typing.get_args(kind) if typing.get_origin(kind) in (Union, types.UnionType) else (kind,)
    # text matches None before str ("none" is no rtv.c_ko), then the members in their declared order
    for member in sorted(members, key=lambda m: m is not type(None)):
        try:
            converted = _as(member, value)
        except (TypeError, ValueError):
            continue
        if choices and isinstance(converted, str) and converted not in choices:
            continue
        return converted
    wanted = [_type_name(m) for m in members if not (choices and m is str)]
    if choices:
        wanted.append(f"one of {', '.join(choices)}")
    raise ParameterError(f"{owner}: option {name} = {value!r} must be {' or '.join(wanted)}")


def _as(kind: Any, value: Any) -> Any:
    """Convert or raise TypeError/ValueError."""
    text = value.strip().lower() if isinstance(value, str) else None
    if kind is type(None):
        if value is None or text in _NONE:
            return None
    elif kind is bool:
        if isinstance(value, bool):
            return value
        if text in _TRUE or text in _FALSE:
            return text in _TRUE
    elif kind is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        if text is not None:
            return int(text)
    elif kind is float:
        number = (
            float(value)
            if (isinstance(value, (int, float)) and not isinstance(value, bool)) or text is not None
            else None
        )
        if number is not None and math.isfinite(number):
            return number
    elif kind is str:
        if isinstance(value, str):
            return value
    elif typing.get_origin(kind) is tuple:  # tuple[float, ...]: a list, or text "a,b,c"
        (item, _) = typing.get_args(kind)
        items = value.split(",") if isinstance(value, str) else value
        if isinstance(items, (list, tuple)) and items:
            return tuple(_as(item, v) for v in items)
    raise TypeError(f"not a {kind}")


def _type_name(kind: Any) -> str:
    if kind is type(None):
        return "none"
    if typing.get_origin(kind) is tuple:
        return f"a list of {_type_name(typing.get_args(kind)[0])}s"
    return {bool: "true/false", int: "an integer", float: "a finite number", str: "text"}.get(kind, str(kind))
