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
from dataclasses import dataclass

from rpbench.backends import Preset, solve
from rpbench.backends.base import SolveOptions
from rpbench.exceptions import ResultsError, RpbenchError
from rpbench.model import Model, Solution, Status, Structure
from rpbench.solu import Known

#: Backends that are front ends of HiGHS (scipy.optimize.milp and linprog are HiGHS too).
_HIGHS_FRONT_ENDS = {"highs", "scipy", "cvxpy", "pyomo"}


def algorithm(preset: Preset, model: Model, sol: Solution) -> str:
    """The algorithm that proved ``sol``: what counts as independent evidence."""
    backend = preset.backend
    message = sol.message or ""
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


def prove(model: Model, presets: list[Preset], time_limit_s: float, *, stop_when_agreed: bool = True) -> Proof:
    """Solve ``model`` with the presets that support its structure, in order, and combine their answers;
    ``stop_when_agreed``: stop at the first two different algorithms proving the same optimum."""
    proven: dict[float, set[str]] = {}
    best: float | None = None
    bound: float | None = None
    answers = []
    for preset in presets:
        adapter = preset.adapter()
        if not adapter.supports(model.structure) or not adapter.is_installed():
            continue
        options: SolveOptions = dataclasses.replace(preset.options, time_limit_s=time_limit_s)
        try:
            sol = solve(model, dataclasses.replace(preset, options=options))
        except RpbenchError as exc:
            answers.append(f"{preset.name}: error ({exc})")
            continue
        answers.append(f"{preset.name}: {sol.status.value} {sol.objective:.0f}")
        if sol.status is Status.OPTIMAL:
            agreed = proven.setdefault(float(sol.objective), set())
            agreed.add(algorithm(preset, model, sol))
            if len(agreed) >= 2 and len(proven) == 1 and stop_when_agreed:
                break  # two independent proofs: the others would only spend time
        best = sol.objective if best is None else max(best, sol.objective)
        if sol.bound is not None:
            bound = sol.bound if bound is None else min(bound, sol.bound)
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
