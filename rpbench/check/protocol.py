"""``protocol``: the protocol an evaluation records is whole, well formed and the one its digest names.

``rpbench evaluate`` records the protocol it ran in the evaluation's meta.json (``protocol``) with a digest of
its fields (:func:`rpbench.results.digest.protocol_digest`).  Everything else the checker holds an evaluation to
(its units, each unit's scenario, the tables' metrics and bootstrap) is read from that record, so a record that
is missing, malformed or does not hash to its digest fails here, by name: it is never a reason to skip.

The record is read with the exact types the protocol reader gives its fields (a bool is no number, a seed no
text), here rather than by that reader: the protocols sit above the checker.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from typing import Any

from rpbench.check.core import RunCheck
from rpbench.results.digest import PROTOCOL_DIGEST, protocol_digest
from rpbench.results.layout import META
from rpbench.results.legacy import LEGACY_KPIS
from rpbench.results.metrics import DECISION_KPIS, KPI_ORDER
from rpbench.results.ratios import RATIO_KPIS

PROTOCOL_CHECK = "protocol"
#: What a recorded protocol's metrics may name (the protocol reader's list, and names an older rpbench used).
KNOWN_METRICS = {*KPI_ORDER, *RATIO_KPIS, *DECISION_KPIS, *LEGACY_KPIS}
#: Separates the two ends of a protocol's range of dates (``2017-05-01..2017-05-14``).
DATE_RANGE = ".."


class MalformedRecord(ValueError):
    """A field of the recorded protocol is missing or of the wrong kind (its message names the field)."""


@dataclass(frozen=True)
class RecordedProtocol:
    """The fields of an evaluation's protocol record the checker holds its units and tables to."""

    name: str
    version: int
    scenario: str
    seeds: tuple[int, ...]
    strategies: tuple[str, ...]
    metrics: tuple[str, ...]
    sample: float | None
    dates: str | None
    preset: str
    oracle_preset: str | None
    digest: str

    @property
    def days(self) -> list[str | None]:
        """The protocol's days (None for an undated scenario): ``A..B`` is every calendar day from A to B."""
        return protocol_days(self.dates)

    @property
    def title(self) -> str:
        return f"protocol {self.name!r} version {self.version}"


def read_protocol(fc: RunCheck, meta: dict) -> RecordedProtocol | None:
    """The evaluation's recorded protocol, its digest recomputed (``protocol``); None, after a named failure,
    when the record is missing or malformed (then nothing else can be held to it)."""
    record = meta.get("protocol")
    if record is None:
        fc.fail(PROTOCOL_CHECK, f"{META} records no protocol: the evaluation's units and tables cannot be held to one")
        return None
    if not isinstance(record, dict):
        fc.fail(PROTOCOL_CHECK, f"{META}'s protocol is a {type(record).__name__}, not a record of its fields")
        return None
    try:
        protocol = _parse(record)
    except MalformedRecord as exc:
        fc.fail(PROTOCOL_CHECK, f"{META}'s protocol is malformed: {exc}")
        return None
    actual = protocol_digest(record)
    if protocol.digest != actual:
        fc.fail(
            PROTOCOL_CHECK,
            f"{META}'s protocol does not hash to its digest {protocol.digest!r} (its fields hash to {actual!r}): "
            "the record was edited after the evaluation ran",
        )
    fc.checked["protocol_fields"] = len(record)
    return protocol


def protocol_days(dates: str | None) -> list[str | None]:
    """The days of a protocol's ``dates``: None for an undated scenario, every calendar day of ``A..B``, or the
    listed days of ``A,B,C``; :class:`MalformedRecord` for any other text.  A range means every day in it: a
    data folder lacking a day of the range evaluates without it, and the checker, which never reads the data
    folder, then reports that day's units missing (list the days instead)."""
    if dates is None:
        return [None]
    if DATE_RANGE in dates:
        first, _, last = dates.partition(DATE_RANGE)
        a, b = _day(first), _day(last)
        if b < a:
            raise MalformedRecord(f"dates {dates!r}: the range ends before it starts")
        return [(a + dt.timedelta(days=k)).isoformat() for k in range((b - a).days + 1)]
    days = [_day(d).isoformat() for d in dates.split(",") if d.strip()]
    if not days or len(set(days)) != len(days):
        raise MalformedRecord(f"dates {dates!r}: not a range A..B nor a list of distinct days")
    return list(days)


def _day(text: str) -> dt.date:
    try:
        return dt.date.fromisoformat(text.strip())
    except ValueError:
        raise MalformedRecord(f"dates: {text.strip()!r} is not a day (YYYY-MM-DD)") from None


def _parse(record: dict[str, Any]) -> RecordedProtocol:
    boot = record.get("bootstrap")
    if not isinstance(boot, dict):
        raise MalformedRecord(f"bootstrap is {boot!r}, not a record of resamples, seed and level")
    _integer(boot, "resamples", "bootstrap.", lo=1)
    _integer(boot, "seed", "bootstrap.", lo=0)
    level = _number(boot, "level", "bootstrap.")
    if not 0.5 <= level < 1.0:
        raise MalformedRecord(f"bootstrap.level {level!r} is not in [0.5, 1)")
    seeds = _list(record, "seeds", int)
    if any(s < 0 for s in seeds):
        raise MalformedRecord(f"seeds {list(seeds)!r} are not all >= 0")
    metrics = _list(record, "metrics", str)
    unknown = [m for m in metrics if m not in KNOWN_METRICS]
    if unknown:
        raise MalformedRecord(f"metrics name {', '.join(unknown)}, which are no KPI rpbench reports")
    sample = None if record.get("sample") is None else _number(record, "sample", "")
    if sample is not None and not 0.0 < sample <= 1.0:
        raise MalformedRecord(f"sample {sample!r} is not in (0, 1]")
    protocol = RecordedProtocol(
        name=_text(record, "name"),
        version=_integer(record, "version", "", lo=1),
        scenario=_text(record, "scenario"),
        seeds=seeds,
        strategies=_list(record, "strategies", str),
        metrics=metrics,
        sample=sample,
        dates=None if record.get("dates") is None else _text(record, "dates"),
        preset=_text(record, "preset"),
        oracle_preset=None if record.get("oracle_preset") is None else _text(record, "oracle_preset"),
        digest=_text(record, PROTOCOL_DIGEST),
    )
    protocol_days(protocol.dates)  # a malformed range fails here
    return protocol


def _text(record: dict, key: str) -> str:
    value = record.get(key)
    if not isinstance(value, str) or not value:
        raise MalformedRecord(f"{key} is {value!r}, not a non-empty string")
    return value


def _integer(record: dict, key: str, prefix: str, *, lo: int) -> int:
    value = record.get(key)
    if isinstance(value, bool) or not isinstance(value, int) or value < lo:
        raise MalformedRecord(f"{prefix}{key} is {value!r}, not a whole number >= {lo}")
    return value


def _number(record: dict, key: str, prefix: str) -> float:
    value = record.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MalformedRecord(f"{prefix}{key} is {value!r}, not a finite number")
    return float(value)


def _list(record: dict, key: str, kind: type) -> tuple:
    values = record.get(key)
    if (
        not isinstance(values, list)
        or not values
        or any(isinstance(v, bool) or not isinstance(v, kind) for v in values)
        or len(set(values)) != len(values)
    ):
        what = "whole numbers" if kind is int else "strings"
        raise MalformedRecord(f"{key} is {values!r}, not a non-empty list of distinct {what}")
    return tuple(values)
