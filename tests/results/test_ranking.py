"""An evaluation's ranking: online runs, then clairvoyant ones apart, then offline references."""

from __future__ import annotations

import pandas as pd

from rpbench.results.ranking import misranked, ranked, ranking, run_groups

RECORDS = {
    "mb": {"kind": "simulation", "source": "mb", "options": {}, "clairvoyant": False},
    "hindsight": {"kind": "simulation", "source": "hindsight", "options": {}, "clairvoyant": False},  # flag edited
    "seer": {"kind": "simulation", "source": "pkg:Seer", "clairvoyant": True},  # a plug-in: its flag decides
    "bound": {"kind": "oracle"},
}


def board(**means: float) -> pd.DataFrame:
    return pd.DataFrame([{"run": r, "kpi": "total_saving_km", "mean": m} for r, m in means.items()])


def test_groups_come_from_the_records_and_the_strategy_classes():
    groups = run_groups([RECORDS], list(RECORDS))
    assert groups == {"mb": "online", "hindsight": "clairvoyant", "seer": "clairvoyant", "bound": "offline"}
    # one unit saying a run read the future is enough
    other = {**RECORDS, "mb": {**RECORDS["mb"], "clairvoyant": True}}
    assert run_groups([RECORDS, other], ["mb"]) == {"mb": "clairvoyant"}


def test_each_group_is_ranked_by_the_metric_after_the_earlier_groups():
    groups = {"mb": "online", "rtv": "online", "hindsight": "clairvoyant", "bound": "offline"}
    means = board(mb=5.0, rtv=6.0, hindsight=9.0, bound=20.0)
    runs = ["mb", "rtv", "hindsight", "bound", "np"]
    assert ranking(means, {**groups, "np": "online"}, "total_saving_km", runs) == [
        "rtv",
        "mb",
        "np",
        "hindsight",
        "bound",
    ]
    out = ranked(means, groups, "total_saving_km", runs[:4])
    assert out.set_index("run")["rank"].to_dict() == {"mb": 2, "rtv": 1, "hindsight": 3, "bound": 4}
    assert misranked(out) == []


def test_a_recorded_ranking_that_contradicts_itself_is_named():
    bad = pd.DataFrame(
        {
            "run": ["hindsight", "mb", "bound", "odd"],
            "group": ["clairvoyant", "online", "offline", "sideways"],
            "rank": [1, 2, 3, 4],
        }
    )
    problems = misranked(bad)
    assert "clairvoyant run hindsight is ranked 1, above the online run mb (ranked 2)" in problems
    assert any("group 'sideways'" in p for p in problems)
