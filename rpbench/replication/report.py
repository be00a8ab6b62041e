"""Tables of a replication: agreement with the committed outputs, the ablation, the paper's Table 2, conclusions."""

from __future__ import annotations

import numpy as np
import pandas as pd

from rpbench.replication.reference import REFERENCE_FILE

#: The agreement criterion with the committed outputs: MB and RTV within MATCH_REL_TOL on pairing ratio and total
#: saving, NP's response rate within NP_RESPONSE_TOL, on at least REQUIRED_DAYS of every OF_DAYS days that
#: have committed outputs (in proportion, rounded up, for fewer days).
MATCH_REL_TOL = 0.15
NP_RESPONSE_TOL = 0.03
CRITERION_STRATEGIES = ("mb", "rtv")
REQUIRED_DAYS, OF_DAYS = 10, 14
#: What the criterion says when the data folder has no committed outputs at all (a fetched one has none).
NO_REFERENCE = "no reference outputs to compare with"


def _fmt(x, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "–"
    return f"{x:,.{digits}f}"


def _rel(a, b) -> float:
    if a is None or b is None or not np.isfinite(a) or not np.isfinite(b) or b == 0:
        return float("nan")
    return (a - b) / abs(b)


def agreement(frame: pd.DataFrame) -> pd.DataFrame:
    """Per date and strategy: the authors' engine beside the committed output, with relative differences.

    ``within`` is NaN where there is nothing to compare: a strategy outside the criterion, or a day
    without the committed values the criterion compares.
    """
    a = frame[frame["engine"] == "authors"].copy()
    a["rel_pairing"] = [_rel(x, y) for x, y in zip(a["pairing_ratio"], a["committed_pairing_ratio"], strict=True)]
    a["rel_saving"] = [_rel(x, y) for x, y in zip(a["total_saving_km"], a["committed_total_saving_km"], strict=True)]
    a["diff_response"] = a["response_rate"].astype(float) - a["committed_response_rate"].astype(float)
    columns = (a["strategy"], a["rel_pairing"], a["rel_saving"], a["diff_response"])
    a["within"] = [_within(*row) for row in zip(*columns, strict=True)]
    return a


def _within(strategy: str, rel_pairing: float, rel_saving: float, diff_response: float) -> float:
    """1.0 / 0.0 whether one day is within the criterion's tolerance, NaN when it cannot be compared."""
    compared: tuple[float, ...]
    if strategy in CRITERION_STRATEGIES:
        compared = (rel_pairing, rel_saving)
        tol = MATCH_REL_TOL
    elif strategy == "np":
        compared = (diff_response,)
        tol = NP_RESPONSE_TOL
    else:
        return np.nan
    if not all(np.isfinite(x) for x in compared):
        return np.nan
    return float(all(abs(x) <= tol for x in compared))


def required_days(days: int) -> int:
    """Days within tolerance the criterion asks of ``days`` compared: REQUIRED_DAYS of OF_DAYS in proportion."""
    return -(-REQUIRED_DAYS * days // OF_DAYS)


def _day(n: int) -> str:
    return "day" if n == 1 else "days"


def _days_text(dates: list[str]) -> str:
    if len(dates) <= 3:
        return ", ".join(dates)
    return f"{len(dates)} days ({dates[0]} .. {dates[-1]})"


def criterion(frame: pd.DataFrame, *, reference: bool = True) -> dict[str, str]:
    """Per strategy of the criterion that ran: ``met: K of N days within ...``, ``not met: ...`` or ``not
    evaluated: ...`` (``reference`` false: the data folder has no committed outputs; or none for these days).

    Only the days with committed outputs count: N is their number, the bar :func:`required_days` of it.
    """
    a = agreement(frame)
    out = {}
    for s in ("mb", "rtv", "np"):
        part = a[a["strategy"] == s]
        if not len(part):
            continue
        if not reference:
            out[s] = f"not evaluated: {NO_REFERENCE}"
            continue
        compared = part[part["within"].notna()]
        missing = sorted(set(part["date"]) - set(compared["date"]))
        if not len(compared):
            out[s] = f"not evaluated: no committed outputs for {_days_text(missing)}"
            continue
        ok, n = int(compared["within"].sum()), len(compared)
        need = required_days(n)
        text = f"{'met' if ok >= need else 'not met'}: {ok} of {n} {_day(n)} within (at least {need} needed)"
        if missing:
            text += f"; no committed outputs for {_days_text(missing)}, not counted"
        out[s] = text
    return out


def criterion_text(frame: pd.DataFrame, *, reference: bool = True) -> str:
    """The criterion as the report states it, its day count taken from the days with committed outputs."""
    if not reference:
        return (
            f"No reference outputs to compare with: the data folder has no `{REFERENCE_FILE.as_posix()}` (a fetched "
            "data folder has none: the registry does not pin it), so the criterion is not evaluated."
        )
    a = agreement(frame)
    ran = a[a["strategy"].isin((*CRITERION_STRATEGIES, "np"))]
    days = sorted(set(ran.loc[ran["within"].notna(), "date"]))
    if len(ran) and not days:
        return (
            f"No committed outputs for {_days_text(sorted(set(ran['date'])))}: the criterion is not evaluated "
            "(the authors' outputs cover 2017-05-01 .. 2017-05-14)."
        )
    n = len(days) if days else OF_DAYS
    scaled = "" if n == OF_DAYS else f"; {REQUIRED_DAYS} of {OF_DAYS} in proportion"
    return (
        f"Criterion: MB and RTV within {MATCH_REL_TOL * 100:.0f} % on pairing ratio and total saving, "
        f"NP's response rate within {NP_RESPONSE_TOL}, each on at least {required_days(n)} of {n} {_day(n)} "
        f"(the days with committed outputs{scaled})."
    )


def agreement_table(frame: pd.DataFrame) -> str:
    a = agreement(frame)
    lines = [
        (
            "| date | strategy | pairing (committed) | rel. diff | saving km (committed) | rel. diff | "
            "response (committed) | diff | within |"
        ),
        "|---|---|---:|---:|---:|---:|---:|---:|:-:|",
    ]
    for _, r in a.sort_values(["strategy", "date"]).iterrows():
        within = "" if pd.isna(r["within"]) else ("yes" if r["within"] else "no")
        lines.append(
            f"| {r['date']} | {r['strategy']} | {_fmt(r['pairing_ratio'])} ({_fmt(r['committed_pairing_ratio'])}) | "
            f"{_fmt(100 * r['rel_pairing'], 1)} % | {_fmt(r['total_saving_km'], 1)} "
            f"({_fmt(r['committed_total_saving_km'], 1)}) | {_fmt(100 * r['rel_saving'], 1)} % | "
            f"{_fmt(r['response_rate'])} ({_fmt(r['committed_response_rate'])}) | {_fmt(r['diff_response'])} | "
            f"{within} |"
        )
    return "\n".join(lines)


def ablation_table(frame: pd.DataFrame) -> str:
    """Per strategy and engine: means over the dates, and the share of the authors-to-rpbench gap each step covers."""
    lines = [
        "| strategy | engine | days | pairing | saving km | response | detour m | share of saving gap |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for strategy, part in frame.groupby("strategy", sort=False):
        means = part.groupby("engine", sort=False)[
            ["pairing_ratio", "total_saving_km", "response_rate", "avg_detour_m"]
        ].mean(numeric_only=True)
        days = part.groupby("engine", sort=False)["date"].nunique()
        base = means["total_saving_km"].get("authors", np.nan)
        top = means["total_saving_km"].get("rpbench", np.nan)
        gap = top - base if np.isfinite(base) and np.isfinite(top) else np.nan
        for engine, r in means.iterrows():
            share = (r["total_saving_km"] - base) / gap if np.isfinite(gap) and gap != 0 else np.nan
            lines.append(
                f"| {strategy} | {engine} | {days[engine]} | {_fmt(r['pairing_ratio'])} | "
                f"{_fmt(r['total_saving_km'], 1)} | {_fmt(r['response_rate'])} | {_fmt(r['avg_detour_m'], 0)} | "
                f"{_fmt(100 * share, 0)} % |"
            )
    return "\n".join(lines)


def cumulative_table(frame: pd.DataFrame) -> str:
    """The cumulative path authors -> mechanisms 1..k off -> all off (means over the dates): each step's
    change, and its share of the whole authors-to-all-off change of the total saving (the shares add to 1)."""
    cum = frame[frame["engine"].str.startswith("authors-cum") | (frame["engine"] == "authors")]
    if not cum["engine"].str.startswith("authors-cum").any():
        return ""
    lines = [
        (
            "| strategy | step (mechanisms 1..k off) | pairing | saving km | response | change of saving km | "
            "share of the whole change |"
        ),
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for strategy, part in cum.groupby("strategy", sort=False):
        means = part.groupby("engine", sort=False)[["pairing_ratio", "total_saving_km", "response_rate"]].mean()
        order = ["authors"] + sorted((e for e in means.index if e != "authors"), key=lambda e: int(e.split("-")[1][3:]))
        means = means.loc[order]
        whole = means["total_saving_km"].iloc[-1] - means["total_saving_km"].iloc[0]
        previous = None
        for engine, r in means.iterrows():
            change = np.nan if previous is None else r["total_saving_km"] - previous
            share = change / whole if np.isfinite(change) and whole else np.nan
            lines.append(
                f"| {strategy} | {engine} | {_fmt(r['pairing_ratio'])} | {_fmt(r['total_saving_km'], 1)} | "
                f"{_fmt(r['response_rate'])} | {_fmt(change, 1)} | {_fmt(100 * share, 0)} % |"
            )
            previous = r["total_saving_km"]
    return "\n".join(lines)


def paper_table(frame: pd.DataFrame, date: str = "2017-05-01") -> str:
    """The paper's Table 2 beside the authors' engine, rpbench's engine and the committed output."""
    rows = frame[frame["date"] == date]
    if not len(rows):
        return ""
    kpis = (
        ("response_rate", 3),
        ("pairing_ratio", 3),
        ("total_saving_km", 1),
        ("avg_detour_m", 0),
        ("avg_shared_m", 0),
    )
    lines = [
        "| strategy | KPI | authors' engine | rpbench's engine | committed output | paper (origin) |",
        "|---|---|---:|---:|---:|---|",
    ]
    for strategy in dict.fromkeys(rows["strategy"]):
        part = rows[rows["strategy"] == strategy].set_index("engine")
        for kpi, digits in kpis:
            ours = part[kpi].get("authors") if "authors" in part.index else None
            rp = part[kpi].get("rpbench") if "rpbench" in part.index else None
            ref = part.iloc[0]
            origin = ref.get(f"paper_{kpi}_origin")
            origin = origin if isinstance(origin, str) else ""  # NaN when read back from runs.csv
            paper_value = ref.get(f"paper_{kpi}")
            shown = _fmt(paper_value, digits) + (f" ({origin})" if origin else "")
            lines.append(
                f"| {strategy} | {kpi} | {_fmt(ours, digits)} | {_fmt(rp, digits)} | "
                f"{_fmt(ref.get(f'committed_{kpi}'), digits)} | {shown} |"
            )
    return "\n".join(lines)


def conclusions(frame: pd.DataFrame) -> str:
    """Whether the paper's conclusions hold per engine: FL saves the most, detours least, responds less."""
    lines = ["| engine | FL saves the most | FL detours least | FL responds less |", "|---|---:|---:|---:|"]
    rivals = ("mb", "rtv", "fl-nd")
    for engine, part in frame.groupby("engine", sort=False):
        pivot = {
            k: part.pivot_table(index="date", columns="strategy", values=k)
            for k in ("total_saving_km", "avg_detour_m", "response_rate")
        }
        if "fl" not in pivot["total_saving_km"].columns:
            continue
        others = [s for s in rivals if s in pivot["total_saving_km"].columns]
        if not others:
            continue
        n = len(pivot["total_saving_km"])
        most = int((pivot["total_saving_km"]["fl"] >= pivot["total_saving_km"][others].max(axis=1)).sum())
        least = int((pivot["avg_detour_m"]["fl"] <= pivot["avg_detour_m"][others].min(axis=1)).sum())
        less = int((pivot["response_rate"]["fl"] < pivot["response_rate"][others].min(axis=1)).sum())
        lines.append(f"| {engine} | {most} of {n} days | {least} of {n} days | {less} of {n} days |")
    return "\n".join(lines)


def markdown(frame: pd.DataFrame, meta: dict, *, reference: bool = True) -> str:
    """The report; ``reference`` false: the data folder has no committed outputs (the criterion is not evaluated)."""
    crit = criterion(frame, reference=reference)
    parts = [
        f"# rpbench replicate: {meta.get('dates_text', '')}",
        "",
        (
            f"- strategies {', '.join(meta.get('strategies', []))}; solver preset `{meta.get('preset')}`; "
            f"rpbench {meta.get('version')}, commit `{meta.get('git_commit')}`"
        ),
        f"- command: `{meta.get('command') or ''}`",
        "",
        "## Agreement of the authors' engine with the committed outputs",
        "",
        criterion_text(frame, reference=reference),
        "",
    ]
    parts += [f"- {s}: {v}" for s, v in crit.items()] + [""]
    if reference:
        parts += [agreement_table(frame), ""]
    parts += [
        "## Ablation (means over the dates; one mechanism off at a time)",
        "",
        (
            "`share of saving gap` = (engine - authors) / (rpbench - authors) of the mean total saving, where "
            "`rpbench` is rpbench's engine on the authors' input; `rpbench-peak` is rpbench's engine on its own "
            "input (haikou-peak), the counterpart of `authors-all-off`."
        ),
        "",
        ablation_table(frame),
        "",
    ]
    cumulative = cumulative_table(frame)
    if cumulative:
        parts += [
            "## Cumulative ablation (mechanisms 1..k off, in the fixed order; means over the dates)",
            "",
            cumulative,
            "",
        ]
    table2 = paper_table(frame)
    if table2:
        parts += [
            "## Beside the paper's Table 2 (2017-05-01)",
            "",
            (
                "Origin of each printed value: `typed` = typed into the authors' Analysis.py, `run` = equals "
                "the committed output of a run, `neither` = matches neither."
            ),
            "",
            table2,
            "",
        ]
    parts += ["## The paper's conclusions under each engine", "", conclusions(frame), ""]
    return "\n".join(parts)
