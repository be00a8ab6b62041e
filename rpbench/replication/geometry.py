"""A second passenger joining a first one under the authors' rules: pick-up, rides, shared distance, saving.

The first passenger rides alone (``lead_m``) until the vehicle reaches the
second passenger's origin; from there the drop-off order is first-on-first-off
or first-on-last-off, whichever is shorter (Eqs. (5)-(6); ties as the
``pickup_from_first_origin`` switch says).  MB's and FL's matching fills one
:class:`TakerGeometry` per taker with arrays over the candidate second
passengers; RTV's pair edges and the commit of a match fill one with floats.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

Metres = TypeVar("Metres", float, np.ndarray)


@dataclass(frozen=True)
class TakerGeometry(Generic[Metres]):
    """One pair's (or, vectorised, each candidate pair's) geometry, distances in metres."""

    pickup_m: Metres  # the pick-up weight of the match
    lead_m: Metres  # the first passenger's ride up to the second origin (the second pick-up in the ledger)
    fofo: bool | np.ndarray  # first-on-first-off (else first-on-last-off)
    first_ride_m: Metres  # the first passenger's in-vehicle distance
    second_ride_m: Metres  # the second passenger's in-vehicle distance
    shared_m: Metres  # the distance both ride together
    saving_m: Metres  # e(v_p', p) of Eq. (5): both solo rides less the pooled route
    first_detour_m: Metres
    second_detour_m: Metres
    rest_m: Metres  # the route from the second origin to the last drop-off

    def first(self: TakerGeometry[np.ndarray]) -> TakerGeometry[float]:
        """The first candidate's geometry as floats."""
        return TakerGeometry(
            pickup_m=_first(self.pickup_m),
            lead_m=_first(self.lead_m),
            fofo=bool(np.ravel(self.fofo)[0]),
            first_ride_m=_first(self.first_ride_m),
            second_ride_m=_first(self.second_ride_m),
            shared_m=_first(self.shared_m),
            saving_m=_first(self.saving_m),
            first_detour_m=_first(self.first_detour_m),
            second_detour_m=_first(self.second_detour_m),
            rest_m=_first(self.rest_m),
        )


def _first(values: np.ndarray) -> float:
    return float(np.ravel(values)[0])
