"""Every number a reader is shown, recomputed: ``kpi`` (kpis.csv), ``decision-budget`` (the ``over_budget``
flags of rounds.csv.gz), ``hourly`` (hourly.csv) and ``report`` (the KPI tables of report.md).

The KPIs are recomputed from the per-order table of :func:`.events.check_events` (event times, and
odometers read at the matched trajectory entries), by code of their own: the occupied distance is the union
of the passengers' odometer intervals per vehicle, the shared distance the overlap of a pair's intervals.
:mod:`rpbench.results.metrics` (what the run used) steps through pick-up/drop-off events instead.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from rpbench import results
from rpbench.check.core import UNVERIFIED_KPIS, RunCheck, as_number, same, show
from rpbench.check.folder import Folder
from rpbench.exceptions import ResultsError, RpbenchError, one_line
from rpbench.report.comparison import BEST_RUN_HERE_LABEL, fmt, report_markdown
from rpbench.results.layout import HOURLY, KPIS, META, REPORT, ROUNDS
from rpbench.results.metrics import BOUND_MATCHING_KPIS, DECISION_KPIS, KPI_LABELS
from rpbench.results.ratios import BOUND, BRACKET_PREFIX, DENOMINATORS
from rpbench.results.read import load_kpis
from rpbench.scenarios.base import Params


# ------------------------------------------------------------------------- KPIs
def _union_length(vehicle: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """Total length of the union of the intervals [start, end] of each vehicle (odometer readings)."""
    keep = np.isfinite(start) & np.isfinite(end)
    vehicle, start, end = vehicle[keep], start[keep], end[keep]
    if not len(vehicle):
        return 0.0
    srt = np.lexsort((start, vehicle))
    vehicle, start, end = vehicle[srt], start[srt], end[srt]
    reach = pd.Series(end).groupby(vehicle).cummax().to_numpy()  # furthest end so far, per vehicle
    before = np.r_[-np.inf, reach[:-1]]
    before[np.r_[True, vehicle[1:] != vehicle[:-1]]] = -np.inf
    return float(np.maximum(0.0, end - np.maximum(start, before)).sum())


def _passenger_facts(tab: pd.DataFrame, solo: np.ndarray) -> dict[str, np.ndarray]:
    """Per order: served, pooled, partner, ride, shared distance, detour, pick-up distance, response and
    pick-up times (read off the per-order table)."""
    served = tab["served"].to_numpy()
    partner = tab["partner"].to_numpy()
    pooled = served & (partner >= 0)
    p = np.maximum(partner, 0)
    pick, drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    ride = drop - pick
    shared = np.where(pooled, np.maximum(0.0, np.minimum(drop, drop[p]) - np.maximum(pick, pick[p])), 0.0)
    return {
        "served": served,
        "pooled": pooled,
        "partner": partner,
        "ride": ride,
        "shared": shared,
        "detour": ride - solo,
        "pickup_m": pick - tab["odo_start"].to_numpy(),
        "response_s": (tab["assign_s"] - tab["request_s"]).to_numpy(),
        "pickup_s": (tab["pickup_s"] - tab["assign_s"]).to_numpy(),
    }


def _mean(x: np.ndarray, mask: np.ndarray) -> float:
    return float(x[mask].mean()) if mask.any() else float("nan")


def simulation_kpis(tab: pd.DataFrame, solo: np.ndarray, params: Params) -> dict:
    """docs/simulator.md's KPI definitions, from the event log and the odometers (the ratios, derived from the
    other runs too, are :mod:`.ratios`')."""
    x = _passenger_facts(tab, solo)
    served, pooled = x["served"], x["pooled"]
    n, n_served, n_pooled = len(tab), int(served.sum()), int(pooled.sum())
    occupied_km = (
        _union_length(
            tab["vehicle"].to_numpy()[served], tab["odo_pick"].to_numpy()[served], tab["odo_drop"].to_numpy()[served]
        )
        / 1000.0
    )
    solo_km = float(solo[served].sum()) / 1000.0
    fare = np.where(pooled, params.fare_pooled_cny_per_km, params.fare_solo_cny_per_km)
    revenue = float((fare * solo)[served].sum()) / 1000.0
    alt = params.fare_solo_cny_per_km * (x["ride"] - x["shared"]) + params.fare_pooled_cny_per_km * x["shared"]
    pay = params.driver_pay_cny_per_km * occupied_km
    return {
        "orders": n,
        "served": n_served,
        "cancelled": int(tab["cancelled"].sum()),
        "pooled_passengers": n_pooled,
        "pairs": n_pooled // 2,
        "response_rate": n_served / n if n else float("nan"),
        "pairing_ratio": n_pooled / n_served if n_served else float("nan"),
        "pairing_ratio_of_orders": n_pooled / n if n else float("nan"),
        "platform_profit_cny": revenue - pay,
        "platform_profit_alt_cny": float(alt[served].sum()) / 1000.0 - pay,
        "avg_response_time_s": _mean(x["response_s"], served),
        "avg_pickup_time_s": _mean(x["pickup_s"], served),
        "avg_pickup_distance_m": _mean(x["pickup_m"], served),
        "avg_detour_m": _mean(x["detour"], pooled),
        "avg_shared_m": _mean(x["shared"], pooled),
        "total_occupied_km": occupied_km,
        "total_solo_served_km": solo_km,
        # Σ over pairs of l_A + l_B - L: without a pair exactly 0, not the float noise of two equal sums (a
        # ratio over LB = 0 is undefined, over 1e-13 it would be 1)
        "total_saving_km": solo_km - occupied_km if n_pooled else 0.0,
    }


