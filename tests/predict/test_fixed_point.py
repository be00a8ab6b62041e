"""The fixed point (A1)-(A6): a state-level reference, invariants I1-I6, limiting cases L1-L8."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rpbench.data.road import NetworkTables
from rpbench.network import RoadNetwork
from rpbench.predict import OdRates, PredictConfig, build_prediction_model, solve_prediction_model
from rpbench.predict.fixed_point import PairSums, _cut, evaluate
from rpbench.scenarios.base import Params

from .conftest import make_instance
from .test_match_sets import line_network, model_list


# ---------------------------------------------------------------- reference: one state at a time
def reference_map(model, rho):
    """(A1)-(A6) written literally over taker *states* (no classes, no log-space), as in Appendix A."""
    sp, lam, cfg = model.space, model.rates.rate_per_s, model.config
    eta = np.zeros(sp.n_states)
    p_s = np.zeros(len(lam))
    for w in range(len(lam)):
        states, _ = model_list(model, w)
        running = lam[w]
        survive = 1.0
        for t in states:
            eta[t] += running  # η_t^{s(w)} = λ_w Π_{t' ≻ t} (1 - ρ_t')
            running *= 1.0 - rho[t]
            survive *= 1.0 - rho[t]
        p_s[w] = 1.0 - survive
    p_t = 1.0 - np.exp(-eta * sp.tau_s)
    lam_t = np.zeros(sp.n_states)
    for w in range(len(lam)):
        prev = lam[w] * (1.0 - p_s[w])
        for t in range(sp.od_state_off[w], sp.od_state_off[w + 1]):
            lam_t[t] = prev
            prev *= 1.0 - p_t[t]
    rho_next = np.where(eta > 0, lam_t * p_t / np.where(eta > 0, eta, 1.0), lam_t * sp.tau_s)
    return np.minimum(rho_next, cfg.rho_cap), eta, p_s, p_t, lam_t


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10_000), rate=st.sampled_from([2.0, 20.0, 200.0]), tau0=st.sampled_from([0.0, 60.0, 300.0]))
def test_vectorised_map_equals_reference(seed, rate, tau0):
    inst = make_instance(seed=seed, size=4, n_od=8, rate_per_h=rate, tau0_s=tau0)
    model = inst.model()
    rho = np.random.default_rng(seed).uniform(0, 0.6, model.space.n_states)
    ev = evaluate(model.system, rho)
    ref_next, eta, p_s, p_t, lam_t = reference_map(model, rho)
    np.testing.assert_allclose(ev.eta, eta, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(ev.p_seeker, p_s, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(ev.p_taker, p_t, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(ev.lam_taker, lam_t, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(ev.rho_next, ref_next, rtol=1e-9, atol=1e-13)


def test_evaluation_does_not_depend_on_the_thread_count():
    """The per-class and per-state passes run on one range of classes / ODs per thread."""
    from numba import get_num_threads, set_num_threads

    model = make_instance(seed=5, size=5, n_od=30, rate_per_h=60.0, tau0_s=60.0).model()
    rho = np.random.default_rng(5).uniform(0, 0.6, model.space.n_states)
    before = get_num_threads()
    try:
        runs = []
        for threads in (1, before):
            set_num_threads(threads)
            runs.append(evaluate(model.system, rho))
    finally:
        set_num_threads(before)
    for name in ("rho_next", "eta", "p_taker", "lam_taker", "log_not_taker", "class_log_q", "member_log_r"):
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name))


@pytest.mark.parametrize("sizes", [[], [0], [5], [3, 0, 0, 4, 1], [1] * 7, [0, 0, 9]])
@pytest.mark.parametrize("threads", [1, 2, 3, 8])
def test_cut_covers_every_group_once_in_order(sizes, threads):
    from numba import get_num_threads, set_num_threads

    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    before = get_num_threads()
    try:
        set_num_threads(min(threads, before))
        cut = _cut(offsets)
    finally:
        set_num_threads(before)
    assert cut[0] == 0 and cut[-1] == len(sizes)
    assert np.all(np.diff(cut) > 0) or len(sizes) == 0
    assert len(cut) - 1 <= max(1, min(threads, before))


# ---------------------------------------------------------------- invariants
@settings(max_examples=15, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    rate=st.sampled_from([1.0, 10.0, 60.0, 300.0]),
    priority=st.sampled_from(["net_saving", "pickup", "vehicle_distance", "authors_feng_grid"]),
)
def test_invariants_at_the_fixed_point(seed, rate, priority):
    inst = make_instance(seed=seed, size=5, n_od=14, rate_per_h=rate, priority=priority)
    model, pred = inst.solve()
    assert pred.info["converged"]
    ev = evaluate(model.system, pred.rho)
    sp, lam = model.space, model.rates.rate_per_s
    tol = 1e-8
    # I1: probabilities in [0,1]; λ_t non-increasing along paths; λ_t0 = λ_w (1 - p_s)
    for arr in (ev.p_seeker, ev.p_taker, ev.rho, pred.od.pairing_prob):
        assert np.all((arr >= 0) & (arr <= 1))
    first = sp.od_state_off[:-1][np.diff(sp.od_state_off) > 0]
    np.testing.assert_allclose(ev.lam_taker[first], (lam * (1 - ev.p_seeker))[sp.od[first]], rtol=1e-12)
    same_od = sp.od[1:] == sp.od[:-1]
    assert np.all(ev.lam_taker[1:][same_od] <= ev.lam_taker[:-1][same_od] * (1 + 1e-12))
    # I3: ρ' η = λ_t p_t (exact for the map output)
    np.testing.assert_allclose(ev.rho_next * ev.eta, ev.lam_taker * ev.p_taker, rtol=1e-10, atol=1e-18)
    # I4: pairs counted from both sides; I5: paired passengers = 2 x pairs
    seeker_pairs = np.sum(lam * ev.p_seeker)
    assert np.sum(ev.lam_taker * ev.p_taker) == pytest.approx(seeker_pairs, rel=tol, abs=1e-14)
    assert np.sum(lam * pred.od.pairing_prob) == pytest.approx(2 * seeker_pairs, rel=tol, abs=1e-14)
    # I6: P_w = p_s + (1 - p_s)(1 - Π(1 - p_t)) = 1 - λ_t,last (1 - p_t,last) / λ_w
    for w in range(len(lam)):
        s = slice(sp.od_state_off[w], sp.od_state_off[w + 1])
        expected = ev.p_seeker[w] + (1 - ev.p_seeker[w]) * (1 - np.prod(1 - ev.p_taker[s]))
        assert pred.od.pairing_prob[w] == pytest.approx(expected, abs=1e-12)
        if lam[w] > 0 and s.stop > s.start:
            last = s.stop - 1
            assert pred.od.pairing_prob[w] == pytest.approx(
                1 - ev.lam_taker[last] * (1 - ev.p_taker[last]) / lam[w], abs=1e-10
            )


def test_opportunity_rates_bounded_and_telescoping():  # I1 (η^s <= λ), I2
    model, pred = make_instance(seed=8, size=5, n_od=14, rate_per_h=30).solve()
    lam = model.rates.rate_per_s
    sums = PairSums.zeros(model.space.n_classes, len(lam))
    ev = evaluate(model.system, pred.rho, sums)
    # I1: each pair weight λ_s Π_{c' ≻ c} Q_c' is at most λ_s, so a class's total is at most Σ λ_s over its seekers
    cls, _, _, _ = model.matching.arrays()
    owner = np.repeat(np.arange(len(lam)), np.diff(model.matching.seeker_off))
    cap = np.bincount(cls, weights=lam[owner], minlength=model.space.n_classes)
    assert np.all(sums.by_class[:, 0] <= cap * (1 + 1e-12))
    np.testing.assert_array_equal(sums.by_class[:, 0], ev.class_h)
    # I2: Σ_{t in class} ρ_t η_t^s telescopes to λ_s P_{s,c} (1 - Q_c); summed over the list: λ p_s
    np.testing.assert_allclose(sums.by_seeker[:, 0], lam * ev.p_seeker, rtol=1e-10, atol=1e-16)
    # the same sum state by state, from the reference map
    _, eta_ref, _, _, _ = reference_map(model, pred.rho)
    assert np.sum(pred.rho * eta_ref) == pytest.approx(np.sum(lam * ev.p_seeker), rel=1e-10)


# ---------------------------------------------------------------- limiting cases
def test_l1_zero_demand():
    inst = make_instance(seed=1, size=5, n_od=10)
    inst.rates = inst.rates.scaled(0.0)
    model, pred = inst.solve()
    assert pred.info["iterations"] == 1 and pred.info["converged"]
    for arr in (
        pred.rho,
        pred.p_taker,
        pred.eta,
        pred.od.pairing_prob,
        pred.od.p_seeker,
        pred.od.e_vacant,
        pred.od.e_seeker,
        pred.od.e_taker,
    ):
        assert np.all(arr == 0)


def test_l2_no_feasible_pairs():
    # R̄ ~ 0 and distinct origins.  The origin state must be left out: a seeker can always join an
    # earlier order of its own OD still waiting at the same node (pk = 0, detours 0, E = l_w by G3).
    inst = make_instance(seed=2, size=6, n_od=12, max_pickup_m=1e-6)
    inst.rates = OdRates.from_arrays(np.arange(12), (np.arange(12) + 7) % 36, np.full(12, 1e-3), n_nodes=36)
    assert inst.model().matching.n_pairs == len(inst.rates)  # exactly the own-origin pairs
    model, pred = inst.solve(include_origin_state=False)
    assert model.matching.n_pairs == 0
    assert np.all(pred.od.p_seeker == 0) and np.all(pred.p_taker == 0) and np.all(pred.od.pairing_prob == 0)
    np.testing.assert_allclose(pred.rho, pred.lam_taker * model.space.tau_s)


def single_state_prediction(lam_tau: float, tau0: float = 120.0):
    """One OD on one link: only its origin state (k = 0) can pair with its own seekers (L3)."""
    net = line_network([800.0])
    rates = OdRates.from_arrays([0], [1], [lam_tau / tau0], n_nodes=2)
    model = build_prediction_model(net, rates, Params(), PredictConfig(tau0_s=tau0))
    assert model.matching.n_pairs == 1 and model.matching.seeker(0)[0].tolist() == [model.space.cls[0]]
    return solve_prediction_model(model)


def test_l3_closed_form():
    pred = single_state_prediction(1.0)
    c = 1 - np.exp(-1.0)
    assert pred.od.p_seeker[0] == pytest.approx(0.38730, abs=5e-6)
    assert pred.od.p_seeker[0] == pytest.approx(c / (1 + c), abs=1e-9)
    assert pred.rho[0] == pytest.approx(c / (1 + c), abs=1e-9)
    assert pred.p_taker[0] == pytest.approx(c, abs=1e-9)
    assert pred.od.pairing_prob[0] == pytest.approx(2 * c / (1 + c), abs=1e-9)
    assert pred.od.e_seeker[0] == pytest.approx(800.0) and pred.od.e_taker[0] == pytest.approx(800.0)


def test_l3_monotone_limits_and_slope():
    loads = [1e-4, 0.1, 1.0, 5.0, 50.0]
    preds = [single_state_prediction(x) for x in loads]
    p_s = [p.od.p_seeker[0] for p in preds]
    p_w = [p.od.pairing_prob[0] for p in preds]
    assert np.all(np.diff(p_s) > 0) and np.all(np.diff(p_w) > 0)
    assert p_w[-1] == pytest.approx(1.0, abs=1e-9) and p_s[-1] == pytest.approx(0.5, abs=1e-9)
    assert p_w[0] == pytest.approx(2 * loads[0], rel=1e-3)  # small-demand slope P ≈ 2λτ


def test_l4_time_unit_invariance():
    a = make_instance(seed=6, size=5, n_od=15, rate_per_h=20)
    b = make_instance(seed=6, size=5, n_od=15, rate_per_h=20, tau0_s=60.0)
    b.rates = b.rates.scaled(2.0)
    b.params = b.params.replace(speed_mps=a.params.speed_mps * 2)  # every τ halves, every λ doubles
    _, pa = a.solve()
    _, pb = b.solve()
    for x, y in ((pa.od.pairing_prob, pb.od.pairing_prob), (pa.od.p_seeker, pb.od.p_seeker), (pa.rho, pb.rho)):
        np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-12)


def scaled_network(net: RoadNetwork, factor: float) -> RoadNetwork:
    return RoadNetwork.from_tables(
        NetworkTables(
            name=f"{net.name} x{factor:g}",
            node_id=net.node_id,
            lon=net.lon,
            lat=net.lat,
            arc_from=net.node_id[net.arc_tail],
            arc_to=net.node_id[net.arc_head],
            arc_length_m=net.arc_length_m * factor,
            arc_link_id=net.arc_link_id,
            source="scaled",
        )
    )


def test_l5_distance_unit_invariance():
    a = make_instance(seed=7, size=5, n_od=15, rate_per_h=20)
    _, pa = a.solve()
    b = make_instance(seed=7, size=5, n_od=15, rate_per_h=20)
    b.network = scaled_network(a.network, 2.0)
    b.params = Params(max_pickup_m=3000.0, max_detour_m=3000.0, speed_mps=a.params.speed_mps * 2)
    _, pb = b.solve()
    np.testing.assert_allclose(pa.od.pairing_prob, pb.od.pairing_prob, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(2 * pa.od.e_vacant, pb.od.e_vacant, rtol=1e-6)
    np.testing.assert_allclose(2 * pa.od.e_seeker, pb.od.e_seeker, rtol=1e-6)
    np.testing.assert_allclose(2 * pa.od.ride_m, pb.od.ride_m, rtol=1e-6)


def test_l6_symmetry_and_relabelling():
    # Mirror-symmetric line (lengths read the same both ways) with mirrored ODs of equal rate, chosen
    # so that no seeker list holds a priority tie (ties are broken by class index, which a mirror
    # image does not preserve; docs/algorithms.md L6 asks for an invariant tie key).
    net = line_network([250.0, 610.0, 430.0, 610.0, 250.0])
    rates = OdRates.from_arrays([0, 5, 1, 4], [3, 2, 5, 0], [2e-3] * 4, n_nodes=6)
    pred = solve_prediction_model(build_prediction_model(net, rates, Params(), PredictConfig()))
    p = dict(
        zip(zip(rates.origin.tolist(), rates.destination.tolist(), strict=True), pred.od.pairing_prob, strict=True)
    )
    assert p[(0, 3)] == pytest.approx(p[(5, 2)], abs=1e-12) and p[(1, 5)] == pytest.approx(p[(4, 0)], abs=1e-12)
    e = dict(zip(zip(rates.origin.tolist(), rates.destination.tolist(), strict=True), pred.od.e_vacant, strict=True))
    assert e[(0, 3)] == pytest.approx(e[(5, 2)], rel=1e-9)
    # Relabelling the OD rows (input order) changes nothing.
    inst = make_instance(seed=9, size=5, n_od=12)
    perm = np.random.default_rng(0).permutation(len(inst.rates))
    r = inst.rates
    shuffled = OdRates.from_arrays(
        r.origin[perm], r.destination[perm], r.rate_per_s[perm], r.od_id[perm], n_nodes=inst.network.n_nodes
    )
    _, pa = inst.solve()
    inst.rates = shuffled
    _, pb = inst.solve()
    np.testing.assert_array_equal(pa.od.pairing_prob, pb.od.pairing_prob)


def test_l8_damping_does_not_change_the_solution():
    inst = make_instance(seed=10, size=5, n_od=16, rate_per_h=40)
    sols = [inst.solve(beta=beta)[1] for beta in (1.0, 0.5, 0.25)] + [inst.solve(accel="anderson")[1]]
    for s in sols:
        assert s.info["converged"]
        np.testing.assert_allclose(s.rho, sols[1].rho, atol=1e-8)
        np.testing.assert_allclose(s.od.pairing_prob, sols[1].od.pairing_prob, atol=1e-8)


def test_clipping_is_counted_and_poisson_mode_never_clips():
    # No pairs at all (R̄ ~ 0, no origin state): ρ = λ_t τ_t, far above 1 at this demand.
    inst = make_instance(seed=12, size=3, n_od=6, rate_per_h=300, max_pickup_m=1e-6, include_origin_state=False)
    _, little = inst.solve()
    assert little.info["clip_count"] > 0 and little.rho.max() <= inst.config.rho_cap
    _, poisson = inst.solve(rho_mode="poisson")
    assert poisson.info["clip_count"] == 0 and poisson.rho.max() < 1
