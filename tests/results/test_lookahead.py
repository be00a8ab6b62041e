"""Whether a built-in strategy reads the future under a run's recorded options, from its class alone."""

from __future__ import annotations

from rpbench.results.lookahead import declared_clairvoyant, reads_future


def test_the_class_under_the_recorded_options_decides():
    sim = {"kind": "simulation"}
    assert declared_clairvoyant("hindsight", {**sim, "source": "hindsight", "options": {}}) is True
    assert declared_clairvoyant("fl", {**sim, "source": "fl", "options": {"rates": "scenario"}}) is True
    assert declared_clairvoyant("fl", {**sim, "source": "fl", "options": {"rates": "history"}}) is False
    # a variant runs its strategy's class: its source
    assert declared_clairvoyant("fl@rates=scenario", {**sim, "source": "fl", "options": {"rates": "scenario"}})


def test_what_the_class_cannot_say_rests_on_the_flag():
    plugin = {"kind": "simulation", "source": "pkg.rules:Seer", "clairvoyant": True}
    assert declared_clairvoyant("seer", plugin) is None and reads_future("seer", plugin)
    unknown = {"kind": "simulation", "source": "fl", "options": {"no_such_option": 1}}  # another version's
    assert declared_clairvoyant("fl", unknown) is None and not reads_future("fl", unknown)
    assert declared_clairvoyant("bound", {"kind": "oracle"}) is None
