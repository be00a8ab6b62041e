"""Known values of instances: the MIPLIB-style ``.solu`` file.

One instance a line, fields separated by white space::

    # comment (a line whose first non-blank character is '#'); blank lines are skipped
    =opt=   NAME VALUE    the proven optimum
    =best=  NAME VALUE    the best known objective (a feasible solution reaches it; not proven optimal)
    =bound= NAME VALUE    a proven bound: no solution exceeds it (rpbench's models maximise)
    =inf=   NAME          proven infeasible
    =unkn=  NAME          nothing known

``NAME`` is the instance's name as a benchmark table shows it (the file stem, see
:func:`rpbench.model.instances.load_instances`); ``VALUE`` is in model units, the instance's integral
objective (``values`` summed), a finite decimal number.  Each name appears once.  ``rpbench bench
--solu FILE`` checks every answer against these values (:func:`rpbench.bench.runner.cross_check`).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from rpbench.exceptions import ParameterError

#: The tags of a ``.solu`` line: those that take a value, and those that do not.
VALUED = ("opt", "best", "bound")
BARE = ("inf", "unkn")
KINDS = VALUED + BARE
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_TAG = re.compile(r"=(?P<kind>[^=\s]*)=")


@dataclass(frozen=True)
class Known:
    """What is known of one instance: ``kind`` one of :data:`KINDS`, ``value`` (model units) for the
    valued kinds and ``None`` for ``inf`` / ``unkn``."""

    kind: str
    value: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ParameterError(f"known value kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if (self.kind in VALUED) != (self.value is not None):
            need = "needs a value" if self.kind in VALUED else "takes no value"
            raise ParameterError(f"known value ={self.kind}= {need} (got {self.value!r})")
        if self.value is not None and not math.isfinite(self.value):
            raise ParameterError(f"known value ={self.kind}= {self.value!r} is not a finite number")


def read_solu(path: str | os.PathLike) -> dict[str, Known]:
    """The known values of a ``.solu`` file by instance name; a bad line is one :class:`ParameterError`
    naming the file and the line number."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ParameterError(f"known values file {str(path)!r} is not UTF-8 text ({exc.reason})") from None
    except OSError as exc:
        raise ParameterError(f"cannot read known values file {str(path)!r}: {exc.strerror or exc}") from None
    known: dict[str, Known] = {}
    first_line: dict[str, int] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        where = f"{path}, line {number}"
        tag = _TAG.fullmatch(fields[0])
        if tag is None:
            raise ParameterError(
                f"{where}: {_shown(line)} is not a known-value line (expected =opt=, =best=, =bound= NAME VALUE, "
                "=inf= NAME or =unkn= NAME)"
            )
        kind = tag["kind"]
        if kind not in KINDS:
            raise ParameterError(f"{where}: unknown tag {fields[0]!r} (tags: {', '.join(f'={k}=' for k in KINDS)})")
        want = 3 if kind in VALUED else 2
        if len(fields) != want:
            form = f"={kind}= NAME VALUE" if kind in VALUED else f"={kind}= NAME"
            raise ParameterError(f"{where}: {_shown(line)} has {len(fields)} fields; expected {form}")
        name = fields[1]
        value = None
        if kind in VALUED:
            if not _NUMBER.fullmatch(fields[2]) or not math.isfinite(float(fields[2])):
                raise ParameterError(f"{where}: value {fields[2]!r} of {name!r} is not a finite decimal number")
            value = float(fields[2])
        if name in known:
            raise ParameterError(f"{where}: instance {name!r} is given again (first on line {first_line[name]})")
        known[name] = Known(kind, value)
        first_line[name] = number
    return known


def write_solu(path: str | os.PathLike, entries: Mapping[str, Known], header: Iterable[str] = ()) -> Path:
    """Write ``entries`` as a ``.solu`` file, the ``header`` lines first as comments, then one line per
    instance sorted by name: the same entries give the same bytes.  Written to a sibling and renamed, so a
    failed write leaves no half-written file."""
    path = Path(path)
    lines = [f"# {h}".rstrip() if not h.startswith("#") else h.rstrip() for h in header]
    for h in lines:
        if "\n" in h or "\r" in h:
            raise ParameterError(f"a header line of {str(path)!r} holds a line break: {h!r}")
    for name in sorted(entries):
        k = entries[name]
        if not name or any(c.isspace() for c in name) or name.startswith("#"):
            raise ParameterError(f"instance name {name!r} cannot be written to a .solu file (blank, or a '#' first)")
        lines.append(f"={k.kind}= {name}" + ("" if k.value is None else f" {_number(k.value)}"))
    tmp = path.with_name(f".{path.name}.partial-{os.getpid()}")
    try:
        tmp.write_text("".join(f"{line}\n" for line in lines), encoding="utf-8")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def check_names(known: Mapping[str, Known], names: Iterable[str], where: str, library: Iterable[str] = ()) -> list[str]:
    """The names of ``known`` (read from ``where``) that name a ``library`` instance not benchmarked here
    (a collection-wide file, as MIPLIB's, judges any subset of its collection); one
    :class:`ParameterError` line when a name names neither: a typo there would silently check nothing."""
    have, collection = set(names), set(library)
    unknown = sorted(set(known) - have - collection)
    if unknown:
        shown = ", ".join(repr(n) for n in unknown[:5]) + (f" and {len(unknown) - 5} more" if len(unknown) > 5 else "")
        which = "names no instance" if len(unknown) == 1 else "name no instance"
        raise ParameterError(
            f"{where}: {shown} {which} benchmarked here ({len(have)} instances) or of the library; remove the "
            "line or name the instance"
        )
    return sorted((set(known) - have) & collection)


def _number(value: float) -> str:
    """A whole number without ``.0``; otherwise the shortest text that reads back as the same float."""
    return str(int(value)) if value.is_integer() and abs(value) < 2**63 else repr(value)


def _shown(line: str) -> str:
    line = line.strip()
    return repr(line if len(line) <= 60 else line[:57] + "...")