def compare_kpis(
    rc: RunCheck, kind: str, recomputed: dict, reported: pd.DataFrame, claims: dict[str, str | None] | None = None
) -> None:
    """Every recomputed KPI is reported and equal; every reported one is recomputed, a solver claim that
    passed its consistency test (``claims``: key -> failure message or None) or listed as unverifiable."""
    seen: dict[str, float | None] = {}
    for key, value in zip(reported["kpi"].to_numpy(), reported["value"].to_numpy(), strict=True):
        if key in seen:
            rc.fail("kpi", f"KPI {key} is reported twice")
        seen[key] = as_number(value)
        if seen[key] is None:
            rc.fail("kpi", f"KPI {key}: reported {value!r} is not a number")
    for key, value in recomputed.items():
        reported_value = seen.get(key)
        if key not in seen:
            rc.fail("kpi", f"KPI {key} is not reported in {KPIS}")
        elif reported_value is not None and not same(reported_value, float(value)):
            rc.fail("kpi", f"KPI {key}: reported {reported_value!r}, recomputed {float(value)!r}")
    for message in (claims or {}).values():
        if message is not None:
            rc.fail("kpi", message)
    allowed = set(recomputed) | set(claims or {}) | UNVERIFIED_KPIS[kind]
    for key in sorted(set(seen) - allowed):
        rc.fail("kpi", f"KPI {key} in {KPIS} is not a KPI rpbench reports for a {kind} run")
    for key in sorted(set(seen) & UNVERIFIED_KPIS[kind]):  # timings and sizes: plausible at least
        number = seen[key]
        if number is not None and not (np.isnan(number) or 0 <= number < np.inf):
            rc.fail("kpi", f"KPI {key}: reported {number!r}, not a time or size (finite, >= 0)")
    rc.checked["kpis"] = len(recomputed)


# ----------------------------------------------------------------------- decision time
_DECISION_COLUMNS = ("strategy_build_s", "solver_build_s", "solve_s", "extract_s")


def decision_expected(rc: RunCheck, f: Folder, run: str, reported: pd.DataFrame) -> dict:
    """A run's decision-time KPIs from the folder's per-round table (median and 95th percentile by linear
    interpolation between order statistics, the maximum, rounds slower than Δt); nothing, and said so, for a
    folder written before rpbench reported them."""
    if not set(DECISION_KPIS) & set(reported["kpi"]):
        rc.skip("kpi", "no decision-time KPIs: the folder was written before rpbench reported them")
        return {}
    path = f.path / ROUNDS
    if not path.is_file():
        rc.fail("kpi", f"decision-time KPIs are reported but the folder has no {ROUNDS} to recompute them from")
        return {}
    rounds = results.read_csv(path)
    mine = rounds[rounds["run"] == run]
    if mine.empty:
        return dict.fromkeys(DECISION_KPIS[:3], float("nan")) | {"rounds_over_dt": 0.0}
    ordered = np.sort(_decision_totals(mine))

    def at(q: float) -> float:  # the linear-interpolation quantile, spelled out
        pos = q * (len(ordered) - 1)
        low = int(np.floor(pos))
        high = min(low + 1, len(ordered) - 1)
        return float(ordered[low] + (ordered[high] - ordered[low]) * (pos - low))

    return {
        "decision_p50_s": at(0.5),
        "decision_p95_s": at(0.95),
        "decision_max_s": float(ordered[-1]),
        "rounds_over_dt": float(np.count_nonzero(ordered > f.params.dt_s)),
    }


