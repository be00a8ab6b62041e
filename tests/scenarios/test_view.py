"""The online view: what a dispatcher knows before the day, without the orders; the toy city's demand history."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rpbench.exceptions import LookaheadError, ParameterError, RpbenchError
from rpbench.scenarios import build_scenario
from rpbench.scenarios.base import Demand, History, OnlineView
from rpbench.scenarios.toy import HISTORY_DAYS, TOY_BASE_ORDERS, history_seeds

HINT = (
    "online strategies see orders only as they are revealed in RoundState; declare `clairvoyant = True` to read "
    "the future"
)


@pytest.fixture(scope="module")
def toy():
    return build_scenario("toy", sample=0.3, seed=4)


def test_the_view_carries_what_is_known_before_the_day(toy):
    view = toy.online_view("strategy 'x' (mod.X)")
    assert isinstance(view, OnlineView)
    for name in ("name", "label", "network", "fleet", "params", "seed", "horizon_s", "start_time", "synthetic"):
        assert getattr(view, name) is getattr(toy, name) or getattr(view, name) == getattr(toy, name), name
    assert view.demand is toy.demand and view.provenance == toy.provenance
    view.provenance["sample"] = 1.0  # a copy: the scenario's own is untouched
    assert toy.provenance["sample"] == 0.3
    with pytest.raises(dataclasses.FrozenInstanceError):
        view.seed = 5  # type: ignore[misc]


@pytest.mark.parametrize("name", ["orders", "summary"])
def test_reading_the_orders_is_one_clear_error_naming_the_reader(toy, name):
    view = toy.online_view("strategy 'peek' (mod.Peek)")
    with pytest.raises(LookaheadError) as info:
        getattr(view, name)
    text = str(info.value)
    assert text == f"strategy 'peek' (mod.Peek) read the scenario's {name} before they were revealed: {HINT}"
    assert isinstance(info.value, RpbenchError) and "\n" not in text
    assert str(view.refusal(name)) == text  # what code that checks isinstance first raises


def test_asking_whether_the_view_has_orders_says_no(toy):
    view = toy.online_view()
    assert not hasattr(view, "orders") and getattr(view, "orders", None) is None
    with pytest.raises(AttributeError) as info:
        view.ordrs  # type: ignore[attr-defined]  # noqa: B018
    assert not isinstance(info.value, LookaheadError)  # a typo is a plain AttributeError
    with pytest.raises(LookaheadError, match="^an online strategy read the scenario's orders"):
        view.orders  # noqa: B018


def test_the_toy_history_is_other_seeds_of_its_generator(toy):
    history = toy.demand.history
    assert toy.demand.table == "history" and isinstance(history, History)
    assert history.days == HISTORY_DAYS == 10
    assert len(history.origin) == HISTORY_DAYS * round(0.3 * TOY_BASE_ORDERS)
    assert toy.seed not in history_seeds(toy.seed)
    assert not set(history_seeds(4)) & set(history_seeds(5))  # each scenario seed has its own past days
    # the past days are the generator's own draws at those seeds: day k is the toy city of seed history_seeds[k]
    first = build_scenario("toy", sample=0.3, seed=history_seeds(4)[0]).orders
    n = len(first)
    assert np.array_equal(history.request_s[:n], first.request_s)
    assert np.array_equal(history.origin[:n], first.origin)
    assert np.array_equal(history.destination[:n], first.destination)
    # and not the day itself
    assert not np.array_equal(history.origin[:n], toy.orders.origin)


def test_the_history_does_not_depend_on_the_realisation():
    a, b = build_scenario("toy", sample=0.3, seed=4), build_scenario("toy", sample=0.3, seed=4)
    assert np.array_equal(a.demand.history.origin, b.demand.history.origin)
    other = build_scenario("toy", sample=0.3, seed=5)
    assert not np.array_equal(a.demand.history.origin, other.demand.history.origin)


def test_a_history_is_checked():
    with pytest.raises(ParameterError, match="table 'history' and a history go together"):
        Demand(table="history")
    with pytest.raises(ParameterError, match="at least one"):
        History(np.zeros(0), np.zeros(0, np.int32), np.zeros(0, np.int32), days=0, source="x")
