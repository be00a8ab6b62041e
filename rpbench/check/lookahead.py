"""``clairvoyant``: a run that read the future says so in meta.json.

A run's ``"clairvoyant": true`` marks it in every table and ranks it apart in an evaluation; the simulator
records it, and no digest covers it.  So a flag edited to false (or removed) on a run whose built-in strategy
reads the future under the run's recorded options (:func:`rpbench.results.lookahead.declared_clairvoyant`:
``hindsight``, ``fl`` with ``rates=scenario``) fails here.  A plug-in's class is not imported: its flag is
taken as written.
"""

from __future__ import annotations

from rpbench.check.core import RunCheck
from rpbench.check.folder import Folder
from rpbench.results.layout import META
from rpbench.results.lookahead import declared_clairvoyant
from rpbench.results.runs import run_label

CLAIRVOYANT_CHECK = "clairvoyant"


def check_clairvoyant(rc: RunCheck, f: Folder, name: str) -> None:
    """The run's recorded flag covers what its strategy class declares under its recorded options."""
    record = f.meta["runs"][name]
    flag = record.get("clairvoyant")
    if flag is not None and not isinstance(flag, bool):
        rc.fail(CLAIRVOYANT_CHECK, f"{META} records clairvoyant {flag!r} for the run, not true or false")
        return
    declared = declared_clairvoyant(name, record)
    if declared is None:
        return  # a plug-in, or options of another rpbench version: nothing to hold the flag to
    if declared and flag is not True:
        rc.fail(
            CLAIRVOYANT_CHECK,
            f"{META} records the run as online (clairvoyant: {'absent' if flag is None else 'false'}), but its "
            f"strategy {run_label(str(record.get('source', name)))} reads the future under the recorded options",
        )
    rc.checked["clairvoyant"] = 1
