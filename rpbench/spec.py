"""The run specification: everything one comparison needs, frozen, built once and passed down.

A :class:`RunSpec` names the scenario (a :class:`~rpbench.scenarios.ScenarioRequest`),
the runs in column order (:class:`RunEntry`: strategies and offline runs,
each under its name with its typed options), the solver presets, the strict
policy, the decision budget (rounds slower than it are flagged, never changed), the command line to
record and the formats its reports' figures are written in (:data:`FIGURE_FORMATS`; PNG alone by
default).  ``rpbench run`` builds one from its arguments (:mod:`rpbench.commands._runs`); the multi-day
runner and sweeps derive one per day or point (:meth:`RunSpec.for_request`) and hand it to worker
processes as it is (it pickles); Python callers build one with
:meth:`RunSpec.of`.

A run's *name* is its folder ``runs/<name>/``, its ``--opt NAME.option=...``
prefix and its column in ``kpis.csv``.  A built-in strategy or offline run is
named as typed (``mb``, ``bound``); a plug-in strategy, given as an entry point
or as ``module:Class``, runs under its class's ``name`` attribute, and its
*source* (the text it was found by) is what worker processes resolve.

A *variant* runs a strategy a second time under other options: ``fl@tau0_s=200`` (several settings:
``fl@tau0_s=200@accel=damped``) is a run of its own, named as typed, labelled "FL (tau0_s=200)", drawn
in a colour of its own, with those options set (``--opt`` may set more).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rpbench.exceptions import ParameterError
from rpbench.options import RunOptions
from rpbench.oracle.runs import ORACLE_RUNS
from rpbench.plugins import is_spec
from rpbench.scenarios import ScenarioRequest
from rpbench.strategies import STRATEGY_REGISTRY, Strategy, strategy_class, strategy_plugin_names

#: A run name is a folder name and an ``--opt`` prefix: letters, digits and ``._-``, not starting with a dot.
_RUN_NAME = re.compile(r"^[A-Za-z0-9_-][A-Za-z0-9._-]*$")
#: A run name names its folder ``runs/<name>/``: at most NAME_MAX bytes (255 on every common file system).
MAX_RUN_NAME_BYTES = 255
#: A round's decision budget beyond a day flags nothing.
MAX_DECISION_BUDGET_S = 86400.0
#: Separates a variant's settings from its strategy (``fl@tau0_s=200``).
VARIANT_SEP = "@"
#: A variant setting ``KEY=VALUE``: an option name, and a value that stays a plain folder-name part.
_SETTING = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)=([A-Za-z0-9._+-]+)$")
#: The formats a report's figures can be written in: PNG (the one report.md shows, always written) and the
#: vector copies for papers, on request (``--figures png,svg,pdf``; :func:`figure_formats`).
FIGURE_FORMATS = ("png", "svg", "pdf")
#: What a report writes without ``--figures``: PNG only (the vector copies cost most of a report's time).
DEFAULT_FIGURE_FORMATS = ("png",)


def figure_formats(given: str | Sequence[str], flag: str = "--figures") -> tuple[str, ...]:
    """``png,svg`` (text, or names) -> the formats figures are written in, in :data:`FIGURE_FORMATS` order,
    PNG always among them (report.md shows it); an unknown or no format is one error line naming ``flag``."""
    text = given if isinstance(given, str) else ",".join(map(str, given))
    names = [item.strip().lower() for item in text.split(",") if item.strip()]
    unknown = [n for n in names if n not in FIGURE_FORMATS]
    if unknown or not names:
        what = f"unknown figure format {unknown[0]!r}" if unknown else "no figure format"
        raise ParameterError(
            f"{flag} {text!r}: {what}; name one or more of {', '.join(FIGURE_FORMATS)} (e.g. {flag} png,svg,pdf)"
        )
    return tuple(f for f in FIGURE_FORMATS if f == "png" or f in names)


@dataclass(frozen=True)
class RunEntry:
    """One column of a comparison: a strategy (simulated) or an offline run (bound, oracles)."""

    name: str
    source: str  # what finds its class: a built-in name, an entry-point name or ``module:Class``
    options: RunOptions
    settings: tuple[tuple[str, str], ...] = ()  # a variant's options as typed (``fl@tau0_s=200``)
    label: str | None = None  # a label its caller gave, instead of its class's (the Gymnasium environment's)

    @property
    def offline(self) -> bool:
        return self.name in ORACLE_RUNS

    def label_of(self, label: str) -> str:
        """The run's label from its class's: a variant says its settings ("FL (tau0_s=200)"); a label given
        to the run is its label."""
        if self.label is not None:
            return self.label
        return f"{label} ({', '.join(f'{k}={v}' for k, v in self.settings)})" if self.settings else label

    def renamed(self, name: str, label: str | None = None) -> RunEntry:
        """This run under another run name (its folder, its column), checked as a run name is."""
        if not isinstance(name, str) or not _RUN_NAME.match(name):
            raise ParameterError(
                f"run name {name!r}: letters, digits, '.', '_' and '-', not starting with a dot (it names a folder)"
            )
        check_run_name_length(name)
        return dataclasses.replace(self, name=name, label=label)

    def color_of(self, color: str | None) -> str | None:
        """The run's colour from its class's: a variant takes the next free colour (None), not its strategy's."""
        return None if self.settings else color

    def strategy_class(self) -> type[Strategy]:
        """The strategy class of a simulated run (resolved from :attr:`source`, also in a worker process)."""
        return strategy_class(self.source)


