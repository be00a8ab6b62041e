"""Light copies of verified results folders for ``results/`` (``rpbench publish``).

A results folder holds everything the checker needs — orders, network,
fleet, every event log and trajectory — tens of megabytes for a full day.
The published copy keeps what a reader needs (``meta.json``, KPI tables,
per-round solver statistics with timings rounded to 1 µs, reports, plots) plus ``check.txt``, the
checker's verdict on the full folder, written only when every check
passed: a failing run is never published.  Re-running the command in
``meta.json`` regenerates the full folder: it is recorded with the published
folder's name as ``--out``, not the scratch folder it ran in.

A parent's light copy (multi-day, sweep, evaluation) also records in its meta.json the SHA-256 of what each
child keeps that the parent's tables are recomputed from (``light_copy``: kpis.csv, meta.json, check.txt), so
that ``rpbench check`` of the copy recomputes the parent's tables from children it proves unedited; the copy
is checked so before it is moved into place.

What is published is what was checked: the source is first copied whole into a staging folder beside
DEST (``.DEST.partial-PID-XXXX``, private to this process), the checker runs on that snapshot, and the
light copy, its reports and its page are made from it, so a source changing meanwhile cannot slip in
unchecked files.  Publishing copies bytes, never links: a symbolic link anywhere in the source (to a file
or a folder, inside the folder or out of it) or a special file is refused before anything is read or
written (rpbench writes no links; a link to a file outside would publish that file's content).  One
publish to a DEST at a time: a second one fails at once (a lock file ``.DEST.publish.lock``, removed
afterwards), and the snapshot is renamed into place only while DEST does not exist.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shlex
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rpbench.check import check_tree, format_report
from rpbench.check.light import VERDICT_HEADER
from rpbench.exceptions import ResultsError
from rpbench.harness.multiday import write_multiday_report
from rpbench.harness.sweep import write_sweep_report
from rpbench.report.comparison import write_report
from rpbench.report.evaluation import write_evaluation_report
from rpbench.report.html import write_html
from rpbench.results import layout
from rpbench.results.digest import LIGHT_COPY, light_copy_record
from rpbench.results.layout import HEAVY, PARENT_KINDS
from rpbench.results.store import make_parents, read_meta, remove_empty, remove_stale_partials, write_json

#: A published page larger than this (its map: a full day's trips) is published without its map, and one
#: still larger (its plotting library is 1.9 MB of it) not at all; the full folder's page, which the recorded
#: command regenerates, has everything.
PAGE_BUDGET_BYTES = 2 * 1024 * 1024


def publish(source: str | Path, dest: str | Path) -> Path:
    """Check ``source`` (a run, multi-day or sweep folder) and write its light copy to ``dest``."""
    source, dest = Path(source), Path(dest)
    if not source.is_dir():
        raise ResultsError(f"results folder {str(source)!r} does not exist")
    root = source.resolve()
    refuse_links(root, source)  # before the checker, which would read through them
    if Path(os.path.abspath(dest.parent)).resolve().is_relative_to(root):
        raise ResultsError(f"{str(dest)!r} is inside the results folder {str(source)!r}; publish it elsewhere")
    _check_free(dest)
    created = make_parents(dest.parent, dest)
    try:
        with _only_publish_to(dest):
            _check_free(dest)  # published meanwhile by a publish that has finished
            remove_stale_partials(dest.parent)
            staging = Path(tempfile.mkdtemp(prefix=f".{dest.name}.partial-{os.getpid()}-", dir=dest.parent))
            try:
                light = _stage(source, root, dest, staging)
                _move_into_place(light, dest)
            finally:
                shutil.rmtree(staging, ignore_errors=True)
    except BaseException:
        remove_empty(created)
        raise
    return dest


def refuse_links(root: Path, shown: Path) -> None:
    """One :class:`ResultsError` line naming the first symbolic link or special file below ``root``
    (``shown`` is how the user named ``root``); folders are walked without following links."""

    def fail(error: OSError) -> None:
        raise error

    for folder, dirs, files in os.walk(root, onerror=fail):
        for name in sorted(dirs + files):
            path = Path(folder, name)
            mode = path.lstat().st_mode
            where = str(shown / path.relative_to(root))
            if stat.S_ISLNK(mode):
                target = os.readlink(path)
                if not path.resolve().is_relative_to(root.resolve()):
                    raise ResultsError(
                        f"{where!r} is a symbolic link to {target!r}, outside the results folder; publish never "
                        "copies what a link points to, nothing was written"
                    )
                raise ResultsError(
                    f"{where!r} is a symbolic link (to {target!r}); publish copies only files and folders: "
                    "replace the link by what it points to, nothing was written"
                )
            if not (stat.S_ISDIR(mode) or stat.S_ISREG(mode)):
                raise ResultsError(f"{where!r} is not a file nor a folder; nothing was written")


def _check_free(dest: Path) -> None:
    if os.path.lexists(dest):
        raise ResultsError(f"{str(dest)!r} already exists; publish never overwrites")


@contextlib.contextmanager
def _only_publish_to(dest: Path) -> Iterator[None]:
    """Hold ``.DEST.publish.lock`` (flock: the kernel releases it when this process dies, even by SIGKILL);
    a publish finding it held fails at once."""
    lock = dest.with_name(f".{dest.name}.publish.lock")
    busy = ResultsError(f"another publish to {str(dest)!r} is running; nothing was written")
    fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise busy from None
        try:
            same = os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if not same:  # its holder removed the file after we opened it: a newer publish may hold a new one
            raise busy
        try:
            yield
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(lock)  # while holding it: a publish that opened this file meanwhile sees it gone
    finally:
        os.close(fd)


def _move_into_place(light: Path, dest: Path) -> None:
    # rename would replace an empty folder made at DEST meanwhile (by something else than a publish)
    _check_free(dest)
    try:
        os.rename(light, dest)
    except OSError:
        if os.path.lexists(dest):
            raise ResultsError(f"{str(dest)!r} appeared while publishing; publish never overwrites") from None
        raise


def _stage(source: Path, root: Path, dest: Path, staging: Path) -> Path:
    """Snapshot ``root`` into ``staging``, check the snapshot and build its light copy there; returns it."""
    full, tmp = staging / "full", staging / "light"
    shutil.copytree(root, full, symlinks=True)  # a link made since refuse_links is copied as a link, not followed
    refuse_links(full, source)
    base = Path(os.path.abspath(source))

    def shown(folder: str | Path) -> str:
        return str(base / Path(folder).relative_to(full))

    verdicts = []
    for result in check_tree(full):  # a parent's own checks (deleted days, tables) gate it too
        if result.error is not None:
            error = result.error.replace(str(full), str(base))
            raise ResultsError(f"{shown(result.folder)!r} cannot be checked ({error}); not published")
        bad = [c.run for c in result.checks if not c.ok]
        if bad:
            raise ResultsError(f"{shown(result.folder)!r} fails rpbench check ({', '.join(bad)}); not published")
        if result.runs:
            verdicts.append((Path(result.folder).relative_to(full), format_report(result.checks)))
    shutil.copytree(full, tmp, ignore=shutil.ignore_patterns(*HEAVY))
    for rounds in tmp.rglob(layout.ROUNDS):
        _shrink_rounds(rounds)
    for folder in (tmp, full):  # the snapshot too: the pages drawn from it show the command as published
        for meta in folder.rglob(layout.META):  # the folder and each day's or point's
            _record_published_command(meta, dest.name)
    # reports re-rendered from the copy say it is a light copy (and point to check.txt)
    kind = read_meta(tmp).get("kind")  # the multi-day or sweep summary, under the published name
    # the days, points or units of a parent (tens of them) keep their tables and report but no page: the
    # parent's page summarises them and links each report, and a page is megabytes (its plotting library);
    # an evaluation's units keep no figures either
    children = {Path(child) for child in read_meta(tmp).get("children", [])}
    for rel, _ in verdicts:
        copy, name = tmp / rel, (base / rel).name
        if rel in children:
            write_report(copy, name, figures=kind != "evaluate")
            (copy / layout.REPORT_HTML).unlink(missing_ok=True)
            continue
        write_report(copy, name)
        # the page is drawn from the full snapshot: its map needs the event logs the copy leaves out
        page = write_html(full / rel, name, dest=copy, published=True)
        if page.stat().st_size > PAGE_BUDGET_BYTES:  # drawn again from the copy: no map, saying why
            page = write_html(copy, name, published=True)
        if page.stat().st_size > PAGE_BUDGET_BYTES:  # its plotting library and data alone: report.md only
            page.unlink()
    if kind == "multi-day":
        write_multiday_report(tmp, name=dest.name)
    elif kind == "sweep":
        write_sweep_report(tmp, name=dest.name)
    elif kind == "evaluate":
        write_evaluation_report(tmp, name=dest.name)
    if kind in ("multi-day", "sweep", "evaluate"):
        write_html(tmp, name=dest.name)
    for rel, text in verdicts:
        (tmp / rel / layout.CHECK).write_text(f"{VERDICT_HEADER}\n\n{text}\n")
    if kind in PARENT_KINDS:
        _record_light_children(tmp, [rel.as_posix() for rel, _ in verdicts if rel != Path(".")])
        _check_light_copy(tmp, base)
    return tmp


def _record_light_children(light: Path, children: list[str]) -> None:
    """The parent's record of what its light children keep (:func:`~rpbench.results.digest.light_copy_record`),
    made last, over the files as published."""
    meta = read_meta(light)
    meta[LIGHT_COPY] = light_copy_record(light, children)
    write_json(light / layout.META, meta)


def _check_light_copy(light: Path, source: Path) -> None:
    """The light copy passes ``rpbench check`` as a light copy: its tables against the children it keeps, each
    as its parent's record has it (``source``: the folder published, to name a failing one)."""
    for result in check_tree(light):
        bad = [c.run for c in result.checks if not c.ok]
        if result.error is not None or bad:
            where = str(source / Path(result.folder).relative_to(light))
            raise ResultsError(
                f"the light copy of {where!r} fails rpbench check ({result.error or ', '.join(bad)}); not published"
            )