def _decision_totals(rounds: pd.DataFrame) -> np.ndarray:
    """Each round's decision time: its parts added in :data:`_DECISION_COLUMNS` order."""
    total = np.zeros(len(rounds))
    for column in _DECISION_COLUMNS:
        total = total + rounds[column].to_numpy(dtype=float)
    return total


#: The KPI and the rounds.csv.gz column of a folder run with a decision budget (meta.json's decision_budget_s).
BUDGET_KPI, BUDGET_COLUMN, BUDGET_FIELD = "rounds_over_budget", "over_budget", "decision_budget_s"


def budget_expected(rc: RunCheck, f: Folder, run: str, reported: pd.DataFrame) -> tuple[dict, dict[str, str | None]]:
    """A run's ``rounds_over_budget`` recounted from its rounds' decision times and the budget meta.json
    records, and its rounds' ``over_budget`` flags checked against them (``decision-budget``); returns the
    recomputed KPI and the claims :func:`compare_kpis` allows.  Without a recorded budget there must be
    neither the KPI nor the column."""
    budget = f.meta.get(BUDGET_FIELD)
    path = f.path / ROUNDS
    rounds = results.read_csv(path) if path.is_file() else None
    mine = rounds[rounds["run"] == run] if rounds is not None else None
    if budget is None:
        if rounds is not None and BUDGET_COLUMN in rounds.columns and mine is not None and len(mine):
            rc.fail("decision-budget", f"{ROUNDS} has an {BUDGET_COLUMN} column but {META} records no decision budget")
        if BUDGET_KPI in set(reported["kpi"]):
            return {}, {BUDGET_KPI: f"KPI {BUDGET_KPI} is reported but {META} records no decision budget"}
        return {}, {}
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not 0 < budget < np.inf:
        rc.fail("decision-budget", f"{META}'s {BUDGET_FIELD} {budget!r} is not a finite number of seconds > 0")
        return {}, {BUDGET_KPI: None}  # not recountable: the failure above says why
    if mine is None:
        rc.fail("decision-budget", f"{META} records a decision budget but the folder has no {ROUNDS}")
        return {}, {BUDGET_KPI: None}
    totals = _decision_totals(mine)
    over = totals > budget
    if BUDGET_COLUMN not in mine.columns:
        rc.fail("decision-budget", f"{ROUNDS} lacks the {BUDGET_COLUMN} column of the {budget:g} s budget")
    else:
        flags = mine[BUDGET_COLUMN].map({True: True, False: False, "True": True, "False": False})
        text = flags.isna().to_numpy()
        wrong = np.flatnonzero(~text & (flags.fillna(False).to_numpy(dtype=bool) != over))
        if text.any():
            first = mine[BUDGET_COLUMN].to_numpy()[np.flatnonzero(text)[0]]
            rc.fail("decision-budget", f"{ROUNDS}: {BUDGET_COLUMN} holds {show(first)}, not True/False")
        if len(wrong):
            k = wrong[0]
            rc.fail(
                "decision-budget",
                f"{len(wrong)} round(s) of {ROUNDS} flagged {BUDGET_COLUMN} against their decision time and the "
                f"{budget:g} s budget, e.g. round {mine['round'].to_numpy()[k]}: {BUDGET_COLUMN} "
                f"{bool(flags.to_numpy()[k])}, decision {float(totals[k])!r} s",
            )
        rc.checked["budget_rounds"] = len(mine)
    return {BUDGET_KPI: float(np.count_nonzero(over))}, {}


# ----------------------------------------------------------------------- hourly
def hourly_expected(tab: pd.DataFrame, solo: np.ndarray) -> pd.DataFrame:
    """Per request hour (metrics.hourly's definitions): a pair's saving, l_A + l_B - (last drop-off odometer
    - first pick-up odometer), counts in the hour of its earlier request."""
    x = _passenger_facts(tab, solo)
    request = tab["request_s"].to_numpy()
    hour = np.floor(request / 3600.0).astype(np.int64)
    served, pooled, partner = x["served"], x["pooled"], x["partner"]
    lead = np.flatnonzero(pooled & (partner > np.arange(len(tab))))
    b = partner[lead]
    pick, drop = tab["odo_pick"].to_numpy(), tab["odo_drop"].to_numpy()
    saving = solo[lead] + solo[b] - (np.maximum(drop[lead], drop[b]) - np.minimum(pick[lead], pick[b]))
    pair_hour = np.floor(np.minimum(request[lead], request[b]) / 3600.0).astype(np.int64)
    frame = pd.DataFrame(
        {
            "hour": hour,
            "served": served,
            "pooled": pooled,
            "detour": np.where(pooled, x["detour"], np.nan),
            "shared": np.where(pooled, x["shared"], np.nan),
            "pickup_m": np.where(served, x["pickup_m"], np.nan),
            "pickup_s": np.where(served, x["pickup_s"], np.nan),
        }
    )
    g = frame.groupby("hour")
    n_served = g["served"].sum()
    out = pd.DataFrame(
        {
            "orders": g.size(),
            "response_rate": g["served"].mean(),
            "pairing_ratio": g["pooled"].sum() / n_served.where(n_served > 0),
            "avg_detour_m": g["detour"].mean(),
            "avg_shared_m": g["shared"].mean(),
            "total_saving_km": pd.Series(saving / 1000.0).groupby(pair_hour).sum(),
            "avg_pickup_m": g["pickup_m"].mean(),
            "avg_pickup_time_s": g["pickup_s"].mean(),
        }
    )
    out["total_saving_km"] = out["total_saving_km"].fillna(0.0)
    return out.loc[g.size().index]


