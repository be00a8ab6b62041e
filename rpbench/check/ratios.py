"""``competitive-ratio``: the rows of kpis.csv derived from the other runs, recomputed (docs/simulator.md).

Each simulated run's competitive ratio against the proven upper bound U (``competitive_ratio_bound``) and
against the best known schedule LB (``competitive_ratio_best_known``), and its saving / Oracle-1
(``saving_over_oracle1``); LB, the largest saving among the folder's simulated runs as the checker recomputes
them from their event logs (each a schedule the other checks verify, so OPT >= LB); the bound's rows
``best_known_saving_km`` and ``bound_over_best_known`` (U / LB); and meta.json's record of the run that gave
LB.  U and Oracle-1's saving are the reported ones, which their own runs' checks verify.  The quotients are
written out here, apart from :mod:`rpbench.results.ratios`.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping

import pandas as pd

from rpbench.check.core import RunCheck, as_number, same, show
from rpbench.check.folder import Folder, bound_km
from rpbench.results.layout import KPIS, META
from rpbench.results.ratios import BEST_KNOWN_FIELD, BRACKET_KPIS, RATIO_KPIS

RATIO_CHECK = "competitive-ratio"
#: The offline run whose saving ``saving_over_oracle1`` divides by.
ORACLE1 = "oracle1"


def _quotient(numerator: float, denominator: float | None) -> float:
    return numerator / denominator if denominator is not None and denominator > 0 else math.nan


def check_ratios(fc: RunCheck, f: Folder, runs: list[RunCheck], savings: Mapping[str, float | None]) -> None:
    """The derived rows of every simulated run (``savings``: each one's saving as recomputed here, None when
    its checks could not recompute it), of the bound, and meta.json's best known schedule."""
    by_name = {rc.run: rc for rc in runs}
    reported = set(f.kpis["kpi"])
    older = BEST_KNOWN_FIELD not in f.meta and not {"competitive_ratio_best_known", *BRACKET_KPIS} & reported
    if older:
        fc.skip(RATIO_CHECK, f"the folder was written before rpbench recorded the best known schedule: only the ratios "
                       f"its {KPIS} reports are compared")  # fmt: skip
    unknown = sorted(run for run, saving in savings.items() if saving is None)
    known = {run: float(saving) for run, saving in savings.items() if saving is not None}
    lb_run = max(known, key=known.__getitem__) if known and not unknown else None
    lb = known[lb_run] if lb_run is not None else None
    bound = bound_km(f)
    oracle1 = _oracle1_saving(f)
    for run, saving in known.items():
        expected: dict[str, float] = {}
        if bound is not None:
            expected["competitive_ratio_bound"] = _quotient(saving, bound)
        if lb is not None:
            expected["competitive_ratio_best_known"] = _quotient(saving, lb)
        if oracle1 is not None:
            expected["saving_over_oracle1"] = _quotient(saving, oracle1)
        # a folder of an older rpbench always reported the ratio against the bound, and no other
        required = ["competitive_ratio_bound"] if older else list(expected)
        _compare(by_name[run], f.reported(run), expected, RATIO_KPIS, required)
    if older:
        return
    if unknown:
        fc.skip(
            RATIO_CHECK, f"LB cannot be recomputed: the saving of {', '.join(unknown)} could not be (see its checks)"
        )
        return
    _check_record(fc, f.meta.get(BEST_KNOWN_FIELD), lb_run, lb, known)
    name = _bound_run(f)
    if name is not None and bound is not None and name in by_name:
        expected = {} if lb is None else {"best_known_saving_km": lb, "bound_over_best_known": _quotient(bound, lb)}
        _compare(by_name[name], f.reported(name), expected, BRACKET_KPIS, list(expected))


def _compare(
    rc: RunCheck, rows: pd.DataFrame, expected: dict[str, float], keys: Collection[str], required: Collection[str]
) -> None:
    """The rows ``keys`` of one run: each expected one equal, each ``required`` one reported; no other."""
    found = {k: as_number(v) for k, v in zip(rows["kpi"], rows["value"], strict=True) if k in keys}
    for key, value in expected.items():
        number = found.get(key)
        if key not in found:
            if key in required:
                rc.fail(RATIO_CHECK, f"KPI {key} is not reported in {KPIS}")
        elif number is None or not same(number, value):
            rc.fail(RATIO_CHECK, f"KPI {key}: reported {show(number)}, recomputed {value!r}")
    for key in sorted(set(found) - set(expected)):
        rc.fail(RATIO_CHECK, f"KPI {key} is reported, but the folder has no run it divides by or derives from")
    rc.checked["ratios"] = rc.checked.get("ratios", 0) + len(expected)


def _check_record(fc: RunCheck, record, lb_run: str | None, lb: float | None, known: dict[str, float]) -> None:
    """meta.json's ``best_known``: the run with the largest recomputed saving (any of equals) and LB."""
    if lb_run is None or lb is None:
        if record is not None:
            fc.fail(RATIO_CHECK, f"{META} records a best known schedule, but the folder has no simulated run")
        return
    if not isinstance(record, Mapping) or not isinstance(record.get("run"), str):
        fc.fail(RATIO_CHECK, f"{META}'s {BEST_KNOWN_FIELD} is {record!r}, not the run that gave LB and its saving")
        return
    run, saving = record["run"], as_number(record.get("saving_km"))
    if run not in known or not same(known[run], lb):
        fc.fail(
            RATIO_CHECK,
            f"{META} names {run!r} as the best known schedule; the largest recomputed saving is "
            f"{lb!r} km, of {lb_run!r}",
        )
    if saving is None or not same(saving, lb):
        fc.fail(RATIO_CHECK, f"{META}'s best known saving is {show(record.get('saving_km'))} km, recomputed {lb!r} km")
    fc.checked["best_known"] = 1


def _bound_run(f: Folder) -> str | None:
    """The folder's bound run (its rules' window), None without one."""
    return next(
        (
            n
            for n, r in f.meta["runs"].items()
            if r.get("kind") == "oracle" and r.get("rules", {}).get("window") == "bound"
        ),
        None,
    )


def _oracle1_saving(f: Folder) -> float | None:
    """Oracle-1's reported saving (its own checks recompute it), None without an Oracle-1 run."""
    if f.meta["runs"].get(ORACLE1, {}).get("kind") != "oracle":
        return None
    rows = f.reported(ORACLE1)
    value = rows.loc[rows["kpi"] == "total_saving_km", "value"]
    number = as_number(value.iloc[0]) if len(value) else None
    return math.nan if number is None else number
