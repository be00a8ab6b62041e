"""Independent verification of a results folder from its own files alone.

The checker re-reads what the folder stores — orders, network, fleet, every
event log, trajectory and oracle pair list, the reported tables — never the
data folder, the simulator's state or the KPI code a run used
(:mod:`rpbench.results.metrics`), and recomputes every number a reader is
shown.  ``docs/guarantees.md`` says what it proves and what it trusts.

Folder checks (reported as the run ``(folder)``):

* ``manifest`` — the runs meta.json lists are exactly the ``runs/`` folders
  (a multi-day or sweep parent: every listed day or point folder is there);
* ``inputs-digest`` — the SHA-256 of orders.csv.gz, fleet.csv.gz,
  network.npz, of the parameters and of each run's options and rules equal
  the digest recorded at run time (skipped, and said so, for older folders);
* ``orders`` — orders in request order, stored solo distances = shortest
  paths of the folder's network;
* ``hourly`` — hourly.csv recomputed from the event logs and odometers;
* ``report`` — the KPI tables of report.md are the rendering of kpis.csv;
* ``report-html`` — report.html's comparison table shows kpis.csv (printed numbers and raw values);
* ``competitive-ratio`` — LB (the largest recomputed saving of the simulated runs), every run's ratios
  against U and LB and its saving / Oracle-1, the bound's rows LB and U / LB, and meta.json's
  ``best_known`` (:mod:`.ratios`);
* ``parent-tables`` — a multi-day, sweep or evaluation parent's tables are its children's KPIs;
* ``ranking`` — an evaluation's leaderboard ranks the online runs first and the clairvoyant runs apart,
  as its units make them (:mod:`.ranking`).

Simulation runs:

* ``clairvoyant`` — a run whose built-in strategy reads the future under its recorded options is recorded
  clairvoyant in meta.json (:mod:`.lookahead`);
* ``event-log`` — every event has a known kind, a finite time, an existing
  order, vehicle and node; one request per order at its request time and
  origin; pick-ups and cancellations at the origin, drop-offs at the
  destination; each partner named consistently;
* ``assigned-once`` — each order is assigned at most once, never after it
  was cancelled, and cancelled only when unassigned at request + K_p;
* ``within-patience`` — assignment happens between the request and request + K_p;
* ``service`` — every assigned passenger is picked up after assignment and
  dropped off after pick-up, by the assigned vehicle, and the vehicle passes
  the passenger's origin / destination node at exactly those times;
* ``max-pickup`` — pick-up distance <= R̄ (driven from the assignment, or
  from the partner's pick-up when the partner was collected first, A14);
* ``max-detour`` — ride distance - solo distance <= D̄ for every passenger;
* ``capacity`` — at most two passengers assigned-or-on-board at once, at
  most two on board, partners on the same vehicle;
* ``movement`` — finite trajectories that start at the vehicle's initial
  node, follow arcs of the network, with odometer steps equal to arc lengths
  and time steps of at least length / speed, times non-decreasing;
* ``kpi`` — every KPI of kpis.csv equals its recomputation by the checker's
  own code from the event log and the odometers; none missing, unknown or text
  (timings such as ``wall_s`` and ``prepare_s``, which no file reproduces, are
  only held to be finite and >= 0);
* ``decision-budget`` — with a decision budget in meta.json, a number > 0, every round's ``over_budget``
  flag in rounds.csv.gz says whether its decision took longer (``rounds_over_budget`` is recounted by
  ``kpi``); without one, no such column;
* ``bound-certificate`` — every pair the run formed is an edge of the upper
  bound's graph (docs/bound.md) whose weight covers its realised saving (read
  off the odometers, + :data:`.core.CERT_TOL_M`); with a ``bound`` run in the
  folder, the run's saving is at most the bound.

Oracle runs (``pairs.csv.gz``): ``oracle-rules`` (the recorded pair rules are
the folder's parameters), ``oracle-pairs`` (a matching of pairs inside the
rules' time windows — en-route pairs included — whose saving, route length,
detours, shared and pick-up distances are recomputed from the orders and the
network, feasible and in the rule's service and pick-up order; the bound's
pairs are bound edges of the largest weight), ``max-detour`` and ``kpi``
(recomputed from the recomputed pairs; the solver's objective re-summed).

The bound run also gets ``bound-optimal`` (:mod:`.matching`): its value is at
least the maximum-weight matching of the bound's graph, which the checker
enumerates itself, proven by a dual certificate verified here.

A ``rpbench replicate`` folder (the authors' engine, whose vehicles teleport):
``manifest``, ``paths`` and ``report`` over its files; ``records``,
``assignment`` and ``accounting`` from the authors' passenger records;
rpbench's own runs as full results folders (``engine-rows``); every check
built on trajectories is skipped by name, with the reason.  A run none of
whose checks could be made is reported skipped, never OK.

A ``rpbench bench --out`` folder (:mod:`.bench`): ``manifest``, ``environment``, ``known-values``,
``verdict`` per preset (recomputed against the folder's ``known.solu`` and the other presets' optima),
``summary``, ``profile`` and ``report`` (recomputed from ``results.csv``).

A folder that cannot be read — a file missing, truncated or unparseable, a
column missing or not numeric, meta.json without its parameters — is
*unreadable*: :class:`ResultsError` (``rpbench check`` exit status 2).  A
readable folder whose content breaks a rule fails that check by name (exit
status 1).  Everything is vectorised: loops run per vehicle or per path
position, never per event.

The modules, in import order: :mod:`.core` (verdicts, tolerances, schemas),
:mod:`.folder` (reading, the digest, the folder checks), :mod:`.events`
(movement, event log, service rules), :mod:`.kpis` (kpi, decision-budget, hourly, report),
:mod:`.certificate` (the checker's pair geometry, bound-certificate),
:mod:`.matching` (bound-optimal), :mod:`.oracle`, :mod:`.lookahead` (clairvoyant), :mod:`.ratios`
(competitive-ratio), :mod:`.ranking`, :mod:`.parents`, :mod:`.verify` (a comparison folder's checks),
:mod:`.replication` (a ``rpbench replicate`` folder, its engines' folders checked by :mod:`.verify`)
and :mod:`.tree` (the entry point: any folder).
"""

from rpbench.check.certificate import bound_weights
from rpbench.check.core import (
    EXIT_FAILED,
    EXIT_OK,
    EXIT_UNREADABLE,
    FOLDER,
    FolderResult,
    RunCheck,
    exit_status,
    format_report,
)
from rpbench.check.tree import check_tree
from rpbench.check.verify import check_folder, check_results

__all__ = [
    "EXIT_FAILED",
    "EXIT_OK",
    "EXIT_UNREADABLE",
    "FOLDER",
    "FolderResult",
    "RunCheck",
    "bound_weights",
    "check_folder",
    "check_results",
    "check_tree",
    "exit_status",
    "format_report",
]
