"""Evaluation protocols: named, versioned, fixed choices of days, sample, seeds, runs, presets and metrics.

A protocol is a TOML file (this folder holds the built-in ones; ``rpbench evaluate PATH.toml`` takes any),
so that two studies quoting the same protocol name and version ran the same experiment.  Its fields:
``name``, ``version``, ``description``, ``scenario``, ``dates`` (optional: a range or list, for dated
scenarios), ``sample``, ``seeds``, ``strategies``, ``preset``, ``oracle_preset``, ``metrics`` (the first
ranks the leaderboard) and ``[bootstrap]`` (``resamples``, ``seed``, ``level``).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from rpbench.exceptions import ParameterError
from rpbench.files import parse_toml, read_text
from rpbench.protocols.schema import SAFE_NAME, Fields
from rpbench.report.leaderboard import Bootstrap
from rpbench.results.metrics import DECISION_KPIS, KPI_ORDER
from rpbench.results.ratios import DENOMINATORS, RATIO_KPIS


@dataclass(frozen=True)
class Protocol:
    name: str
    version: int
    description: str
    scenario: str
    seeds: tuple[int, ...]
    strategies: tuple[str, ...]
    metrics: tuple[str, ...]
    sample: float | None = None
    dates: str | None = None
    preset: str = "highs"
    oracle_preset: str | None = None
    bootstrap: Bootstrap = field(default_factory=Bootstrap)

    def record(self) -> dict[str, Any]:
        """The protocol as meta.json records it (and its digest, which a resumed evaluation must match)."""
        out = asdict(self)
        out["seeds"], out["strategies"], out["metrics"] = list(self.seeds), list(self.strategies), list(self.metrics)
        out["digest"] = hashlib.sha256(json.dumps(out, sort_keys=True).encode()).hexdigest()[:16]
        return out


#: What a protocol's metrics may name: the comparison table's KPIs, the ratios (the competitive ratio's two ends,
#: saving / Oracle-1), decision times.
PROTOCOL_METRICS = (*KPI_ORDER, *RATIO_KPIS, *DECISION_KPIS)
#: A ratio metric and the offline run it divides by: a protocol naming one must run that run.
RATIO_NEEDS = DENOMINATORS


def builtin_names() -> list[str]:
    return sorted(p.name[: -len(".toml")] for p in resources.files(__package__).iterdir() if p.name.endswith(".toml"))


def load_protocol(name_or_path: str) -> Protocol:
    """A built-in protocol by name, or a TOML file by path; a bad one is one ParameterError line."""
    if name_or_path.endswith(".toml") or "/" in name_or_path:
        path = Path(name_or_path)
        text, where = read_text(path, "protocol file", ParameterError), name_or_path
    elif name_or_path in builtin_names():
        text = resources.files(__package__).joinpath(f"{name_or_path}.toml").read_text(encoding="utf-8")
        where = name_or_path
    else:
        raise ParameterError(f"unknown protocol {name_or_path!r} (built in: {', '.join(builtin_names())})")
    return _parse(parse_toml(text, f"protocol {where!r}", ParameterError), where)


def _parse(raw: dict[str, Any], where: str) -> Protocol:
    """The protocol of a parsed TOML table, every field checked (:mod:`.schema`)."""
    known = {"name", "version", "description", "scenario", "dates", "sample", "seeds", "strategies", "preset"}
    known |= {"oracle_preset", "metrics", "bootstrap"}
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ParameterError(f"protocol {where!r}: unknown field(s) {', '.join(unknown)}")
    missing = sorted({"name", "version", "scenario", "seeds", "strategies", "metrics"} - set(raw))
    if missing:
        raise ParameterError(f"protocol {where!r}: missing field(s) {', '.join(missing)}")
    f = Fields(raw, where)
    boot_raw = raw.get("bootstrap", {})
    if not isinstance(boot_raw, dict):
        raise f.fail("bootstrap", f"must be a table ([bootstrap]), not {boot_raw!r}")
    unknown_boot = sorted(set(boot_raw) - {"resamples", "seed", "level"})
    if unknown_boot:
        raise ParameterError(f"protocol {where!r}: unknown bootstrap field(s) {', '.join(unknown_boot)}")
    b = Fields(boot_raw, where, prefix="bootstrap.")
    protocol = Protocol(
        name=f.text("name", pattern=SAFE_NAME),
        version=f.integer("version", lo=1),
        description=f.text("description", ""),
        scenario=f.text("scenario"),
        seeds=f.integers("seeds", lo=0),
        strategies=f.texts("strategies"),
        metrics=f.texts("metrics"),
        sample=f.optional_number("sample", lo=0.0, hi=1.0, lo_open=True, hi_open=False),
        dates=f.optional_text("dates"),
        preset=f.text("preset", "highs"),
        oracle_preset=f.optional_text("oracle_preset"),
        bootstrap=Bootstrap(
            resamples=b.integer("resamples", 2000, lo=1, hi=100_000),
            seed=b.integer("seed", 0, lo=0, hi=2**63 - 1),
            level=b.number("level", 0.95, lo=0.5, hi=1.0, lo_open=False, hi_open=True),
        ),
    )
    bad = [m for m in protocol.metrics if m not in PROTOCOL_METRICS]
    if bad:
        raise ParameterError(
            f"protocol {where!r}: unknown metric(s) {', '.join(bad)} (known: {', '.join(PROTOCOL_METRICS)})"
        )
    for metric, needs in RATIO_NEEDS.items():
        if metric in protocol.metrics and needs not in protocol.strategies:
            raise ParameterError(
                f"protocol {where!r}: metric {metric} divides by the run {needs!r}, which its strategies do not list"
            )
    return protocol
