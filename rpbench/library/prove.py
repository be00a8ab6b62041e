"""Known optimal values: each instance solved by several exact presets, kept when independent algorithms agree.

An instance's value is ``=opt=`` in the ``.solu`` file only when presets of at least two different
*algorithms* prove the same optimum (HiGHS's simplex or branch and cut, Jonker-Volgenant, sparse
blossom, Blossom V, OR-Tools): two front ends of HiGHS (highs, scipy, cvxpy-highs, pyomo-highs) count
once.  A value proven by one algorithm only is ``=best=``; an instance no preset proved within the time
limit gets the best incumbent as ``=best=`` and the tightest proven bound as ``=bound=`` when one is
known, else ``=unkn=``.  Proven optima that differ are a :class:`ResultsError` (a solver is wrong).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from rpbench.backends import Preset, solve
from rpbench.backends.base import SolveOptions
from rpbench.bench.runner import IsolatedWorker
from rpbench.exceptions import ResultsError, RpbenchError
from rpbench.model import Model, Status, Structure
from rpbench.results.solu import Known

#: Backends that are front ends of HiGHS (scipy.optimize.milp and linprog are HiGHS too).
_HIGHS_FRONT_ENDS = {"highs", "scipy", "cvxpy", "pyomo"}


def algorithm(preset: Preset, model: Model, message: str) -> str:
    """The algorithm that proved an answer (``message``: the solver's message): what counts as independent
    evidence."""
    backend = preset.backend
    if backend in _HIGHS_FRONT_ENDS or "HiGHS" in message:
        return "HiGHS"
    if "Blossom V" in message or backend in ("blossom", "blossom-v"):
        return "Blossom V"
    if backend == "matching":
        return "Jonker-Volgenant" if model.structure is Structure.ASSIGNMENT else "sparse blossom (PyMatching)"
    if backend == "ortools":
        return "OR-Tools"
    return backend


@dataclass(frozen=True)
class Proof:
    known: Known
    #: The algorithms that proved the value (``=opt=``/``=best=``), and what each preset answered.
    algorithms: tuple[str, ...]
    answers: tuple[str, ...]


def with_time_limit(preset: Preset, time_limit_s: float) -> Preset:
    """``preset`` with its solver time limit set to ``time_limit_s``."""
    options: SolveOptions = dataclasses.replace(preset.options, time_limit_s=time_limit_s)
    return dataclasses.replace(preset, options=options)


def prove(
    model: Model,
    presets: list[Preset],
    time_limit_s: float,
    *,
    stop_when_agreed: bool = True,
    workers: Mapping[str, IsolatedWorker] | None = None,
) -> Proof:
    """Solve ``model`` with the presets that support its structure, in order, and combine their answers;
    ``stop_when_agreed``: stop at the first two different algorithms proving the same optimum.  With
    ``workers`` (by preset name, each made from the preset :func:`with_time_limit`), every solve runs in
    that preset's own process, killed past its hard timeout: HiGHS checks its limit too rarely on the
    largest pairing models to stop near it."""
    proven: dict[float, set[str]] = {}
    best: float | None = None
    bound: float | None = None
    answers = []
    for preset in presets:
        adapter = preset.adapter()
        if not adapter.supports(model.structure) or not adapter.is_installed():
            continue
        if workers is not None:
            row = workers[preset.name].run(model, 1)
            status, objective, message = str(row["status"]), row["objective"], str(row["message"] or "")
            found_bound = None if row["bound"] is None or row["bound"] != row["bound"] else float(row["bound"])
        else:
            try:
                sol = solve(model, with_time_limit(preset, time_limit_s))
            except RpbenchError as exc:
                answers.append(f"{preset.name}: error ({exc})")
                continue
            status, objective, message, found_bound = sol.status.value, sol.objective, sol.message or "", sol.bound
        if status in ("error", "killed", "memory_limit"):
            answers.append(f"{preset.name}: {status} ({message})")
            continue
        answers.append(f"{preset.name}: {status} {objective:.0f}")
        if status == Status.OPTIMAL.value:
            agreed = proven.setdefault(float(objective), set())
            agreed.add(algorithm(preset, model, message))
            if len(agreed) >= 2 and len(proven) == 1 and stop_when_agreed:
                break  # two independent proofs: the others would only spend time
        if objective is not None and objective == objective:  # NaN: stopped without a solution
            best = objective if best is None else max(best, objective)
        if found_bound is not None:
            bound = found_bound if bound is None else min(bound, found_bound)
    if len(proven) > 1:
        raise ResultsError(f"model {model.name!r}: presets prove different optima ({'; '.join(answers)})")
    if proven:
        value, algorithms = next(iter(proven.items()))
        kind = "opt" if len(algorithms) >= 2 else "best"
        return Proof(Known(kind, value), tuple(sorted(algorithms)), tuple(answers))
    if best is not None:
        return Proof(Known("best", float(best)), (), tuple(answers))
    if bound is not None:
        return Proof(Known("bound", float(bound)), (), tuple(answers))
    return Proof(Known("unkn"), (), tuple(answers))
