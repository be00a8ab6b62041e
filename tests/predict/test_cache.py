"""On-disk cache of predictions: hit on identical inputs, miss on any change."""

from __future__ import annotations

import numpy as np

from rpbench.files.paths import cache_dir
from rpbench.predict import predict
from rpbench.predict.cache import cache_key

from .conftest import make_instance


def test_cache_round_trip_and_keys():
    inst = make_instance(seed=31, size=5, n_od=12)
    first = predict(inst.network, inst.rates, inst.params, inst.config)
    assert not first.from_cache
    second = predict(inst.network, inst.rates, inst.params, inst.config)
    assert second.from_cache
    for a, b in (
        (first.od.pairing_prob, second.od.pairing_prob),
        (first.rho, second.rho),
        (first.od.e_vacant, second.od.e_vacant),
    ):
        np.testing.assert_array_equal(a, b)
    assert second.summary()["iterations"] == first.summary()["iterations"]
    assert str(cache_dir()).find("rpbench-cache") >= 0  # never the repository
    key = cache_key(inst.network, inst.rates, inst.params, inst.config)
    assert key != cache_key(inst.network, inst.rates.scaled(2.0), inst.params, inst.config)
    assert key != cache_key(inst.network, inst.rates, inst.params.replace(max_detour_m=999.0), inst.config)
    assert key != cache_key(inst.network, inst.rates, inst.params, inst.config.replace(tau0_s=60.0))
    assert key == cache_key(inst.network, inst.rates, inst.params.replace(alpha=2.0), inst.config)  # unused
