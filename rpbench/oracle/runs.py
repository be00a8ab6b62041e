"""The oracle runs a comparison can include: which variant, which pair rules, and how they are shown.

``oracle1``/``oracle2`` follow the seed's pair rules (ALGORITHMS.md A18);
``oracle1-enroute`` is Oracle-1 that may also pair an order with one already
riding, in either pick-up order (§4.2).  Their options (``--opt
oracle1.allow_enroute=true``) are typed like a strategy's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rpbench.oracle.pairs import PairRules
from rpbench.scenarios.base import Params
from rpbench.strategies.options import RunOptions, option


@dataclass(frozen=True)
class OracleOptions(RunOptions):
    """Pair-rule flags of an oracle run (None: the run's default)."""

    both_pickup_orders: bool | None = option(None, "try both pick-up orders of a pair (§4.2)")
    pickup_check: bool | None = option(None, "require l(o_first, o_second) <= R̄ (§4.2)")
    allow_enroute: bool | None = option(None, "also pair an order with one already riding (§4.2)")


@dataclass(frozen=True)
class OracleRun:
    """One oracle column of a comparison."""

    name: str
    variant: int                     # 1: maximum saving; 2: maximum pairs, ties by saving
    label: str                       # column header and legend entry
    color: str
    description: str
    defaults: dict[str, bool] = field(default_factory=dict)
    Options = OracleOptions

    def rules(self, params: Params, options: OracleOptions) -> PairRules:
        """The pair rules of this run on a scenario with ``params``."""
        flags: dict[str, Any] = dict(self.defaults)
        flags.update({k: v for k, v in options.as_dict().items() if v is not None})
        return PairRules.from_params(params, **flags)


ORACLE_RUNS: dict[str, OracleRun] = {run.name: run for run in [
    OracleRun("oracle1", 1, "Oracle-1", "tab:red", "offline: maximum total saving over pairs requested within "
              "K̄ of each other (paper Eqs. 18-22)"),
    OracleRun("oracle2", 2, "Oracle-2", "tab:purple", "offline: maximum number of pairs, ties by saving"),
    OracleRun("oracle1-enroute", 1, "Oracle-1 (en-route)", "tab:brown", "offline: Oracle-1 that may also pair an "
              "order with one already riding, either pick-up order", {"allow_enroute": True, "both_pickup_orders": True}),
]}
