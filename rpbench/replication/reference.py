"""The authors' committed outputs (days 1-14) and the paper's printed Table 2, with where each number came from.

The committed outputs are ``reference/authors_committed_outputs_2017-05-01_14.csv`` of
the data folder (decoded ``system_metric.pkl`` files, see its SOURCE.md).  The
paper's Table 2 is :data:`rpbench.data.paper.TABLE2`; the authors' ``Analysis.py``
(read in their repository) shows that several of its values were typed in
rather than produced by a run: it swaps the MB and RTV saving series, then
overwrites day 1 and whole per-day series with typed lists.  :data:`TABLE2_ORIGIN`
records, per printed value, which it is.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from rpbench.data import paper

REFERENCE_FILE = Path("reference") / "authors_committed_outputs_2017-05-01_14.csv"

#: rpbench strategy name -> the method name of the committed outputs.
METHODS = {"np": "NP", "mb": "MB", "rtv": "RTV", "fl-nd": "FL-no_delay", "fl": "FL"}

#: committed metric key -> rpbench KPI name (and a unit factor).
REFERENCE_METRICS = {
    "response_rate": ("response_rate", 1.0),
    "carpool_rate": ("pairing_ratio", 1.0),
    "saved_ride_distance": ("total_saving_km", 1e-3),
    "detour_distance": ("avg_detour_m", 1.0),
    "shared_distance": ("avg_shared_m", 1.0),
    "pickup_time": ("avg_pickup_time_s", 1.0),
}

#: Per strategy and KPI of the paper's Table 2 (2017-05-01): "typed" = a value typed into Analysis.py,
#: "run" = equals the committed output of a run (rounded), "neither" = matches neither.
TABLE2_ORIGIN = {
    "mb": {
        "response_rate": "typed",
        "pairing_ratio": "run",
        "avg_detour_m": "typed",
        "avg_shared_m": "typed",
        "total_saving_km": "typed",
    },
    "rtv": {
        "response_rate": "typed",
        "pairing_ratio": "neither",
        "avg_detour_m": "typed",
        "avg_shared_m": "typed",
        "total_saving_km": "typed",
    },
    "fl": {
        "response_rate": "typed",
        "pairing_ratio": "run",
        "avg_detour_m": "typed",
        "avg_shared_m": "typed",
        "total_saving_km": "typed",
    },
    "fl-nd": {
        "response_rate": "run",
        "pairing_ratio": "run",
        "avg_detour_m": "run",
        "avg_shared_m": "run",
        "total_saving_km": "run",
    },
    "np": {"response_rate": "neither"},
}
TABLE2_DATE = "2017-05-01"
REFERENCE_KPIS = ("response_rate", "pairing_ratio", "total_saving_km", "avg_detour_m", "avg_shared_m")


def has_committed(data_dir: Path) -> bool:
    """Whether ``data_dir`` holds the committed outputs (a fetched data folder does not: no registry entry)."""
    return (data_dir / REFERENCE_FILE).is_file()


def read_committed(data_dir: Path) -> pd.DataFrame:
    """Committed outputs as rows (strategy, date, kpi, value); empty when the file is absent."""
    path = data_dir / REFERENCE_FILE
    if not has_committed(data_dir):
        return pd.DataFrame(columns=["strategy", "date", "kpi", "value"])
    raw = pd.read_csv(path)
    by_method = {v: k for k, v in METHODS.items()}
    raw = raw[raw["method"].isin(by_method) & raw["metric"].isin(REFERENCE_METRICS)]
    return pd.DataFrame(
        {
            "strategy": raw["method"].map(by_method),
            "date": raw["day"],
            "kpi": raw["metric"].map(lambda m: REFERENCE_METRICS[m][0]),
            "value": raw["mean_value"].astype(float) * raw["metric"].map(lambda m: REFERENCE_METRICS[m][1]),
        }
    ).reset_index(drop=True)


def committed_value(table: pd.DataFrame, strategy: str, date: str, kpi: str) -> float:
    hit = table[(table["strategy"] == strategy) & (table["date"] == date) & (table["kpi"] == kpi)]
    return float(hit["value"].iloc[0]) if len(hit) else float("nan")


def printed_value(strategy: str, date: str, kpi: str) -> tuple[float, str]:
    """The paper's Table 2 value (2017-05-01 only) and its origin ("typed", "run", "neither"), else (nan, "")."""
    if date != TABLE2_DATE or strategy not in paper.TABLE2:
        return float("nan"), ""
    value = float(paper.TABLE2[strategy].get(kpi, float("nan")))
    return value, TABLE2_ORIGIN.get(strategy, {}).get(kpi, "")
