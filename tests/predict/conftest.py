"""Fixtures for the prediction-model tests: small seeded grid instances, the Haikou data when present."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from rpbench.predict import OdRates, PredictConfig, build_prediction_model, solve_prediction_model
from rpbench.scenarios.base import Params
from rpbench.scenarios.toy import grid_network


@pytest.fixture(autouse=True)
def _private_cache(request, tmp_path_factory, monkeypatch):
    """Toy tests cache into a session folder; Haikou tests (``data_dir``) keep the user cache, which
    holds the Haikou all-pairs table."""
    if "data_dir" not in request.fixturenames:
        monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path_factory.getbasetemp() / "rpbench-cache"))


@dataclass
class Instance:
    network: object
    rates: OdRates
    params: Params
    config: PredictConfig

    def model(self, **config_changes):
        cfg = self.config.replace(**config_changes) if config_changes else self.config
        return build_prediction_model(self.network, self.rates, self.params, cfg)

    def solve(self, **config_changes):
        model = self.model(**config_changes)
        return model, solve_prediction_model(model)


def make_instance(
    seed: int = 0,
    size: int = 5,
    n_od: int = 12,
    rate_per_h: float = 6.0,
    max_pickup_m: float = 1500.0,
    max_detour_m: float = 1500.0,
    grid_seed: int | None = None,
    **config,
) -> Instance:
    """A seeded grid city with ``n_od`` random OD pairs at random rates (mean ``rate_per_h`` per OD)."""
    net = grid_network(size, seed=seed if grid_seed is None else grid_seed)
    rng = np.random.default_rng(seed)
    n = net.n_nodes
    o = rng.integers(0, n, n_od)
    d = rng.integers(0, n, n_od)
    rate = rng.uniform(0.2, 1.8, n_od) * rate_per_h / 3600.0
    rates = OdRates.from_arrays(o, d, rate, np.arange(n_od), n_nodes=n, source=f"grid seed {seed}")
    return Instance(net, rates, Params(max_pickup_m=max_pickup_m, max_detour_m=max_detour_m), PredictConfig(**config))


@pytest.fixture
def instance() -> Instance:
    return make_instance()
