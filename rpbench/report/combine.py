"""Several comparison folders of one scenario as one comparison (``rpbench report A B C``).

Folders combine only when they hold one instance: the same input files and parameters, as meta.json's
``inputs_digest`` records them (:func:`instance_differences`), so that every run of every folder is a
column of one table and one upper bound divides every run's saving.  What else may differ (the solver
preset, the rpbench version, the commit) is listed (:func:`other_differences`).  A run name found in
several folders is one column where it is the same run (same options and rules, same KPIs apart from
the clock's, :func:`same_run`), else one column per folder, qualified by it (``A/fl``, "FL (A)").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rpbench import files, results
from rpbench.exceptions import ResultsError
from rpbench.files.digests import content_sha256
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.report.comparison import (
    UNPROVEN_MARK,
    fmt,
    markdown_table,
    offline_notes,
    selected_markdown,
    synthetic_lines,
    table_rows,
    unproven_notes,
)
from rpbench.report.plots import kpi_figure
from rpbench.report.tables import csv_table, latex_table
from rpbench.results import layout
from rpbench.results.digest import DIGEST_FILES, json_sha256, recorded_spec
from rpbench.results.metrics import KPI_LABELS, TIMING_KPIS
from rpbench.results.ratios import DENOMINATORS, DERIVED_KPIS, best_known, bracket_line, savings_of, with_ratios
from rpbench.results.read import load_kpis, unproven_runs
from rpbench.results.runs import run_color, run_label, run_styles, simulated_runs
from rpbench.spec import DEFAULT_FIGURE_FORMATS

#: How a folder of another kind is named in the message refusing it (only comparison folders combine).
KIND_NAMES = {
    "multi-day": "a multi-day",
    "sweep": "a sweep",
    "evaluate": "an evaluation",
    "replication": "a replication",
}
#: The KPIs of one run written in two folders agree within this (relative): a run repeated on another
#: machine may differ in the last bits of a sum, a different run differs by far more.
SAME_RTOL = 1e-9
SAME_ATOL = 1e-9


@dataclass(frozen=True)
class SourceFolder:
    """One folder of a combination: where it is, its name in the text, its meta.json and KPI table."""

    path: Path
    name: str
    meta: dict[str, Any]
    table: pd.DataFrame


@dataclass(frozen=True)
class Column:
    """A column of the combined table: its key, the run it shows, the folders holding that same run (the
    first one's values are shown)."""

    key: str
    run: str
    members: tuple[int, ...]


@dataclass(frozen=True)
class Combined:
    """Several folders' runs as one comparison, with what its report says about them."""

    sources: list[SourceFolder]
    columns: list[Column]
    table: pd.DataFrame  # KPI rows x column keys, the ratio rows over the combined runs where they can be
    styles: dict[str, tuple[str, str | None]]
    unproven: dict[str, str]  # column key -> why its numbers are not proven (rpbench.report.comparison)
    differences: list[str]  # what differs between the folders besides their one instance
    notes: list[str]

    @property
    def scenario(self) -> dict[str, Any]:
        return self.sources[0].meta["scenario"]

    @property
    def label(self) -> str:
        return str(self.scenario.get("label", self.scenario.get("name", "")))

    @property
    def runs(self) -> dict[str, dict[str, Any]]:
        """Each column's meta.json run record (the offline notes read the bound's status there)."""
        return {c.key: (self.sources[c.members[0]].meta.get("runs") or {}).get(c.run, {}) for c in self.columns}

    @property
    def simulated(self) -> list[str]:
        """The columns that are simulated runs."""
        return simulated_columns(self.sources, self.columns)


def combine(folders: Sequence[Path]) -> Combined:
    """The comparison folders ``folders``, of one instance, as one comparison; anything else is one
    :class:`ResultsError` line naming the folders and what differs."""
    sources = read_sources(folders)
    for other in sources[1:]:
        differs = instance_differences(sources[0], other)
        if differs:
            raise ResultsError(
                f"cannot combine {str(sources[0].path)!r} and {str(other.path)!r}: their scenarios differ "
                f"({'; '.join(differs)}); only folders of one scenario combine"
            )
    columns = merged_columns(sources)
    table = combined_table(sources, columns)
    return Combined(
        sources=sources,
        columns=columns,
        table=table,
        styles=column_styles(sources, columns),
        unproven=column_unproven(sources, columns),
        differences=other_differences(sources),
        notes=run_notes(sources, columns) + ratio_notes(sources, columns, table),
    )


# ----------------------------------------------------------------------- the folders
def read_sources(folders: Sequence[Path]) -> list[SourceFolder]:
    """Each folder's meta.json and KPI table, named by its folder's name (by its path where two share one)."""
    seen: set[Path] = set()
    for folder in folders:
        if folder.resolve() in seen:
            raise ResultsError(f"{str(folder)!r} is given twice; each folder combines once")
        seen.add(folder.resolve())
    names = [folder.name or folder.resolve().name for folder in folders]
    if len(set(names)) < len(names):
        names = [str(folder) for folder in folders]
    return [SourceFolder(f, n, comparison_meta(f), load_kpis(f)) for f, n in zip(folders, names, strict=True)]


def comparison_meta(folder: Path) -> dict[str, Any]:
    """meta.json of a comparison folder that holds runs; any other folder is refused in one line."""
    meta = results.read_meta(folder)
    kind = meta.get("kind", "comparison")
    if kind != "comparison":
        what = KIND_NAMES.get(str(kind), f"a {kind!r}")
        raise ResultsError(f"{str(folder)!r} is {what} folder; only comparison folders combine: render it alone")
    if not (folder / layout.KPIS).is_file():
        raise ResultsError(f"results folder {str(folder)!r} holds no runs (no {layout.KPIS})")
    return meta


# ---------------------------------------------------------------- one instance
def instance_differences(a: SourceFolder, b: SourceFolder) -> list[str]:
    """What makes the instances of two folders differ, in words; empty when they hold one instance.

    The digests of the input files and parameters decide (a folder without them is compared by its
    scenario's description); the description says in the user's words what differs.
    """
    described = described_differences(a.meta, b.meta)
    digest_a, digest_b = a.meta.get("inputs_digest"), b.meta.get("inputs_digest")
    if not (isinstance(digest_a, dict) and isinstance(digest_b, dict)):
        return described
    files = differing_inputs(a, b)
    if not files and digest_a.get("params") == digest_b.get("params"):
        return []
    if described:
        return described
    if not files:
        return ["their parameters' digests differ"]
    text = f"input files {', '.join(files)}"
    if not all((s.path / f).is_file() for s in (a, b) for f in files):
        text += " by their digests, and a published light copy holds no inputs to compare: combine the full folders"
    return [text]


def described_differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    """``"seed 0 vs 1"`` for each entry of :func:`scenario_description` the two meta.json differ in."""
    da, db = scenario_description(a), scenario_description(b)
    keys = dict.fromkeys([*da, *db])
    return [f"{k} {_show(da.get(k))} vs {_show(db.get(k))}" for k in keys if da.get(k) != db.get(k)]


def scenario_description(meta: dict[str, Any]) -> dict[str, Any]:
    """A folder's scenario as a user names it: scenario, date, sample, seed, fleet placement, period and
    parameters (the values in force: an argument left to its default reads as the scenario made it)."""
    sc = meta.get("scenario") or {}
    args = sc.get("args") or {}
    made = sc.get("provenance") or {}
    params = meta.get("params")
    if not isinstance(params, dict):  # a folder without its parameters in force: those its command gave
        params = args.get("params") or {}
    return {
        "scenario": sc.get("name"),
        "date": _given(args, made, "date"),
        "sample": _given(args, made, "sample"),
        "seed": sc.get("seed", args.get("seed")),
        "fleet placement": _given(args, made, "fleet_placement"),
        "start": sc.get("start_time"),
        "horizon (s)": sc.get("horizon_s"),
    } | {str(k): v for k, v in params.items()}


def _given(args: dict[str, Any], made: dict[str, Any], key: str) -> Any:
    return args[key] if args.get(key) is not None else made.get(key)


def _show(value: Any) -> str:
    return "unset" if value is None else str(value)


def differing_inputs(a: SourceFolder, b: SourceFolder) -> list[str]:
    """The input files whose recorded digests differ, but for those both folders hold with one content (a
    gzip file's header may carry the time it was written: one content, other bytes)."""
    files_a = (a.meta["inputs_digest"].get("files")) or {}
    files_b = (b.meta["inputs_digest"].get("files")) or {}
    out = []
    for name in DIGEST_FILES:
        if files_a.get(name) == files_b.get(name):
            continue
        path_a, path_b = a.path / name, b.path / name
        if path_a.is_file() and path_b.is_file() and content_sha256(path_a) == content_sha256(path_b):
            continue
        out.append(name)
    return out


def _commit(meta: dict[str, Any]) -> str | None:
    commit = meta.get("git_commit")
    if not commit:
        return None
    return str(commit)[:8] + ("+dirty" if str(commit).endswith("+dirty") else "")


#: What else a report says of a folder, which may differ between folders of one instance: name, reader.
FOLDER_FACTS: tuple[tuple[str, Callable[[dict[str, Any]], Any]], ...] = (
    ("preset", lambda m: (m.get("preset") or {}).get("name")),
    ("rpbench", lambda m: (m.get("versions") or {}).get("rpbench")),
    ("commit", _commit),
)


def fact_holders(sources: list[SourceFolder]) -> dict[str, dict[str, list[str]]]:
    """Per :data:`FOLDER_FACTS` entry: each value it takes, with the names of the folders holding it."""
    out: dict[str, dict[str, list[str]]] = {}
    for what, read in FOLDER_FACTS:
        for s in sources:
            out.setdefault(what, {}).setdefault(_show(read(s.meta)), []).append(s.name)
    return out


def other_differences(sources: list[SourceFolder]) -> list[str]:
    """``"preset highs (A) vs ortools (B)"`` for the preset, rpbench version and commit the folders differ in."""
    return [
        f"{what} " + " vs ".join(f"{v} ({', '.join(names)})" for v, names in holders.items())
        for what, holders in fact_holders(sources).items()
        if len(holders) > 1
    ]


def shared_facts(sources: list[SourceFolder]) -> list[str]:
    """``"preset highs"`` for the preset, rpbench version and commit every folder shares."""
    return [f"{what} {next(iter(h))}" for what, h in fact_holders(sources).items() if len(h) == 1]


# -------------------------------------------------------------------- the runs
def merged_columns(sources: list[SourceFolder]) -> list[Column]:
    """Every run of every folder, a run name of several folders as one column per distinct run; the
    simulations in the order the folders first show them, then the offline runs."""
    groups: dict[str, list[list[int]]] = {}
    for i, source in enumerate(sources):
        for run in map(str, source.table.columns):
            clusters = groups.setdefault(run, [])
            same = next((c for c in clusters if same_run(run, sources[c[0]], source)), None)
            if same is None:
                clusters.append([i])
            else:
                same.append(i)
    columns = [
        Column(f"{sources[c[0]].name}/{run}" if len(clusters) > 1 else run, run, tuple(c))
        for run, clusters in groups.items()
        for c in clusters
    ]
    return sorted(columns, key=lambda c: c.run in ORACLE_RUNS)


def same_run(run: str, a: SourceFolder, b: SourceFolder) -> bool:
    """Whether ``run`` of two folders is one run: the same options and rules (meta.json's run digest),
    and the same KPIs apart from the clock's (:data:`~rpbench.results.metrics.TIMING_KPIS`)."""
    if run_digest(a.meta, run) != run_digest(b.meta, run):
        return False
    shared = a.table.index.intersection(b.table.index)
    rows = [k for k in shared if k not in TIMING_KPIS and k not in DERIVED_KPIS]
    x = a.table.loc[rows, run].to_numpy(dtype=float)
    y = b.table.loc[rows, run].to_numpy(dtype=float)
    return bool(np.allclose(x, y, rtol=SAME_RTOL, atol=SAME_ATOL, equal_nan=True))


def run_digest(meta: dict[str, Any], run: str) -> str | None:
    """The digest of a run's options and rules: recorded in meta.json, else computed as rpbench records it."""
    recorded = ((meta.get("inputs_digest") or {}).get("runs") or {}).get(run)
    if recorded is not None:
        return str(recorded)
    record = (meta.get("runs") or {}).get(run)
    return json_sha256(recorded_spec(record)) if isinstance(record, dict) else None


def simulated_columns(sources: list[SourceFolder], columns: list[Column]) -> list[str]:
    """The keys of the columns that show a simulated run (by its folder's record)."""
    return [c.key for c in columns if simulated_runs(sources[c.members[0]].meta, [c.run])]


def combined_table(sources: list[SourceFolder], columns: list[Column]) -> pd.DataFrame:
    """The KPI table of ``columns``.  One instance: LB is the best saving over every folder's simulated runs,
    and a ratio row whose offline run is one column divides every column by it; with an offline run differing
    between folders (two columns), each folder's own ratio stays."""
    parts = []
    for col in columns:
        values = sources[col.members[0]].table[col.run]
        for i in col.members[1:]:  # a KPI only another folder's rpbench wrote
            values = values.combine_first(sources[i].table[col.run])
        parts.append(values.rename(col.key))
    table = pd.concat(parts, axis=1, sort=False)
    own = table.loc[[k for k in DENOMINATORS if k in table.index]].copy()  # each folder's, from load_kpis
    table = with_ratios(table, simulated_columns(sources, columns))
    for row, oracle in DENOMINATORS.items():
        if row in own.index and oracle not in table.columns:
            table.loc[row] = own.loc[row]
    return table


def column_styles(sources: list[SourceFolder], columns: list[Column]) -> dict[str, tuple[str, str | None]]:
    """Each column's label and colour from its folder's record; a qualified column's label names its folders."""
    out = {}
    for col in columns:
        own = run_styles(sources[col.members[0]].meta)
        label = run_label(col.run, own)
        if col.key != col.run:
            label = f"{label} ({', '.join(sources[i].name for i in col.members)})"
        out[col.key] = (label, run_color(col.run, own))
    return out


def column_unproven(sources: list[SourceFolder], columns: list[Column]) -> dict[str, str]:
    """The columns whose numbers rest on solver answers not proven optimal, with why (the folders' words)."""
    found = [unproven_runs(s.path) for s in sources]
    out = {}
    for col in columns:
        why = next((found[i][col.run] for i in col.members if col.run in found[i]), None)
        if why is not None:
            out[col.key] = why
    return out


# ------------------------------------------------------------------- the notes
def run_notes(sources: list[SourceFolder], columns: list[Column]) -> list[str]:
    """What became of each run name found in several folders: one column, or one per distinct run."""
    notes = []
    by_run: dict[str, list[Column]] = {}
    for col in columns:
        by_run.setdefault(col.run, []).append(col)
    for run, cols in by_run.items():
        first = sources[cols[0].members[0]]
        label = run_label(run, run_styles(first.meta))
        if len(cols) == 1 and len(cols[0].members) > 1:
            notes.append(
                f"{label} is the same run in {_names(sources, cols[0].members)} (same options, same KPIs apart "
                f"from the clock's): shown once, with the timings of `{first.name}`."
            )
        elif len(cols) > 1:
            holders = [i for col in cols for i in col.members]
            notes.append(
                f"{label} differs between {_names(sources, holders)} (in its options or its KPIs): one column "
                "per distinct run, named after its folder."
            )
    return notes


def ratio_notes(sources: list[SourceFolder], columns: list[Column], table: pd.DataFrame) -> list[str]:
    """Where a ratio row divides a folder's runs by another folder's offline run or schedule, or cannot."""
    notes = []
    lb = best_known(savings_of(table, simulated_columns(sources, columns)))
    holder = next((c for c in columns if lb is not None and c.key == lb.run), None)
    if holder is not None and len(sources) > 1:
        notes.append(
            f"{KPI_LABELS['competitive_ratio_best_known']}: every run is divided by the best known schedule over "
            f"all the folders, {run_label(holder.key, column_styles(sources, [holder]))} of "
            f"{_names(sources, holder.members)}, as the folders hold one instance."
        )
    for row, oracle in DENOMINATORS.items():
        holders = [c for c in columns if c.run == oracle]
        if not holders:
            continue
        name = KPI_LABELS.get(row, row)
        if len(holders) > 1:
            notes.append(
                f"{run_label(oracle)} differs between the folders: {name} divides each folder's runs by its own."
            )
            continue
        without = [i for i in range(len(sources)) if i not in holders[0].members]
        if without and row in table.index:
            notes.append(
                f"{name}: the runs of {_names(sources, without)} are divided by {run_label(oracle)} of "
                f"{_names(sources, holders[0].members)}, as the folders hold one instance."
            )
    return notes


def _names(sources: list[SourceFolder], indices: Sequence[int]) -> str:
    names = [f"`{sources[i].name}`" for i in dict.fromkeys(indices)]
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


# ------------------------------------------------------------------- rendering
def combined_markdown(c: Combined, metrics: list[str] | None = None, *, figures: bool = False) -> str:
    """The combined report: the scenario once, the folders and what differs between them, one table (the
    KPIs ``metrics`` only, when given), its notes; ``figures``: embed :func:`write_combined`'s figure."""
    sc = c.scenario
    summary = sc.get("summary") or {}
    lines = [f"# rpbench combined comparison: {c.label}", ""]
    lines += synthetic_lines(sc)
    lines += [
        f"- scenario `{sc.get('name')}`, seed {sc.get('seed')}, {summary.get('orders')} orders, "
        f"{summary.get('vehicles')} vehicles, {summary.get('nodes')} nodes: one instance in every folder "
        "(the same input files and parameters)",
        "- folders: " + ", ".join(f"`{s.name}`" for s in c.sources),
    ]
    shared = shared_facts(c.sources)
    lines += [f"- In every folder: {', '.join(shared)}"] if shared else []
    lines += [f"- Differences between the folders: {'; '.join(c.differences)}."] if c.differences else []
    lines += [
        "",
        "## Comparison (paper Table 2 layout)",
        "",
    ]
    if metrics is None:
        lines += [markdown_table(c.table, unproven=c.unproven, styles=c.styles), ""]
        bracket = bracket_line(c.table, c.simulated, fmt, c.styles)
        lines += [bracket, ""] if bracket else []
        lines += unproven_notes(c.unproven, c.styles) + offline_notes(c.table, {"runs": c.runs})
    else:
        lines += [selected_markdown(c.table.loc[selected_rows(c.table, metrics)], c.styles), ""]
    lines += [*(f"- {note}" for note in c.notes), ""] if c.notes else []
    lines += _figure_lines() if figures else _no_figure_lines()
    return "\n".join(lines)


def _figure_lines() -> list[str]:
    return [
        "## Figures",
        "",
        # links, so that they follow the files when `rpbench report --out FILE` renames them
        f"The figure is PNG (`--figures png,svg,pdf` writes SVG and PDF beside it); the combined table is "
        f"[`{layout.TABLE_TEX}`]"
        f"({layout.TABLE_TEX}) (LaTeX, booktabs) and [`{layout.TABLE_CSV}`]({layout.TABLE_CSV}) (raw values). Each "
        "folder's own report.md keeps its timeline, per-hour figures and solver statistics.",
        "",
        f"![headline KPIs per run]({layout.KPIS_PNG})",
        "",
        "Headline KPIs of the combined table, one bar per column; a panel leaves out the runs without that KPI.",
        "",
    ]


def _no_figure_lines() -> list[str]:
    return [
        f"`--out FILE` writes the headline-KPI figure and the table as `{layout.TABLE_TEX}` and `{layout.TABLE_CSV}` "
        "beside FILE. Each folder's own report.md keeps its timeline, per-hour figures and solver statistics.",
        "",
    ]


def selected_rows(table: pd.DataFrame, metrics: list[str] | None) -> list[str]:
    """The table's rows in report order, or the KPIs ``metrics`` it holds, in their order."""
    return table_rows(table) if metrics is None else [m for m in metrics if m in table.index]


def write_combined(
    c: Combined, dest: Path, metrics: list[str] | None = None, formats: Sequence[str] = DEFAULT_FIGURE_FORMATS
) -> list[Path]:
    """Write the combined table as ``table.tex`` and ``table.csv`` (the rows the report shows) and the
    headline-KPI figure ``kpis.png`` (in ``formats``) into ``dest``; returns the files' paths."""
    rows = selected_rows(c.table, metrics)
    caption = f"{c.label}: the runs of {', '.join(s.name for s in c.sources)} combined"
    note = bracket_line(c.table, c.simulated, fmt, c.styles)
    tex = latex_table(
        c.table, rows, fmt, caption=caption, unproven=c.unproven, mark=UNPROVEN_MARK, styles=c.styles, note=note
    )
    files.write_text(dest / layout.TABLE_TEX, tex)
    csv_table(c.table, rows, c.styles).to_csv(dest / layout.TABLE_CSV)
    png = kpi_figure(c.table, dest / layout.KPIS_PNG, c.label, fmt, c.styles, formats=formats)
    return [dest / layout.TABLE_TEX, dest / layout.TABLE_CSV, *(png.with_suffix(f".{f}") for f in formats)]