@dataclass(frozen=True)
class RunSpec:
    """A comparison of runs on one scenario, as one frozen, picklable object (see the module docstring)."""

    request: ScenarioRequest
    runs: tuple[RunEntry, ...]
    preset: str = "highs"
    oracle_preset: str | None = None  # None: the comparison's own preset
    strict: bool = False  # an answer the solver did not prove optimal is an error, not a note
    command: str | None = None  # the command line recorded in results folders
    decision_budget_s: float | None = None  # flag rounds deciding slower than this (None: no budget)
    formats: tuple[str, ...] = DEFAULT_FIGURE_FORMATS  # the reports' figure formats (:func:`figure_formats`)

    def __post_init__(self) -> None:
        object.__setattr__(self, "formats", figure_formats(self.formats, "formats"))  # checked, in order
        budget = self.decision_budget_s
        if budget is not None and not (
            isinstance(budget, (int, float))
            and not isinstance(budget, bool)
            and math.isfinite(budget)
            and 0 < budget <= MAX_DECISION_BUDGET_S
        ):
            raise ParameterError(
                f"decision budget {budget!r} must be a finite number of seconds > 0 and <= {MAX_DECISION_BUDGET_S:g}"
            )
        if not self.runs:
            raise ParameterError("a comparison needs at least one strategy or offline run")
        names = [r.name for r in self.runs]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ParameterError(f"run name {twice[0]!r} appears twice; every run of a comparison needs its own name")
        for name in names:
            check_run_name_length(name)

    @classmethod
    def of(
        cls,
        request: ScenarioRequest | str,
        strategies: Sequence[str],
        *,
        preset: str = "highs",
        options: Mapping[str, RunOptions | Mapping[str, Any]] | None = None,
        oracle_preset: str | None = None,
        strict: bool = False,
        command: str | None = None,
        decision_budget_s: float | None = None,
        formats: Sequence[str] = DEFAULT_FIGURE_FORMATS,
    ) -> RunSpec:
        """A spec from run names (or plug-in sources) and per-run options keyed by run name.

        ``request`` may be a scenario name (its defaults otherwise); option
        values are Python values or text, checked against each run's declared
        options.
        """
        if isinstance(request, str):
            request = ScenarioRequest(name=request)
        entries = resolve_runs(strategies)
        given = dict(options or {})
        unknown = [name for name in given if name not in {e.name for e in entries}]
        if unknown:
            raise ParameterError(f"options for {unknown[0]!r}, which is not one of the runs ({', '.join(given)})")
        entries = [dataclasses.replace(e, options=typed_options(e, _merged(e, given.get(e.name)))) for e in entries]
        return cls(
            request=request,
            runs=tuple(entries),
            preset=preset,
            oracle_preset=oracle_preset,
            strict=strict,
            command=command,
            decision_budget_s=decision_budget_s,
            formats=tuple(formats),
        )

    @property
    def names(self) -> list[str]:
        """The run names in column order."""
        return [r.name for r in self.runs]

    @property
    def simulated(self) -> list[RunEntry]:
        return [r for r in self.runs if not r.offline]

    @property
    def offline(self) -> list[RunEntry]:
        return [r for r in self.runs if r.offline]

    def entry(self, name: str) -> RunEntry:
        for r in self.runs:
            if r.name == name:
                return r
        raise KeyError(name)

    def for_request(self, request: ScenarioRequest) -> RunSpec:
        """The same comparison on another scenario request (a day of a multi-day run, a sweep point)."""
        return dataclasses.replace(self, request=request)

    def with_options(self, name: str, values: Mapping[str, Any]) -> RunSpec:
        """The comparison with run ``name``'s options ``values`` changed (the others kept), checked."""
        entry = self.entry(name)
        options = typed_options(entry, {**entry.options.as_dict(), **values})
        runs = tuple(dataclasses.replace(r, options=options) if r.name == name else r for r in self.runs)
        return dataclasses.replace(self, runs=runs)


def _merged(entry: RunEntry, given: RunOptions | Mapping[str, Any] | None) -> RunOptions | Mapping[str, Any] | None:
    """A variant's settings under the options given for it (which win)."""
    if isinstance(given, RunOptions) or not entry.settings:
        return given
    return {**dict(entry.settings), **dict(given or {})}


def options_class(entry_source: str) -> type[RunOptions]:
    """The declared options of an offline run or a strategy."""
    if entry_source in ORACLE_RUNS:
        return ORACLE_RUNS[entry_source].Options
    return strategy_class(entry_source).Options


