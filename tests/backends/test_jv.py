"""Sparse Jonker-Volgenant (lap.lapmod): exactness of the cost scaling."""

from __future__ import annotations

import numpy as np

from rpbench.backends import jv


def test_lapmod_scale_is_a_power_of_two_below_the_sentinel():
    for cost, n in ((5.0, 10), (1e7, 7000), (3e9, 100)):
        s = jv._lap_scale(cost, n)
        assert np.log2(s) == int(np.log2(s)) and n * cost * s <= jv.LAP_SAFE < jv.LAP_LARGE
