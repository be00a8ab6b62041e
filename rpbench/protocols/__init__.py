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
from rpbench.report.leaderboard import Bootstrap
from rpbench.results.metrics import DECISION_KPIS, KPI_ORDER
from rpbench.results.ratios import RATIO_KPIS


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
    known = {"name", "version", "description", "scenario", "dates", "sample", "seeds", "strategies", "preset"}
    known |= {"oracle_preset", "metrics", "bootstrap"}
    unknown = sorted(set(raw) - known)
    if unknown:
        raise ParameterError(f"protocol {where!r}: unknown field(s) {', '.join(unknown)}")
    missing = sorted({"name", "version", "scenario", "seeds", "strategies", "metrics"} - set(raw))
    if missing:
        raise ParameterError(f"protocol {where!r}: missing field(s) {', '.join(missing)}")
    try:
        seeds = tuple(int(s) for s in raw["seeds"])
        boot_raw = dict(raw.get("bootstrap", {}))
        boot = Bootstrap(
            resamples=int(boot_raw.pop("resamples", 2000)),
            seed=int(boot_raw.pop("seed", 0)),
            level=float(boot_raw.pop("level", 0.95)),
        )
        if boot_raw:
            raise ParameterError(f"protocol {where!r}: unknown bootstrap field(s) {', '.join(sorted(boot_raw))}")
        protocol = Protocol(
            name=str(raw["name"]),
            version=int(raw["version"]),
            description=str(raw.get("description", "")),
            scenario=str(raw["scenario"]),
            seeds=seeds,
            strategies=tuple(str(s) for s in raw["strategies"]),
            metrics=tuple(str(m) for m in raw["metrics"]),
            sample=None if raw.get("sample") is None else float(raw["sample"]),
            dates=None if raw.get("dates") is None else str(raw["dates"]),
            preset=str(raw.get("preset", "highs")),
            oracle_preset=None if raw.get("oracle_preset") is None else str(raw["oracle_preset"]),
            bootstrap=boot,
        )
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"protocol {where!r}: a field has the wrong type ({exc})") from None
    if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
        raise ParameterError(f"protocol {where!r}: seeds must be distinct non-negative integers")
    bad = [m for m in protocol.metrics if m not in PROTOCOL_METRICS]
    if bad or not protocol.metrics:
        raise ParameterError(
            f"protocol {where!r}: unknown metric(s) {', '.join(bad)} (known: {', '.join(PROTOCOL_METRICS)})"
        )
    if not 1 <= boot.resamples <= 100_000 or not 0.5 <= boot.level < 1.0:
        raise ParameterError(f"protocol {where!r}: bootstrap resamples must be 1..100000 and level in [0.5, 1)")
    if protocol.sample is not None and not 0.0 < protocol.sample <= 1.0:
        raise ParameterError(f"protocol {where!r}: sample must be in (0, 1]")
    return protocol
