"""Model benchmark: solve a list of models with each preset, cross-check, tabulate.

:func:`run_benchmark` takes any models (synthetic ones from
:mod:`rpbench.bench.synthetic`, or snapshot instance files read by
:func:`rpbench.model.instances.load_instances`) and returns a tidy
:class:`pandas.DataFrame`, one row per (model, preset):

* ``build_s`` / ``solve_s`` / ``extract_s`` as the backend measured them,
  from the fastest of ``repeat`` runs; ``wall_s`` is that run's whole call;
  ``total_s`` is the fastest run's total and ``total_s_min`` / ``_median`` /
  ``_max`` the spread of every run's total (a time-limited run is not
  repeated); ``time_limit_s`` is the limit the preset ran with;
* ``status`` as the backend reported it (``time_limit`` is a result, not a
  failure), or ``killed`` when the solve overran ``hard_timeout_s`` and its
  worker process was killed, ``memory_limit`` when it ran out of memory
  (a ``MemoryError``, or an isolated worker that died under its memory
  limit), or ``error`` with the message;
* ``agrees``: whether the objective equals the proven optimum of the model
  (values are integral, so "equal" is exact).  ``False`` for a proven
  optimum that differs from another preset's, or for any solution claiming
  more than the optimum — a solver bug.  ``None`` when nothing is proven.
  An instance frozen from a run may carry the optimum that run's preset
  proved (``recorded``); it counts as one more proven optimum;
* ``verdict`` (:func:`cross_check`): ``optimal`` (proven, and right),
  ``wrong``, ``time_limit``, ``feasible`` (stopped at a gap),
  ``infeasible`` (claimed so, nothing known against it), ``memory_limit``,
  ``error`` or ``killed``.  Known values of a ``.solu`` file
  (:mod:`rpbench.results.solu`) decide when they are given;
* ``tier``: the instance's size tier (``all`` when it has none).

Each preset is warmed up on a tiny model first so library imports are not
timed.  With ``isolate=True`` (the default of ``rpbench bench``) every
preset runs in its own spawned worker process, killed and restarted when a
solve overruns its hard timeout: some solvers (HiGHS on 50,000-order
pairings) check their time limit too rarely to stop on time.  A memory
limit (``memory_limit_gb``, isolated only) caps the worker's address space
(``RLIMIT_AS``) before it solves.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing
import resource
import signal
import statistics
import sys
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from multiprocessing.context import SpawnProcess
from typing import Any

import numpy as np
import pandas as pd

from rpbench.backends import Preset, load_preset, preset_names, solve
from rpbench.bench.synthetic import assignment, pairing, trip_packing
from rpbench.exceptions import ParameterError, RpbenchError
from rpbench.model import Model, Status
from rpbench.report.bench import NO_TIER
from rpbench.results.solu import Known

RESULT_COLUMNS = [
    "model",
    "tier",
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
    "verdict",
    "build_s",
    "solve_s",
    "extract_s",
    "total_s",
    "total_s_min",
    "total_s_median",
    "total_s_max",
    "wall_s",
    "repeats",
    "time_limit_s",
    "message",
]
#: Every ``verdict`` of a row; only ``optimal`` counts as solved.
VERDICTS = ("optimal", "wrong", "time_limit", "feasible", "infeasible", "memory_limit", "error", "killed")
#: Bytes of the ``memory_limit_gb`` unit.
GB = 2**30
#: Relative tolerance when an objective is compared with a known value (both are integral sums; this only
#: absorbs a value written with a few digits fewer than a float holds).
KNOWN_RTOL = 1e-9


def installed_presets(names: Iterable[str] | None = None) -> list[Preset]:
    """The named presets (default: every preset in solvers/) whose backend is installed."""
    presets = [load_preset(n) for n in (preset_names() if names is None else names)]
    return [p for p in presets if p.is_installed()]


@dataclass(frozen=True)
class BenchSpec:
    """How a benchmark solves its models, and what it judges the answers against (checked once, here).

    ``presets``: names or presets (None: every installed preset); ``time_limit_s`` overrides every preset's
    limit, ``time_limits`` single presets' (by name); ``repeat`` solves per (model, preset), the fastest
    kept; ``isolate``: each preset in a worker process of its own, killed after ``hard_timeout_s`` (default:
    twice the solve's time limit plus 30 s) and capped at ``memory_limit_gb`` (GB of 2**30 bytes) of address
    space.  ``recorded`` maps model names to optima proven elsewhere (e.g. by the run a snapshot was taken
    from), ``known`` to the values of a ``.solu`` file, ``tiers`` to size tiers.
    """

    presets: Sequence[str | Preset] | None = None
    time_limit_s: float | None = None
    time_limits: Mapping[str, float] = field(default_factory=dict)
    repeat: int = 1
    isolate: bool = False
    hard_timeout_s: float | None = None
    memory_limit_gb: float | None = None
    recorded: Mapping[str, float] = field(default_factory=dict)
    known: Mapping[str, Known] = field(default_factory=dict)
    tiers: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.repeat, int) or self.repeat < 1:
            raise ParameterError(f"repeat = {self.repeat!r} must be an integer >= 1")
        if self.memory_limit_gb is not None:
            if not self.isolate:
                raise ParameterError("a memory limit caps an isolated worker; it needs isolate=True")
            if not (math.isfinite(self.memory_limit_gb) and self.memory_limit_gb > 0):
                raise ParameterError(f"memory_limit_gb = {self.memory_limit_gb!r} must be a positive number")

    def chosen(self) -> list[Preset]:
        """The presets, loaded, each with the time limit it runs under."""
        presets = (
            installed_presets(None)
            if self.presets is None
            else [p if isinstance(p, Preset) else load_preset(p) for p in self.presets]
        )
        return [replace(p, options=replace(p.options, time_limit_s=self.limit_of(p))) for p in presets]

    def limit_of(self, preset: Preset) -> float | None:
        """The time limit ``preset`` solves under."""
        default = self.time_limit_s if self.time_limit_s is not None else preset.options.time_limit_s
        return self.time_limits.get(preset.name, default)


def run_benchmark(models: Sequence[Model], spec: BenchSpec, *, progress: bool | None = False) -> pd.DataFrame:
    """Solve every model with every preset of ``spec``; one row per pair (see the module docstring).
    ``progress``: a bar on stderr (``None``: when stderr is a terminal)."""
    chosen = spec.chosen()
    bar = _bar(len(chosen) * len(models), progress)
    rows = []
    try:
        for preset in chosen:
            limit = preset.options.time_limit_s
            hard = spec.hard_timeout_s if spec.hard_timeout_s is not None else (2 * limit + 30 if limit else None)
            runner = IsolatedWorker(preset, hard, spec.memory_limit_gb) if spec.isolate else _Inline(preset)
            try:
                for model in models:
                    if bar is not None:
                        bar.set_postfix_str(f"{preset.name} {model.name}", refresh=False)
                    row = _row(model, preset, runner.run(model, spec.repeat))
                    row["recorded"] = spec.recorded.get(model.name, math.nan)
                    row["tier"] = spec.tiers.get(model.name, NO_TIER)
                    row["time_limit_s"] = math.nan if limit is None else float(limit)
                    rows.append(row)
                    if bar is not None:
                        bar.update()
            finally:
                runner.close()
    finally:
        if bar is not None:
            bar.close()
    table = pd.DataFrame(rows, columns=RESULT_COLUMNS)
    order = {m.name: i for i, m in enumerate(models)}
    table = table.sort_values("model", key=lambda col: col.map(order), kind="stable").reset_index(drop=True)
    return cross_check(table, spec.known)


def _bar(total: int, enabled: bool | None) -> Any:
    """One tqdm bar on stderr that leaves nothing behind (off when stderr is not a terminal, for ``None``)."""
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled or total == 0:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc="bench", unit="solve", leave=False, file=sys.stderr, dynamic_ncols=True)


def cross_check(table: pd.DataFrame, known: Mapping[str, Known] | None = None) -> pd.DataFrame:
    """Fill ``agrees`` by comparing every row with the proven optima of its model, and ``verdict`` (see
    :func:`verdict`) from those and the ``known`` values (by model name)."""
    table = table.copy()
    agrees: list[bool | None] = []
    verdicts: list[str] = []
    for i, r in table.iterrows():
        same = table[(table["model"] == r["model"]) & (table["status"] == Status.OPTIMAL.value)]
        optima = set(same["objective"])
        peers = [float(v) for v in same.drop(index=i, errors="ignore")["objective"]]
        if "recorded" in table and pd.notna(r["recorded"]):
            optima.add(float(r["recorded"]))
            peers.append(float(r["recorded"]))
        if r["status"] in ("error", "killed", "memory_limit") or not optima:
            agrees.append(None)
        elif len(optima) > 1:
            agrees.append(False)  # two "optimal" answers differ
        elif r["status"] == Status.OPTIMAL.value:
            agrees.append(True)
        else:
            agrees.append(False if r["objective"] > next(iter(optima)) else None)
        verdicts.append(verdict(r["status"], r["objective"], peers, (known or {}).get(r["model"])))
    table["agrees"] = pd.array(agrees, dtype="boolean")
    table["verdict"] = verdicts
    return table


def verdict(status: str, objective: float, peers: Sequence[float], known: Known | None) -> str:
    """The verdict of one answer: ``status`` and ``objective`` as reported, ``peers`` the optima the other
    presets proved on the model (and the one recorded with it), ``known`` its ``.solu`` value.

    ``wrong`` is any answer that contradicts what is known: a proven optimum unequal to ``=opt=``, below
    ``=best=`` or above ``=bound=``; any solution of an ``=inf=`` instance; an objective above a known or
    proven optimum; an infeasibility claim where a solution is known.  Without ``=opt=`` a proven optimum
    must equal every other proven optimum of the model (when two differ both are ``wrong``: nothing tells
    which is right).  Otherwise the status decides: ``optimal``, ``time_limit``, ``feasible`` (stopped at a
    gap), ``infeasible`` (an ``=inf=`` instance proven infeasible is ``optimal``), and the failures
    ``memory_limit``, ``error``, ``killed``.
    """
    if status in ("error", "killed", "memory_limit"):
        return status
    kind = known.kind if known is not None else "unkn"
    value = known.value if known is not None else None
    if status == Status.INFEASIBLE.value:
        if kind == "inf":
            return "optimal"
        return "wrong" if kind in ("opt", "best") or peers else "infeasible"
    has_solution = not (objective is None or pd.isna(objective))
    if not has_solution:
        return status if status in VERDICTS else "error"
    obj = float(objective)
    if kind == "inf":
        return "wrong"
    proven = status == Status.OPTIMAL.value
    if value is not None:
        if kind == "opt" and (not _same(obj, value) if proven else _above(obj, value)):
            return "wrong"
        if kind == "best" and proven and _above(value, obj):
            return "wrong"  # a solution worth more is known
        if kind == "bound" and _above(obj, value):
            return "wrong"
    if kind != "opt" and peers:
        if proven and any(not _same(obj, p) for p in peers):
            return "wrong"
        if not proven and all(_above(obj, p) for p in peers):
            return "wrong"  # more than every proven optimum
    if proven:
        return "optimal"
    return status if status in VERDICTS else "feasible"


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= KNOWN_RTOL * max(1.0, abs(b))


def _above(a: float, b: float) -> bool:
    return a > b and not _same(a, b)


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


def _solve_once(preset: Preset, model: Model, repeat: int, memory_limit_gb: float | None = None) -> dict:
    """The fastest of ``repeat`` solves, as a row fragment with the spread of all their totals (errors, an
    infeasible answer among them, become status ``error``; running out of memory ``memory_limit``)."""
    best: dict[str, Any] = {}
    totals: list[float] = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        try:
            sol = solve(model, preset)  # verified there
        except RpbenchError as exc:
            return _failure("error", str(exc))
        except MemoryError:
            under = f" under the memory limit of {memory_limit_gb:g} GB" if memory_limit_gb else ""
            return _failure("memory_limit", f"ran out of memory (MemoryError){under}")
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
        totals.append(sol.total_s)
        if not best or row["total_s"] < best["total_s"]:
            best = row
        if sol.status is not Status.OPTIMAL:
            break  # a time-limited run is not repeated
    best["repeats"] = len(totals)
    best["total_s_min"] = min(totals)
    best["total_s_median"] = statistics.median(totals)
    best["total_s_max"] = max(totals)
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
        "total_s_min": nan,
        "total_s_median": nan,
        "total_s_max": nan,
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

    def __init__(self, preset: Preset, memory_limit_gb: float | None = None) -> None:
        self.preset, self.error, self.memory_limit_gb = preset, None, memory_limit_gb
        try:
            preset.adapter().ensure_installed()
            _warm_up(preset)
        except RpbenchError as exc:
            self.error = str(exc)

    def run(self, model: Model, repeat: int) -> dict:
        if self.error is not None:
            return _failure("error", self.error)
        return _solve_once(self.preset, model, repeat, self.memory_limit_gb)

    def close(self) -> None:
        pass


def _limit_memory(gb: float) -> None:
    """Cap this process's address space (and its children's: they inherit it) at ``gb`` GB."""
    limit = int(gb * GB)
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)  # an unprivileged process cannot raise its hard limit
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))


def _worker_main(conn, preset: Preset, memory_limit_gb: float | None = None) -> None:
    inline = _Inline(preset, memory_limit_gb)
    if memory_limit_gb is not None:
        _limit_memory(memory_limit_gb)  # after the warm-up: the imports are not the solve's memory
    conn.send("ready")
    while True:
        job = conn.recv()
        if job is None:
            return
        model, repeat = job
        conn.send(inline.run(model, repeat))


class IsolatedWorker:
    """Runs solves in a spawned process; a solve past the hard timeout kills it (status ``killed``), a worker
    that dies under a memory limit reports ``memory_limit``."""

    def __init__(self, preset: Preset, hard_timeout_s: float | None, memory_limit_gb: float | None = None) -> None:
        self.preset, self.hard, self.memory = preset, hard_timeout_s, memory_limit_gb
        self.proc: SpawnProcess | None = None

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")  # a clean process: no solver threads inherited
        self.conn, child = ctx.Pipe()
        # not a daemon: the matching backend forks its own child to enforce time limits
        self.proc = ctx.Process(target=_worker_main, args=(child, self.preset, self.memory))
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
        status = "killed"
        if self.conn.poll(timeout):
            try:
                return self.conn.recv()
            except EOFError:
                message = f"the worker process died ({self._exit()})"
                if self.memory is not None:
                    # RLIMIT_AS makes an allocation fail; C++ solver code often aborts on that
                    status = "memory_limit"
                    message += f" under the memory limit of {self.memory:g} GB"
        else:
            message = f"killed after {timeout:g} s (hard timeout; the solver did not stop at its time limit)"
        self.close()
        return _failure(status, message)

    def _exit(self) -> str:
        """How the worker ended: its signal or exit code."""
        if self.proc is None:
            return "gone"
        self.proc.join(5)
        code = self.proc.exitcode
        if code is None:
            return "still running"
        if code < 0:
            with contextlib.suppress(ValueError):
                return f"signal {signal.Signals(-code).name}"
        return f"exit code {code}"

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
    """A plain-text table: one line per (model, preset) with the model's size, times in milliseconds (the
    fastest run), the agreement with the other presets and the verdict."""
    w = max([len("model"), *map(len, table["model"])])
    sizes = [f"{r:,} x {c:,}" for r, c in zip(table["rows"], table["cols"], strict=True)]
    sw = max([len("rows x cols"), *map(len, sizes)])
    head = (
        f"{'model':<{w}} {'rows x cols':>{sw}} {'preset':<12} {'status':<12} {'objective':>16} {'gap':>8} "
        f"{'build ms':>10} {'solve ms':>10} {'total ms':>10}  agrees  verdict"
    )
    lines = [head, "-" * len(head)]
    for size, (_, r) in zip(sizes, table.iterrows(), strict=True):

        def ms(x):
            return "-" if x is None or (isinstance(x, float) and np.isnan(x)) else f"{1000 * x:,.1f}"

        gap = "-" if r["gap"] is None or pd.isna(r["gap"]) else f"{r['gap']:.1e}"
        obj = "-" if pd.isna(r["objective"]) else f"{r['objective']:,.0f}"
        agree = "-" if pd.isna(r["agrees"]) else "yes" if bool(r["agrees"]) else "NO"
        judged = r["verdict"] if "verdict" in table else "-"
        lines.append(
            f"{r['model']:<{w}} {size:>{sw}} {r['preset']:<12} {r['status']:<12} {obj:>16} {gap:>8} "
            f"{ms(r['build_s']):>10} {ms(r['solve_s']):>10} {ms(r['total_s']):>10}  {agree:<6}  {judged}"
        )
    return "\n".join(lines)