def check_hourly(
    fc: RunCheck, f: Folder, runs: list[RunCheck], tables: dict[str, pd.DataFrame], per_hour: set[str]
) -> None:
    """hourly.csv (plotted as hourly.png) equals its recomputation ``tables``: a run's wrong rows fail that
    run's ``hourly`` check, rows of a run without per-hour figures (not in ``per_hour``) the folder's."""
    path = f.path / HOURLY
    if not tables:
        return
    if not path.is_file():
        fc.skip("hourly", f"the folder has no {HOURLY}")
        return
    try:
        hourly = results.read_csv(path)
    except ResultsError as exc:
        fc.fail("hourly", one_line(exc))
        return
    if not {"hour", "run"} <= set(hourly.columns):
        fc.fail("hourly", f"{HOURLY} lacks its hour or run column")
        return
    hourly = hourly.assign(run=hourly["run"].astype(str), hour=pd.to_numeric(hourly["hour"], errors="coerce"))
    for name in sorted(set(hourly["run"]) - per_hour):
        fc.fail("hourly", f"{HOURLY} has rows of run {name!r}, which has no per-hour figures in this folder")
    for rc in runs:
        if rc.run in tables:
            _compare_hourly(rc, hourly[hourly["run"] == rc.run].set_index("hour"), tables[rc.run])


def _compare_hourly(rc: RunCheck, rows: pd.DataFrame, expected: pd.DataFrame) -> None:
    """One run's rows of hourly.csv: the same hours, and every figure equal to its recomputation."""
    if rows.index.has_duplicates or set(rows.index) != set(expected.index):
        rc.fail(
            "hourly",
            f"{HOURLY} has hours {sorted(map(str, rows.index))}, the run's orders request in "
            f"hours {sorted(map(str, expected.index))}",
        )
        return
    for column in expected.columns:
        if column not in rows.columns:
            rc.fail("hourly", f"{HOURLY} lacks the column {column}")
            continue
        for hour in expected.index:
            value = as_number(rows.loc[hour, column])
            if value is None or not same(value, float(expected.loc[hour, column])):
                rc.fail(
                    "hourly",
                    f"hour {hour}: {column} reported {show(rows.loc[hour, column])}, recomputed "
                    f"{float(expected.loc[hour, column])!r}",
                )
    rc.checked["hours"] = len(expected)


# ----------------------------------------------------------------------- report
MetricTable = list[tuple[str, list[str]]]


def check_report(fc: RunCheck, folder: Path) -> None:
    """The KPI tables of report.md (what most readers read) are the rendering of kpis.csv, which the runs'
    ``kpi`` checks verify (or, in a published light copy, the digest its parent records): a number edited in
    report.md alone fails here."""
    path = folder / REPORT
    if not path.is_file():
        fc.skip("report", f"the folder has no {REPORT}")
        return
    try:
        rendered = report_markdown(folder, folder.name)
        older = _older_by_label(folder)
    except (RpbenchError, KeyError, ValueError, TypeError, IndexError) as exc:
        fc.skip(
            "report",
            f"{KPIS} or {META} cannot be rendered ({type(exc).__name__}: {one_line(exc)}); the kpi checks say why",
        )
        return
    expected = _metric_tables(rendered)
    text = path.read_text(errors="replace")
    found = _metric_tables(text)
    _check_bracket_line(fc, rendered, text)
    unmatched: set[str] = set()
    if len(found) != len(expected):
        unmatched.add(f"({len(found)} KPI tables in {REPORT}, {len(expected)} rendered)")
    for want, have in zip(expected, found, strict=True):
        shown = dict(have)
        older_label = KPI_LABELS["competitive_ratio_best_known"]  # before the row said "best run here"
        if BEST_RUN_HERE_LABEL not in shown and older_label in shown and older_label not in dict(want):
            shown[BEST_RUN_HERE_LABEL] = shown.pop(older_label)
        for label, cells in want:
            if label not in shown:
                unmatched.add(label)
            elif older.get(label) is not None and _older_rendering(shown[label], cells, older[label]):
                unmatched.add(f"{label} (offline cells as an older rpbench showed them)")
            elif shown[label] != cells:
                fc.fail(
                    "report",
                    f"{REPORT} shows {label}: {' | '.join(shown[label])}; {KPIS} renders {' | '.join(cells)}",
                )
        unmatched |= set(shown) - {label for label, _ in want}
    if unmatched:  # a row deleted, or worded by another rpbench version: nothing false is shown
        fc.skip(
            "report",
            f"{REPORT} rows not compared (absent from {REPORT} or from today's rendering): "
            f"{', '.join(sorted(unmatched))}",
        )
    fc.checked["report_tables"] = len(expected)


