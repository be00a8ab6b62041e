"""Property tests: random sparse models of each structure, every installed preset, exact agreement.

On tiny models every preset must return a feasible solution whose objective
equals the exhaustive optimum (values are integral: exact equality); on
larger seeded synthetic models all presets must agree with each other.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rpbench.backends import get_backend
from rpbench.backends.presets import load_preset, preset_names
from rpbench.bench import synthetic
from rpbench.model import AssignmentModel, PairingModel, Status, TripPackingModel

from .brute import MAX_COLS, brute_force

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)


def installed():
    out = []
    for name in preset_names():
        preset = load_preset(name)
        if preset.is_installed():
            out.append((name, get_backend(preset.backend), preset.options))
    return out


INSTALLED = installed()
VALUES = st.integers(-20, 20)


@st.composite
def assignments(draw):
    P, V = draw(st.integers(1, 4)), draw(st.integers(0, 4))
    cols = [(p, v) for p in range(P) for v in range(V) if draw(st.booleans())]
    waits = [p for p in range(P) if draw(st.integers(0, 3)) > 0 or not any(c[0] == p for c in cols)]
    cols = (cols + [(p, -1) for p in waits])[:MAX_COLS]
    for p in range(P):  # truncation must leave every passenger an option
        if not any(c[0] == p for c in cols):
            cols[-1 if cols[-1][0] != p else 0] = (p, -1)
    cols = sorted(set(cols))
    values = draw(st.lists(VALUES, min_size=len(cols), max_size=len(cols)))
    return AssignmentModel(P, V, [c[0] for c in cols], [c[1] for c in cols], values)


@st.composite
def pairings(draw):
    n = draw(st.integers(0, 7))
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n) if draw(st.integers(0, 2)) == 0][:MAX_COLS]
    values = draw(st.lists(VALUES, min_size=len(pairs), max_size=len(pairs)))
    objective = draw(st.sampled_from(["weight", "cardinality_then_weight"]))
    return PairingModel(n, [p[0] for p in pairs], [p[1] for p in pairs], values, objective=objective)


@st.composite
def packings(draw):
    R, V = draw(st.integers(1, 4)), draw(st.integers(1, 3))
    singles = [(v, r, -1) for r in range(R) for v in range(V) if draw(st.booleans())]
    doubles = [(v, a, b) for a in range(R) for b in range(a + 1, R) for v in range(V) if draw(st.integers(0, 2)) == 0]
    cols = (singles + doubles)[:MAX_COLS]
    values = draw(st.lists(VALUES, min_size=len(cols), max_size=len(cols)))
    return TripPackingModel(R, V, [c[0] for c in cols], [c[1] for c in cols], [c[2] for c in cols], values)


def assert_all_presets_equal_brute_force(model):
    best = brute_force(model)
    for name, backend, options in INSTALLED:
        sol = backend.solve(model, options)
        if best is None:
            assert sol.status is Status.INFEASIBLE, name
            continue
        assert sol.status is Status.OPTIMAL, (name, sol.message)
        assert model.violations(sol.chosen) == [], name
        assert sol.objective == best[0], (name, sol.objective, best)
        if getattr(model, "objective", "") == "cardinality_then_weight":
            assert sol.cardinality == best[1], name


@pytest.mark.slow
@settings(max_examples=25, **SETTINGS)
@given(assignments())
def test_assignment_every_preset_equals_brute_force(model):
    assert_all_presets_equal_brute_force(model)


@pytest.mark.slow
@settings(max_examples=25, **SETTINGS)
@given(pairings())
def test_pairing_every_preset_equals_brute_force(model):
    assert_all_presets_equal_brute_force(model)


@pytest.mark.slow
@settings(max_examples=20, **SETTINGS)
@given(packings())
def test_trip_packing_every_preset_equals_brute_force(model):
    assert_all_presets_equal_brute_force(model)


@pytest.mark.parametrize(
    "make",
    [
        lambda seed: synthetic.assignment(12, 40, seed=seed),
        lambda seed: synthetic.assignment(30, 25, seed=seed, wait=seed % 2 == 0, density=(0.5, 0.9)),
        lambda seed: synthetic.pairing(60, partners=8, seed=seed),
        lambda seed: synthetic.pairing(60, partners=8, seed=seed, objective="cardinality_then_weight"),
        lambda seed: synthetic.trip_packing(20, 10, seed=seed),
    ],
    ids=["assignment", "assignment-dense-mandatory", "pairing", "pairing-oracle2", "trip-packing"],
)
@pytest.mark.parametrize("seed", [0, 1])
def test_presets_agree_on_synthetic_models(make, seed):
    model = make(seed)
    results = {}
    for name, backend, options in INSTALLED:
        sol = backend.solve(model, options)
        assert model.violations(sol.chosen) == [] or sol.status is Status.INFEASIBLE, name
        results[name] = (sol.status, sol.objective, sol.cardinality)
    assert len(set(results.values())) == 1, results


@settings(max_examples=40, **SETTINGS)
@given(st.one_of(assignments(), pairings(), packings()))
def test_special_purpose_backends_equal_brute_force(model):
    best = brute_force(model)
    for name in ("scipy", "matching"):
        sol = get_backend(name).solve(model, load_preset(name).options)
        if best is None:
            assert sol.status is Status.INFEASIBLE
        else:
            assert (sol.status, sol.objective) == (Status.OPTIMAL, best[0]), name


def test_random_models_really_vary():
    # guard against a strategy that silently generates only trivial models
    rng = np.random.default_rng(0)
    sizes = [synthetic.pairing(int(n), partners=6, seed=int(s)).n_cols for n, s in rng.integers(10, 40, (5, 2))]
    assert len(set(sizes)) > 1