def typed_options(entry: RunEntry, raw: RunOptions | Mapping[str, Any] | None) -> RunOptions:
    """``raw`` (parsed options, a dict of values or text, or None for the defaults) checked for ``entry``."""
    cls = options_class(entry.source)
    if isinstance(raw, RunOptions):
        if not isinstance(raw, cls):
            raise ParameterError(f"{entry.name}: options must be {cls.__name__}, not {type(raw).__name__}")
        return raw
    return cls.parse(entry.name, dict(raw or {}))


def known_runs() -> list[str]:
    """Every name ``--strategies`` accepts without a ``module:`` prefix (an oracle hides a plug-in's name)."""
    return [*STRATEGY_REGISTRY, *(n for n in strategy_plugin_names() if n not in ORACLE_RUNS), *ORACLE_RUNS]


def resolve_runs(items: Sequence[str]) -> list[RunEntry]:
    """Run entries (default options) for names as typed, in order, each resolved and named.

    Built-in strategy and offline-run names are case-insensitive; an
    entry-point name too; a ``module:Class`` source keeps its case (Python
    names are case-sensitive).  Offline runs take precedence over plug-ins of
    the same name.  A plug-in runs under its class's ``name``, which must be a
    plain name of its own: not a built-in's, not another run's.  Classes are
    imported here, so an import error is reported before any run.
    """
    typed = [s.strip() for s in items if s.strip()]
    if not typed:
        raise ParameterError(f"unknown strategy '(none)'; choose from {', '.join(known_runs())}")
    sources = []
    entries: list[RunEntry] = []
    for text in typed:
        base, *settings = text.split(VARIANT_SEP)
        source = base.strip() if is_spec(base) else base.strip().lower()
        sources.append(source)
        entry = _resolve_one(source)
        if settings:
            entry = _variant(entry, text, settings)
        entries.append(entry)
    seen: dict[str, str] = {}
    for e in entries:
        check_run_name_length(e.name)
        if e.name in seen:
            first = seen[e.name]
            what = f"names {e.name!r} twice" if first == e.source else f"runs {first!r} and {e.source!r} as {e.name!r}"
            raise ParameterError(f"strategy list {','.join(typed)} {what}; every run needs its own name")
        seen[e.name] = e.source
    return entries


def _resolve_one(source: str) -> RunEntry:
    if source in ORACLE_RUNS or source in STRATEGY_REGISTRY:
        return RunEntry(source, source, options_class(source)())
    if not is_spec(source) and source not in strategy_plugin_names():
        raise ParameterError(
            f"unknown strategy {source!r}; choose from {', '.join(known_runs())}, "
            "or give a strategy class as MODULE:CLASS (e.g. mypkg.rules:Greedy)"
        )
    cls = strategy_class(source)
    return RunEntry(_plugin_run_name(source, cls), source, cls.Options())


def _variant(entry: RunEntry, text: str, settings: Sequence[str]) -> RunEntry:
    """``entry`` under the settings of ``text`` (``fl@tau0_s=200``), named after them."""
    if entry.offline:
        raise ParameterError(f"{text!r}: the offline runs take no variants (give their options with --opt)")
    parsed = []
    for setting in settings:
        match = _SETTING.match(setting.strip())
        if match is None:
            raise ParameterError(
                f"{text!r}: a variant's settings are OPTION=VALUE after {VARIANT_SEP!r} (letters, digits and "
                f"'._+-' in the value), e.g. fl{VARIANT_SEP}tau0_s=200; got {setting!r}"
            )
        parsed.append((match[1], match[2]))
    keys = [k for k, _ in parsed]
    if len(set(keys)) != len(keys):
        raise ParameterError(f"{text!r}: a variant sets an option twice")
    name = VARIANT_SEP.join([entry.name, *(f"{k}={v}" for k, v in parsed)])
    variant = RunEntry(name, entry.source, entry.options, tuple(parsed))
    return dataclasses.replace(variant, options=typed_options(variant, dict(parsed)))


def check_run_name_length(name: str) -> None:
    """One error line for a run name too long to name its folder (found before any run, not when the
    results are written)."""
    size = len(name.encode("utf-8", "surrogateescape"))
    if size > MAX_RUN_NAME_BYTES:
        raise ParameterError(
            f"run name {name[:40]!r}... is {size} bytes; it names the run's folder, at most {MAX_RUN_NAME_BYTES}"
        )


def _plugin_run_name(source: str, cls: type[Strategy]) -> str:
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not _RUN_NAME.match(name):
        raise ParameterError(
            f"strategy {source!r}: its class's name {name!r} is not a plain run name (letters, digits, '.', '_', "
            "'-'; it names the run's folder and its --opt prefix)"
        )
    if name.lower() in STRATEGY_REGISTRY or name.lower() in ORACLE_RUNS:
        raise ParameterError(
            f"strategy {source!r} declares name {name!r}, the name of a built-in run; give its class another name"
        )
    return name
