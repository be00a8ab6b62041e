"""The children of a published parent (``rpbench publish``): light copies, checked for what they keep.

A light child keeps its KPI table, its meta.json, its report and ``check.txt`` (the checker's verdict on the
full folder, written only when every check passed), not its event logs, trajectories or inputs.  The parent's
meta.json records the SHA-256 of each child's kpis.csv, meta.json and check.txt as published
(:func:`rpbench.results.digest.light_copy_record`), so the checker of the copy proves that the KPI tables the
parent's tables are recomputed from are the ones the full folders' checks verified:

* ``light-copy`` (the parent) — the record is well formed, of a format this rpbench knows, and names exactly
  the parent's children;
* ``light-copy`` (each child) — each recorded file is there with its recorded SHA-256;
* ``check-verdict`` — check.txt is a verdict of passed checks naming every run of the child;
* ``manifest`` — kpis.csv reports exactly the runs meta.json lists;
* ``report`` — the KPI tables of the child's report.md are the rendering of its kpis.csv.

Every check that needs an event log is skipped, and says so.  A copy published before the record existed has
its digests skipped by name; a parent claiming the record with a file missing fails.  The record is a digest,
not a signature: whoever rewrites a child's KPIs and the record both is caught only by rerunning the command.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rpbench import results
from rpbench.check.core import FOLDER, FolderResult, RunCheck
from rpbench.check.kpis import check_report
from rpbench.check.unit_runs import recorded_runs
from rpbench.exceptions import RpbenchError, one_line
from rpbench.files.digests import file_sha256
from rpbench.results.digest import LIGHT_CHILD_FILES, LIGHT_COPY, LIGHT_COPY_FORMAT
from rpbench.results.layout import CHECK, KPIS, META, RUNS

LIGHT_CHECK, VERDICT_CHECK = "light-copy", "check-verdict"
#: The first line of a light child's check.txt (``rpbench publish`` writes it, over the checker's report).
VERDICT_HEADER = "rpbench check on the full results folder before publishing (all checks passed):"
#: Why a light child's checks that read event logs, trajectories or inputs are not made.
LIGHT_NOTE = (
    "a published light copy keeps no event logs, trajectories nor inputs: check.txt holds the verdict on the "
    "full folder; rerun the command in its meta.json to check one again"
)


@dataclass(frozen=True)
class LightRecord:
    """A published parent's record of its light children: per child (a path relative to the parent), the
    SHA-256 of each file it keeps."""

    children: dict[str, dict[str, str]]


def read_light_record(fc: RunCheck, meta: dict, listed: list[str]) -> LightRecord | None:
    """The parent's record (``light-copy``): None when it has none (not a light copy, or one published before
    rpbench kept one); a malformed record fails and reads as naming no child, so every child then fails."""
    record = meta.get(LIGHT_COPY)
    if record is None:
        return None
    children = record.get("children") if isinstance(record, dict) else None
    well_formed = (
        isinstance(children, dict)
        and record.get("algorithm") == "sha256"
        and all(
            isinstance(files, dict) and all(isinstance(d, str) for d in files.values()) for files in children.values()
        )
    )
    if not well_formed or not isinstance(children, dict):
        fc.fail(LIGHT_CHECK, f"{META}'s {LIGHT_COPY} record is malformed (children -> file -> sha256)")
        return LightRecord({})
    if record.get("format") != LIGHT_COPY_FORMAT:
        fc.fail(LIGHT_CHECK, f"{META} records a light copy of format {record.get('format')!r}, this rpbench reads "
                             f"{LIGHT_COPY_FORMAT}")  # fmt: skip
        return LightRecord({})
    for name in sorted(set(children) - set(listed)):
        fc.fail(LIGHT_CHECK, f"{META}'s {LIGHT_COPY} record names {name}/, which is not a child it lists")
    fc.checked["light_children"] = len(children)
    return LightRecord({str(k): dict(v) for k, v in children.items()})


def is_light(child: Path) -> bool:
    """Whether ``child`` is a published light copy (no runs, the verdict beside its tables)."""
    return not (child / RUNS).is_dir() and (child / CHECK).is_file()


def check_light_child(
    child: Path, name: str, record: LightRecord | None, among_full: bool = False, lone: bool = False
) -> FolderResult:
    """The checks a light child supports (see the module docstring); never raises.  ``lone``: the published
    copy of a single run, which no parent holds a record of."""
    fc = RunCheck(FOLDER)
    if record is not None:
        _check_digests(fc, child, name, record)
    elif lone:
        fc.skip(LIGHT_CHECK, f"the published copy of one run: no parent records the SHA-256 of its files, so its "
                             f"{KPIS} edited together with its report and {CHECK} is not caught (rerun the command "
                             f"in its {META} to check the runs again)")  # fmt: skip
    elif among_full:
        fc.fail(LIGHT_CHECK, "a light copy among full folders, and its parent records no digest of it: its runs "
                             "were removed after it was written")  # fmt: skip
    else:
        fc.skip(LIGHT_CHECK, f"published before rpbench recorded the digests of its light children in the "
                             f"parent's {META}: an edit of its {KPIS} with the parent's tables recomputed from it "
                             "is not caught (republish it from the full folder)")  # fmt: skip
    try:
        meta = results.read_meta(child)
        reported = results.read_csv(child / KPIS)
    except RpbenchError as exc:
        fc.fail(LIGHT_CHECK, one_line(exc))
        return FolderResult(str(child), folder_check=fc)
    runs = recorded_runs(meta)
    _check_verdict(fc, child, runs)
    stray = sorted(set(map(str, reported.get("run", []))) ^ set(runs))
    if stray:
        fc.fail("manifest", f"{KPIS} and {META} disagree on the runs {', '.join(map(repr, stray))}")
    fc.checked["runs"] = len(runs)
    check_report(fc, child)
    fc.skip("runs", LIGHT_NOTE)
    return FolderResult(str(child), folder_check=fc)


def _check_digests(fc: RunCheck, child: Path, name: str, record: LightRecord) -> None:
    recorded = record.children.get(name)
    if recorded is None:
        fc.fail(LIGHT_CHECK, f"the parent's {LIGHT_COPY} record has no digests of {name}/")
        return
    for file in LIGHT_CHILD_FILES:
        path = child / file
        if file not in recorded:
            fc.fail(LIGHT_CHECK, f"the parent's {LIGHT_COPY} record has no digest of {name}/{file}")
        elif not path.is_file():
            fc.fail(LIGHT_CHECK, f"{file} is missing (the parent records the SHA-256 it was published with)")
        elif file_sha256(path) != recorded[file]:
            fc.fail(LIGHT_CHECK, f"{file} is not the file published (its SHA-256 differs from the parent's record)")
    fc.checked["published_files"] = len(LIGHT_CHILD_FILES)


def _check_verdict(fc: RunCheck, child: Path, runs: list[str]) -> None:
    """check.txt says every check of the full folder passed, for the folder and for each of ``runs``."""
    path = child / CHECK
    if not path.is_file():
        fc.fail(VERDICT_CHECK, f"the light copy has no {CHECK}, the checker's verdict on the full folder")
        return
    lines = path.read_text(errors="replace").splitlines()
    if not lines or lines[0] != VERDICT_HEADER or any(": FAILED" in line for line in lines):
        fc.fail(VERDICT_CHECK, f"{CHECK} is not the verdict of a full folder that passed every check")
        return
    passed = {line.split(": OK", 1)[0] for line in lines if ": OK" in line and not line.startswith(" ")}
    lost = [run for run in [FOLDER, *runs] if run not in passed]
    if lost:
        fc.fail(VERDICT_CHECK, f"{CHECK} gives no passing verdict on {', '.join(lost)}")
    fc.checked["verdicts"] = len(runs) + 1
