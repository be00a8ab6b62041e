"""The offline runs a comparison can include: which matching, which pair rules, and how they are shown.

``bound`` is the proven upper bound on the saving of any strategy rpbench's
simulator can run (docs/bound.md): the denominator of the competitive ratio.
``oracle1``/``oracle2`` are the paper's offline oracles with the seed's pair
rules (docs/algorithms.md A18): references, not bounds (a strategy that pairs en
route can save more than Oracle-1).  Their options (``--opt
oracle1.allow_enroute=true``) are typed like a strategy's; the bound has none.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rpbench.options import RunOptions, option
from rpbench.oracle.pairs import PairRules
from rpbench.scenarios.base import Params


@dataclass(frozen=True)
class OracleOptions(RunOptions):
    """Pair-rule flags of an oracle run (None: the run's default)."""

    both_pickup_orders: bool | None = option(None, "try both pick-up orders of a pair (§4.2)")
    pickup_check: bool | None = option(None, "require l(o_first, o_second) <= R̄ (§4.2)")
    allow_enroute: bool | None = option(None, "also pair an order with one already riding (§4.2)")


@dataclass(frozen=True)
class OracleRun:
    """One offline column of a comparison."""

    name: str
    variant: int  # 1: maximum saving; 2: maximum pairs, ties by saving
    label: str  # column header and legend entry
    color: str
    description: str
    defaults: dict[str, Any] = field(default_factory=dict)
    Options: type[RunOptions] = OracleOptions

    def rules(self, params: Params, options: RunOptions) -> PairRules:
        """The pair rules of this run on a scenario with ``params`` (``options``: of this run's :attr:`Options`)."""
        flags: dict[str, Any] = dict(self.defaults)
        flags.update({k: v for k, v in options.as_dict().items() if v is not None})
        return PairRules.from_params(params, **flags)


ORACLE_RUNS: dict[str, OracleRun] = {
    run.name: run
    for run in [
        OracleRun(
            "bound",
            1,
            "Upper bound",
            "black",
            "offline: proven upper bound on any strategy's saving (docs/bound.md)",
            {"window": "bound", "both_pickup_orders": True},
            RunOptions,
        ),
        OracleRun(
            "oracle1",
            1,
            "Oracle-1",
            "tab:red",
            "offline: the paper's Oracle-1, maximum saving over pairs "
            "requested within K̄ of each other (Eqs. 16-20); a reference, not a bound",
        ),
        OracleRun(
            "oracle2",
            2,
            "Oracle-2",
            "tab:purple",
            "offline: the paper's Oracle-2, maximum number of pairs, ties by saving",
        ),
    ]
}
