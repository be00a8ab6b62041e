"""Model benchmark: solve a list of models with each preset, cross-check, tabulate.

:func:`run_benchmark` takes any models (synthetic ones from
:mod:`rpbench.bench.synthetic`, or snapshot instance files read by
:func:`rpbench.instances.load_instances`) and returns a tidy
:class:`pandas.DataFrame`, one row per (model, preset):

* ``build_s`` / ``solve_s`` / ``extract_s`` as the backend measured them,
  from the fastest of ``repeat`` runs; ``wall_s`` is that run's whole call;
* ``status`` as the backend reported it (``time_limit`` is a result, not a
  failure), or ``killed`` when the solve overran ``hard_timeout_s`` and its
  worker process was killed, or ``error`` with the message;
* ``agrees``: whether the objective equals the proven optimum of the model
  (values are integral, so "equal" is exact).  ``False`` for a proven
  optimum that differs from another preset's, or for any solution claiming
  more than the optimum — a solver bug.  ``None`` when nothing is proven.
  An instance frozen from a run may carry the optimum that run's preset
  proved (``recorded``); it counts as one more proven optimum.

Each preset is warmed up on a tiny model first so library imports are not
timed.  With ``isolate=True`` (the default of ``rpbench bench``) every
preset runs in its own spawned worker process, killed and restarted when a
solve overruns its hard timeout: some solvers (HiGHS on 50,000-order
pairings) check their time limit too rarely to stop on time.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from multiprocessing.context import SpawnProcess
from typing import Any

import numpy as np
import pandas as pd

from rpbench.backends import Preset, load_preset, preset_names, solve
from rpbench.bench.synthetic import assignment, pairing, trip_packing
from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.model import Model, Status

COLUMNS = [
    "model",
    "structure",
    "rows",
    "cols",
    "nonzeros",
    "preset",
    "backend",
    "status",
    "objective",
    "bound",
    "gap",
    "pairs",
    "recorded",
    "agrees",
    "build_s",
    "solve_s",
    "extract_s",
    "total_s",
    "wall_s",
    "repeats",
    "message",
]


def installed_presets(names: Iterable[str] | None = None) -> list[Preset]:
    """The named presets (default: every preset in solvers/) whose backend is installed."""
    presets = [load_preset(n) for n in (preset_names() if names is None else names)]
    return [p for p in presets if p.is_installed()]


def run_benchmark(
    models: Sequence[Model],
    presets: Sequence[str | Preset] | None = None,
    *,
    time_limit_s: float | None = None,
    time_limits: dict[str, float] | None = None,
    repeat: int = 1,
    isolate: bool = False,
    hard_timeout_s: float | None = None,
    progress: Callable[[str], None] | None = None,
    recorded: dict[str, float] | None = None,
) -> pd.DataFrame:
    """Solve every model with every preset; one row per pair (see the module docstring).

    ``time_limit_s`` overrides every preset's limit, ``time_limits`` single
    presets' (by name).  ``hard_timeout_s`` (only with ``isolate``) defaults
    to twice the solve's time limit plus 30 s.  ``recorded`` maps model names
    to optima proven elsewhere (e.g. by the run a snapshot was taken from).
    """
    if not isinstance(repeat, int) or repeat < 1:
        raise ParameterError(f"repeat = {repeat!r} must be an integer >= 1")
    chosen = (
        installed_presets(None)
        if presets is None
        else [p if isinstance(p, Preset) else load_preset(p) for p in presets]
    )
    rows = []
    for preset in chosen:
        limit = (time_limits or {}).get(
            preset.name, time_limit_s if time_limit_s is not None else preset.options.time_limit_s
        )
        preset = replace(preset, options=replace(preset.options, time_limit_s=limit))
        hard = hard_timeout_s if hard_timeout_s is not None else (2 * limit + 30 if limit else None)
        runner = _Worker(preset, hard) if isolate else _Inline(preset)
        try:
            for model in models:
                if progress:
                    progress(f"{preset.name:<12} {model.name}")
                row = _row(model, preset, runner.run(model, repeat))
                row["recorded"] = (recorded or {}).get(model.name, math.nan)
                rows.append(row)
        finally:
            runner.close()
    table = pd.DataFrame(rows, columns=COLUMNS)
    order = {m.name: i for i, m in enumerate(models)}
    table = table.sort_values("model", key=lambda col: col.map(order), kind="stable").reset_index(drop=True)
    return cross_check(table)


def cross_check(table: pd.DataFrame) -> pd.DataFrame:
    """Fill ``agrees`` by comparing every row with the proven optima of its model."""
    table = table.copy()
    agrees: list[bool | None] = []
    for _, r in table.iterrows():
        same = table[(table["model"] == r["model"]) & (table["status"] == Status.OPTIMAL.value)]
        optima = set(same["objective"])
        if "recorded" in table and pd.notna(r["recorded"]):
            optima.add(float(r["recorded"]))
        if r["status"] in ("error", "killed") or not optima:
            agrees.append(None)
        elif len(optima) > 1:
            agrees.append(False)  # two "optimal" answers differ
        elif r["status"] == Status.OPTIMAL.value:
            agrees.append(True)
        else:
            agrees.append(False if r["objective"] > next(iter(optima)) else None)
    table["agrees"] = pd.array(agrees, dtype="boolean")
    return table


def _row(model: Model, preset: Preset, result: dict) -> dict:
    size = model.size
    return {
        "model": model.name,
        "structure": model.structure.value,
        "rows": size["rows"],
        "cols": size["cols"],
        "nonzeros": size["nonzeros"],
        "preset": preset.name,
        "backend": preset.backend,
        "agrees": None,
        **result,
    }


def _solve_once(preset: Preset, model: Model, repeat: int) -> dict:
    """The fastest of ``repeat`` solves, as a row fragment (errors, an infeasible answer among them, become
    status ``error``)."""
    best: dict[str, Any] = {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        try:
            sol = solve(model, preset)  # verified there
        except RpbenchError as exc:
            return _failure("error", str(exc))
        wall = time.perf_counter() - t0
        row: dict[str, Any] = {
            "status": sol.status.value,
            "objective": sol.objective,
            "bound": sol.bound,
            "gap": sol.gap,
            "pairs": sol.cardinality,
            "build_s": sol.build_s,
            "solve_s": sol.solve_s,
            "extract_s": sol.extract_s,
            "total_s": sol.total_s,
            "wall_s": wall,
            "message": sol.message,
        }
        if not best or row["total_s"] < best["total_s"]:
            best = row
        if sol.status is not Status.OPTIMAL:
            break  # a time-limited run is not repeated
    best["repeats"] = repeat if best["status"] == Status.OPTIMAL.value else 1
    return best


def _failure(status: str, message: str) -> dict:
    nan = math.nan
    return {
        "status": status,
        "objective": nan,
        "bound": nan,
        "gap": nan,
        "pairs": 0,
        "build_s": nan,
        "solve_s": nan,
        "extract_s": nan,
        "total_s": nan,
        "wall_s": nan,
        "repeats": 0,
        "message": message,
    }


def _warm_up(preset: Preset) -> None:
    """Import the solver library and touch its code paths outside the timings."""
    for model in (assignment(3, 4, seed=1), pairing(12, partners=4, seed=1), trip_packing(4, 3, seed=1)):
        with contextlib.suppress(RpbenchError):
            solve(model, preset)


class _Inline:
    """Runs solves in this process."""

    def __init__(self, preset: Preset) -> None:
        self.preset, self.error = preset, None
        try:
            preset.adapter().ensure_installed()
            _warm_up(preset)
        except RpbenchError as exc:
            self.error = str(exc)

    def run(self, model: Model, repeat: int) -> dict:
        if self.error is not None:
            return _failure("error", self.error)
        return _solve_once(self.preset, model, repeat)

    def close(self) -> None:
        pass


def _worker_main(conn, preset: Preset) -> None:
    inline = _Inline(preset)
    conn.send("ready")
    while True:
        job = conn.recv()
        if job is None:
            return
        model, repeat = job
        conn.send(inline.run(model, repeat))


class _Worker:
    """Runs solves in a spawned process; a solve past the hard timeout kills it (status ``killed``)."""

    def __init__(self, preset: Preset, hard_timeout_s: float | None) -> None:
        self.preset, self.hard = preset, hard_timeout_s
        self.proc: SpawnProcess | None = None

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")  # a clean process: no solver threads inherited
        self.conn, child = ctx.Pipe()
        # not a daemon: the matching backend forks its own child to enforce time limits
        self.proc = ctx.Process(target=_worker_main, args=(child, self.preset))
        self.proc.start()
        child.close()
        self.conn.recv()  # warmed up

    def run(self, model: Model, repeat: int) -> dict:
        try:
            if self.proc is None:
                self._start()
            self.conn.send((model, repeat))
        except (EOFError, BrokenPipeError, OSError):
            self.close()
            return _failure("error", "the worker process died while starting")
        timeout = None if self.hard is None else self.hard * repeat
        if self.conn.poll(timeout):
            try:
                return self.conn.recv()
            except EOFError:
                message = "the worker process died"
        else:
            message = f"killed after {timeout:g} s (hard timeout; the solver did not stop at its time limit)"
        self.close()
        return _failure("killed", message)

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.is_alive():
                try:
                    self.conn.send(None)
                    self.proc.join(2)
                except (BrokenPipeError, OSError):
                    pass
            if self.proc.is_alive():
                self.proc.kill()
            self.proc.join()
            self.proc = None


# ------------------------------------------------------------------ printing
def format_table(table: pd.DataFrame) -> str:
    """A plain-text table: one line per (model, preset) with the model's size, times in milliseconds."""
    w = max([len("model"), *map(len, table["model"])])
    sizes = [f"{r:,} x {c:,}" for r, c in zip(table["rows"], table["cols"], strict=True)]
    sw = max([len("rows x cols"), *map(len, sizes)])
    head = (
        f"{'model':<{w}} {'rows x cols':>{sw}} {'preset':<12} {'status':<10} {'objective':>16} {'gap':>8} "
        f"{'build ms':>10} {'solve ms':>10} {'total ms':>10}  agrees"
    )
    lines = [head, "-" * len(head)]
    for size, (_, r) in zip(sizes, table.iterrows(), strict=True):

        def ms(x):
            return "-" if x is None or (isinstance(x, float) and np.isnan(x)) else f"{1000 * x:,.1f}"

        gap = "-" if r["gap"] is None or pd.isna(r["gap"]) else f"{r['gap']:.1e}"
        obj = "-" if pd.isna(r["objective"]) else f"{r['objective']:,.0f}"
        agree = "-" if pd.isna(r["agrees"]) else "yes" if bool(r["agrees"]) else "NO"
        lines.append(
            f"{r['model']:<{w}} {size:>{sw}} {r['preset']:<12} {r['status']:<10} {obj:>16} {gap:>8} "
            f"{ms(r['build_s']):>10} {ms(r['solve_s']):>10} {ms(r['total_s']):>10}  {agree}"
        )
    return "\n".join(lines)
