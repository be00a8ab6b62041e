"""Synthetic model generators: seeded, shaped like the real models, validated."""

from __future__ import annotations

import numpy as np
import pytest

from rpbench.bench import synthetic
from rpbench.exceptions import ParameterError
from rpbench.model import Structure


def same(m1, m2) -> bool:
    arrays = [f for f in vars(m1) if isinstance(getattr(m1, f), np.ndarray)]
    return all(np.array_equal(getattr(m1, f), getattr(m2, f)) for f in arrays)


def test_generators_are_pure_functions_of_their_seed():
    for make in (
        lambda s: synthetic.assignment(20, 60, seed=s),
        lambda s: synthetic.pairing(300, seed=s),
        lambda s: synthetic.trip_packing(40, 20, seed=s),
    ):
        assert same(make(3), make(3)) and not same(make(3), make(4))


def test_assignment_shape():
    m = synthetic.assignment(100, 500, seed=0)
    wait = m.col_vehicle < 0
    per_passenger = np.bincount(m.col_passenger[~wait], minlength=100) / 500
    assert per_passenger.min() >= 0.05 - 1e-9 and per_passenger.max() <= 0.20 + 1e-9
    assert np.array_equal(np.sort(m.col_passenger[wait]), np.arange(100))  # one wait option each
    assert (m.values[~wait] <= 4_000_000).all() and m.unit_m == 1e-3  # -pickup (+ saving) in mm
    no_wait = synthetic.assignment(5, 10, wait=False)
    assert (no_wait.col_vehicle >= 0).all()


def test_pairing_shape():
    m = synthetic.pairing(2000, seed=0)
    degree = np.bincount(np.r_[m.col_a, m.col_b], minlength=2000)
    assert 15 <= degree.mean() <= 35 and (m.values > 0).all() and m.objective == "weight"
    m2 = synthetic.pairing(2000, seed=0, objective="cardinality_then_weight")
    assert m2.n_cols > m.n_cols and (m2.values <= 0).any()  # Oracle-2 keeps every feasible pair
    assert (m.col_b - m.col_a).max() <= 32 * 15  # partners are near in time


def test_trip_packing_shape():
    m = synthetic.trip_packing(200, 100, seed=0)
    pooled = m.col_request2 >= 0
    assert pooled.any() and (~pooled).any() and m.structure is Structure.TRIP_PACKING


def test_suites_and_bad_parameters():
    names = [m.name for m in synthetic.suite("tiny", objectives=("weight", "cardinality_then_weight"))]
    assert len(names) == 4 and len(set(names)) == 4
    with pytest.raises(ParameterError, match="size set 'huge' unknown"):
        synthetic.suite("huge")
    with pytest.raises(ParameterError, match="seed"):
        synthetic.pairing(10, seed=-1)
    with pytest.raises(ParameterError, match="n_orders"):
        synthetic.pairing(2.5)
    with pytest.raises(ParameterError, match="density"):
        synthetic.assignment(3, 3, density=(0.5, 0.1))
    with pytest.raises(ParameterError, match="objective"):
        synthetic.pairing(10, objective="max")


def test_empty_sizes_are_valid_models():
    assert synthetic.assignment(0, 5).n_cols == 0 and synthetic.pairing(0).n_cols == 0
    assert synthetic.trip_packing(0, 3).n_cols == 0 and synthetic.assignment(3, 0).n_cols == 3