def older_cells(table: pd.DataFrame) -> dict[tuple[str, str], float]:
    """(KPI, run) -> the value an older rpbench showed in a cell of the comparison table where today's shows "/"
    (``table``: :func:`~rpbench.report.comparison.load_kpis`): the bound's matching statistics (they bound nothing,
    kpis.csv names them apart) and an offline run's saving over the bound's or Oracle-1's (offline runs are no
    schedules)."""
    out = {}
    for kpi, name in BOUND_MATCHING_KPIS.items():
        if BOUND in table.columns and name in table.index:
            out[(kpi, BOUND)] = float(table.loc[name, BOUND])
    for kpi, denominator in DENOMINATORS.items():
        if denominator not in table.columns or kpi not in table.index:
            continue
        below = float(table.loc["total_saving_km", denominator])
        for run in map(str, table.columns):
            saving = table.loc["total_saving_km", run]
            if pd.isna(table.loc[kpi, run]) and below > 0 and pd.notna(saving):
                out[(kpi, run)] = float(saving) / below
    return out


def _older_by_label(folder: Path) -> dict[str, dict[int, str]]:
    """:func:`older_cells` as report.md shows them: per row label, column index -> cell text."""
    table = load_kpis(folder)
    columns = [str(c) for c in table.columns]
    out: dict[str, dict[int, str]] = {}
    for (kpi, run), value in older_cells(table).items():
        out.setdefault(KPI_LABELS.get(kpi, kpi), {})[columns.index(run)] = fmt(kpi, value)
    return out


def _older_rendering(shown: list[str], rendered: list[str], older: dict[int, str]) -> bool:
    """Whether a row differs from today's rendering only in cells that hold what an older rpbench showed there
    (alone, or beside the paper's value)."""
    differ = [i for i, (a, b) in enumerate(zip(shown, rendered, strict=False)) if a != b]
    return (
        len(shown) == len(rendered)
        and bool(differ)
        and all(i in older and shown[i].split(" (")[0] == older[i] for i in differ)
    )


def _check_bracket_line(fc: RunCheck, rendered: str, text: str) -> None:
    """The line under the comparison table saying where OPT lies is today's rendering of kpis.csv."""
    want = [line for line in rendered.splitlines() if line.startswith(BRACKET_PREFIX)]
    have = [line for line in text.splitlines() if line.startswith(BRACKET_PREFIX)]
    if not have and want:
        fc.skip("report", f"{REPORT} has no line saying where OPT lies (written by an older rpbench)")
    elif have != want:
        fc.fail("report", f"{REPORT} says {' '.join(have) or 'nothing'} of OPT; {KPIS} renders {' '.join(want)}")


#: Where one markdown cell ends: a ``|`` not escaped (a label's own ``|`` is written ``\\|``).
_CELL_BORDER = re.compile(r"(?<!\\)\|")


def _metric_tables(text: str) -> list[MetricTable]:
    """The markdown tables whose header starts with "| Metric |": per row its label and its cells (the header,
    where a run may be marked unproven, is not compared)."""
    tables: list[MetricTable] = []
    current: MetricTable | None = None
    for line in text.splitlines():
        if line.startswith("| Metric |"):
            current = []
            tables.append(current)
        elif current is not None and line.startswith("|"):
            cells = [c.strip() for c in _CELL_BORDER.split(line.strip().removeprefix("|").removesuffix("|"))]
            if not set("".join(cells)) <= set("-: "):  # not the |---|---:| line
                current.append((cells[0], cells[1:]))
        else:
            current = None
    return tables
