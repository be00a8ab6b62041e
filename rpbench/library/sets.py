"""The named instance sets of the library, in size tiers, and where each instance comes from.

A set is a list of :class:`Source` recipes (a scenario draw and the runs whose models are frozen from it)
plus tagged synthetic models.  The recipes are the set's definition: ``rpbench instances build SET``
regenerates every file from the data, and the set's manifest (:mod:`.manifest`) pins what they hold.
Tiers by the size of their largest models: **S** (committed: the toy city and the default peak hour),
**M** (the 14 peak hours at the default 30 % sample), **L** (full peak hours, every order),
**XL** (the synthetic full day) and **synthetic** (seeded hard models shaped like the real ones); Manhattan's
peak hour in tiers M (``manhattan``, 30 %) and L (``manhattan-full``, every trip).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rpbench.exceptions import ParameterError

#: The library's version: bumped when a set's definition changes (the manifests record it).
LIBRARY_VERSION = 2
PEAK_DAYS = tuple(f"2017-05-{d:02d}" for d in range(1, 15))
ROUND_RUNS = ("mb", "rtv", "fl")
PAIRING_RUNS = ("bound", "oracle1", "oracle2")


@dataclass(frozen=True)
class Source:
    """Models frozen from one scenario draw: the largest round of each strategy and each offline run's model."""

    scenario: str
    date: str | None
    sample: float
    seed: int
    runs: tuple[str, ...]
    largest: int = 1
    tags: tuple[str, ...] = ()

    @property
    def label(self) -> str:
        day = f"_{self.date}" if self.date else ""
        return f"{self.scenario}{day}_s{round(self.sample * 100):03d}_seed{self.seed}"


@dataclass(frozen=True)
class Synthetic:
    """A seeded synthetic model (:mod:`rpbench.bench.synthetic`): ``kind`` is its generator function."""

    kind: str
    args: tuple[int, ...]
    seed: int
    objective: str | None = None
    tags: tuple[str, ...] = ("synthetic",)


@dataclass(frozen=True)
class InstanceSet:
    name: str
    tier: str
    description: str
    sources: tuple[Source, ...] = ()
    synthetic: tuple[Synthetic, ...] = ()
    committed: bool = False
    needs_data: bool = True
    notes: tuple[str, ...] = field(default=())


SETS: dict[str, InstanceSet] = {
    s.name: s
    for s in [
        InstanceSet(
            "S",
            "S",
            "small: the toy city (30 % of its orders) and the 2017-05-01 peak hour (30 %): the largest round of "
            "MB, RTV and FL and the bound's, Oracle-1's and Oracle-2's pairing models",
            sources=(
                Source("toy", None, 0.3, 1, ROUND_RUNS + PAIRING_RUNS, tags=("toy", "synthetic-city")),
                Source("haikou-peak", "2017-05-01", 0.3, 0, ROUND_RUNS + PAIRING_RUNS, tags=("haikou", "peak")),
            ),
            committed=True,
        ),
        InstanceSet(
            "M",
            "M",
            "medium: the 14 peak hours 2017-05-01..14 at the 30 % sample: the largest round of MB, RTV and FL and "
            "the bound's pairing model of each day",
            sources=tuple(
                Source("haikou-peak", day, 0.3, 0, (*ROUND_RUNS, "bound"), tags=("haikou", "peak")) for day in PEAK_DAYS
            ),
        ),
        InstanceSet(
            "L",
            "L",
            "large: four peak hours with every order (2017-05-01, 04, 08, 12): the largest round of MB, RTV and FL "
            "and the bound's, Oracle-1's and Oracle-2's pairing models",
            sources=tuple(
                Source("haikou-peak", day, 1.0, 0, ROUND_RUNS + PAIRING_RUNS, tags=("haikou", "peak", "full-sample"))
                for day in ("2017-05-01", "2017-05-04", "2017-05-08", "2017-05-12")
            ),
        ),
        InstanceSet(
            "XL",
            "XL",
            "extra large: the synthetic 24-hour stand-in of 2017-05-01 (52,124 orders): the largest round of MB, "
            "RTV and FL and the bound's pairing model (millions of pairs)",
            sources=(Source("haikou-day", "2017-05-01", 1.0, 0, (*ROUND_RUNS, "bound"), tags=("haikou", "full-day")),),
        ),
        InstanceSet(
            "manhattan",
            "M",
            "Manhattan's real 08:00-09:00 peak hour at the 30 % sample (1,883 orders, 4,401 nodes): the largest round "
            "of MB, RTV and FL and the bound's, Oracle-1's and Oracle-2's pairing models",
            sources=(Source("manhattan-peak", None, 0.3, 0, ROUND_RUNS + PAIRING_RUNS, tags=("manhattan", "peak")),),
        ),
        InstanceSet(
            "manhattan-full",
            "L",
            "Manhattan's real 08:00-09:00 peak hour with every trip (6,278 orders): the largest round of MB, RTV and "
            "FL and the bound's, Oracle-1's and Oracle-2's pairing models",
            sources=(
                Source(
                    "manhattan-peak", None, 1.0, 0, ROUND_RUNS + PAIRING_RUNS, tags=("manhattan", "peak", "full-sample")
                ),
            ),
        ),
        InstanceSet(
            "synthetic",
            "M",
            "seeded synthetic models shaped like the real ones, sized to be hard (tagged synthetic)",
            synthetic=(
                Synthetic("assignment", (500, 2000), 1),
                Synthetic("assignment", (2000, 5000), 1),
                Synthetic("trip_packing", (200, 400), 1),
                Synthetic("pairing", (2000,), 1, "weight"),
                Synthetic("pairing", (2000,), 1, "cardinality_then_weight"),
                Synthetic("pairing", (50_000,), 1, "weight"),
            ),
            needs_data=False,
        ),
    ]
}


def instance_set(name: str) -> InstanceSet:
    found = SETS.get(name)
    if found is None:
        raise ParameterError(f"unknown instance set {name!r}; expected one of {', '.join(SETS)}")
    return found
