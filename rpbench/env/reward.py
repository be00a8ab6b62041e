"""The environment's rewards: what a round's committed decisions are planned to add to a run's KPI.

Three objectives, each a KPI of the paper's Table 2 (:mod:`rpbench.results.metrics`):

* ``saving`` (default), ``total_saving_km``: a join adds its planned saving e = l_A + l_B - L (Eq. 5);
* ``profit``, ``platform_profit_cny``: fares minus driver pay.  With occupied distance = solo distance
  served - saving, profit = Σ_served fare_i l_i - pay Σ_served l_i + pay saving; so a passenger taking a
  vacant vehicle adds (f_solo - pay) l_p, and one joining A's vehicle adds (f_pooled - pay) l_p +
  (f_pooled - f_solo) l_A (A now pays the pooled fare) + pay e;
* ``response``, ``response_rate``: each passenger assigned adds 1 / orders.

A plan is what the vehicles then drive, so the rewards add up to the KPI; the environment's last step adds
what is left (``final_correction``), so that the return is the KPI exactly.
"""

from __future__ import annotations

from rpbench.exceptions import ParameterError
from rpbench.scenarios.base import Params
from rpbench.strategies.agent import Committed

#: Each reward and the KPI its episode's return equals.
REWARD_KPIS = {"saving": "total_saving_km", "profit": "platform_profit_cny", "response": "response_rate"}


def check_reward(reward: str) -> str:
    if reward not in REWARD_KPIS:
        raise ParameterError(f"reward {reward!r}: choose one of {', '.join(REWARD_KPIS)}")
    return reward


def step_reward(reward: str, c: Committed, params: Params, orders: int) -> float:
    """The planned change of the reward's KPI that ``c`` commits."""
    if reward == "saving":
        return c.saving_m / 1000.0
    if reward == "response":
        return c.assigned / orders if orders else 0.0
    f_solo, f_pooled, pay = params.fare_solo_cny_per_km, params.fare_pooled_cny_per_km, params.driver_pay_cny_per_km
    return (
        (f_solo - pay) * c.vacant_solo_m
        + (f_pooled - pay) * c.joined_solo_m
        + (f_pooled - f_solo) * c.partner_solo_m
        + pay * c.saving_m
    ) / 1000.0