def published_command(command: str, name: str) -> str:
    """``command`` as a reader reruns it: ``--out`` names the published folder ``name`` instead of the scratch
    folder it ran in, and ``--data DIR`` (a path of the machine it ran on) is dropped: rpbench finds the data
    folder by itself (``rpbench data fetch``)."""
    try:
        words = shlex.split(command)
    except ValueError:  # not shell words: keep it as it is
        return command
    out: list[str] = []
    skip = False
    for i, word in enumerate(words):
        if skip:
            skip = False
            continue
        option, eq, _ = word.partition("=")
        if option in ("--out", "--data"):
            skip = not eq and i + 1 < len(words)
            if option == "--out":
                out += ["--out", name]
            continue
        out.append(word)
    return " ".join(shlex.quote(w) for w in out)


def _record_published_command(path: Path, name: str) -> None:
    meta = read_meta(path.parent)
    if isinstance(meta.get("command"), str):
        meta["command"] = published_command(meta["command"], name)
        write_json(path, meta)


def _shrink_rounds(path: Path) -> None:
    """Round per-round timings to 1 µs and objectives to 1 mm (the model unit): half the size, no lost meaning."""
    import pandas as pd

    rounds = pd.read_csv(path)
    timings = [c for c in ("strategy_build_s", "solver_build_s", "solve_s", "extract_s") if c in rounds]
    rounds[timings] = rounds[timings].round(6)
    if "objective_m" in rounds:
        rounds["objective_m"] = rounds["objective_m"].round(3)
    rounds.to_csv(path, index=False)
