"""The mechanisms of the authors' simulator, one named switch each, in the fixed order of the ablation.

``True`` is the authors' behaviour (learnt by reading their public code:
``yangchen-seu/A-prediction-based-forward-looking-vehicle-dispatching-strategy-for-dynamic-ride-pooling``,
``baseline2_batch_matching/Simulation.py`` and siblings); ``False`` is what the
paper's text and rpbench's own simulator do.  All on = the authors' engine;
all off approaches rpbench's engine (``rpbench/sim``), which the ablation runs
too, so the last step's remaining difference is measured, not assumed.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from rpbench.exceptions import ParameterError


@dataclass(frozen=True)
class Mechanism:
    """One switch: its name and what it does on and off."""

    name: str
    when_on: str  # what the switch on does (the authors' code)
    when_off: str  # what the switch off does (the paper's text and rpbench's simulator)


MECHANISMS: tuple[Mechanism, ...] = (
    Mechanism(
        "teleport",
        "a vehicle steps by popping the LAST node of its route: one passenger's vehicle jumps to the "
        "origin in one round and to the destination a few rounds later; vehicles move only in rounds "
        "with waiting passengers and free vehicles; a vehicle assigned while standing at the passenger's "
        "origin counts as having picked the passenger up, its activity time kept",
        "vehicles travel their shortest routes at 30 km/h and are where the clock says",
    ),
    Mechanism(
        "early_release",
        "a solo vehicle is vacant again when it has jumped to the destination (about a minute after "
        "assignment); only pooled trips block the vehicle for (pick-up + route) x 0.12 s/m",
        "a solo vehicle is vacant no earlier than its real arrival at the destination",
    ),
    Mechanism(
        "grid_cells",
        "a vehicle is a candidate only if its node lies in the passenger's 0.05 degree cell",
        "every vehicle within the pick-up radius is a candidate",
    ),
    Mechanism(
        "pickup_from_first_origin",
        "the second pick-up (and the pair's saving and detours) is measured from the first passenger's "
        "origin wherever the vehicle is, weights use the reversed direction (passenger origin -> vehicle); "
        "ties in the drop-off order go to first-on-last-off; the pooled vehicle ends at the second "
        "passenger's destination",
        "pick-ups are measured from the vehicle's position along its route (the first passenger's ridden "
        "distance counts); ties go to first-on-first-off; the vehicle ends at its last drop-off",
    ),
    Mechanism(
        "idle_jumps",
        "an unmatched vacant vehicle heads for a random order origin (and, with teleport, jumps there "
        "once its route's first link's time has passed, then steps back along the route one node per "
        "round until the route is used up; RTV draws anew every round)",
        "an unmatched vacant vehicle waits where it is",
    ),
    Mechanism(
        "authors_input",
        "the authors' exact input: haikou-paper-input (arrive-time selection on 2017-05-01, pandas "
        "sample random_state=1, int(n/4) vehicles, whole sample as the response denominator)",
        "rpbench's haikou-peak input (departures inside the hour, seeded sample, 25 vehicles per 100 "
        "orders, released orders as the denominator)",
    ),
    Mechanism(
        "authors_weights",
        "the authors' weights and small rules: MB 3000 + saving - pick-up / 3000 - pick-up (no match "
        "-3000), NP (ride - pick-up) + 3000, FL-no_delay e - pk + 3000, a taker without a partner "
        "delivered alone after 600 s, patience not floored in MB and NP",
        "rpbench's utilities (NP -pk, MB e - pk / -pk, FL-no_delay e_bar - pk, waiting never "
        "preferred to a feasible match), no 600 s rule, patience floored at 30 s",
    ),
    Mechanism(
        "authors_ledger",
        "the authors' ledger and FL parameters: a solo passenger counts as served only once delivered, "
        "MB's first pick-up keeps only the last link, FL alpha 1.1 and r_w 0.8 with the predicted "
        "savings doubled and the waiting utility times 1/(k+1)",
        "served at assignment, full pick-up distances, the paper's alpha 1.01 and r_w 0.75, predictions as published",
    ),
)

NAMES: tuple[str, ...] = tuple(m.name for m in MECHANISMS)


@dataclass(frozen=True)
class Switches:
    """Which of the authors' mechanisms are on (all on by default = the authors' engine)."""

    teleport: bool = True
    early_release: bool = True
    grid_cells: bool = True
    pickup_from_first_origin: bool = True
    idle_jumps: bool = True
    authors_input: bool = True
    authors_weights: bool = True
    authors_ledger: bool = True

    @classmethod
    def authors(cls) -> Switches:
        return cls()

    @classmethod
    def none(cls) -> Switches:
        return cls(**{name: False for name in NAMES})

    def without(self, *names: str) -> Switches:
        """These switches off, the rest unchanged (one clear error for an unknown name)."""
        unknown = [n for n in names if n not in NAMES]
        if unknown:
            raise ParameterError(f"unknown mechanism {unknown[0]!r}; expected one of {', '.join(NAMES)}")
        return dataclasses.replace(self, **{n: False for n in names})

    def off(self) -> list[str]:
        return [n for n in NAMES if not getattr(self, n)]

    def label(self) -> str:
        off = self.off()
        if not off:
            return "authors"
        if len(off) == len(NAMES):
            return "all-off"
        return "authors-" + "-".join(off)


ABLATIONS = ("single", "cumulative", "both", "none")


def cumulative_steps() -> list[tuple[str, Switches]]:
    """The path from the authors' engine to all-off: mechanisms 1..k off for k = 1..8, in the fixed order.

    The differences between consecutive steps telescope, so they add up to the whole authors-to-all-off
    difference: each is what that mechanism explains *given the ones before it are fixed*.
    """
    return [(f"cum{k}-{name}", Switches().without(*NAMES[:k])) for k, name in enumerate(NAMES, start=1)]


def steps_for(mode: str) -> list[tuple[str, Switches]]:
    """The engine runs of an ablation mode (always starting with the authors' engine)."""
    if mode not in ABLATIONS:
        raise ParameterError(f"--ablation {mode!r}: expected one of {', '.join(ABLATIONS)}")
    single = ablation_steps()
    if mode == "none":
        return single[:1]
    if mode == "single":
        return single
    if mode == "cumulative":
        return single[:1] + cumulative_steps()
    return single + cumulative_steps()[:-1]  # the last cumulative step is all-off, already in single


def ablation_steps() -> list[tuple[str, Switches]]:
    """The fixed ablation: the authors' engine, then one mechanism off at a time, then all off.

    Each step switches ONE mechanism off on top of the authors' engine (not
    cumulatively), so each row's difference to the first is that mechanism's
    own effect; the all-off row shows how far the sum is from rpbench's engine.
    """
    steps = [("authors", Switches.authors())]
    steps += [(f"no-{name}", Switches.authors().without(name)) for name in NAMES]
    steps.append(("all-off", Switches.none()))
    return steps
