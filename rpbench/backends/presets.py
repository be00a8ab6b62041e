"""Solver presets: ``--solver NAME`` means ``solvers/NAME.toml``.

A preset names a backend and its options::

    backend = "highs"
    description = "HiGHS through highspy"
    [options]
    threads = 1
    time_limit_s = 60.0
    mip_rel_gap = 0.0
    method = "lp"          # backend-specific choice of algorithm
    [options.extra]        # passed to the backend verbatim

Every value is checked when the preset is parsed: ``threads`` in [1, 1024],
``time_limit_s`` in (0, 1e6] s, ``mip_rel_gap`` in [0, 1] (finite: TOML's
``nan`` and ``inf`` are refused), ``method``/``solver``/``description``
strings, ``[options.extra]`` a table of scalars (string, integer, finite
number, boolean).  An option the backend does not honour
(:data:`~rpbench.backends.registry.HONOURS`: ``method`` on ``matching``) is
refused unless it asks for the default (``mip_rel_gap = 0``, ``threads = 1``).
The file must be UTF-8 TOML.  Any violation is one
:class:`~rpbench.exceptions.PresetError` naming the file.

Presets are found in the checkout's ``solvers/`` folder, else in the
installed package (the same files, shipped as ``rpbench.presets``).  A path
ending in ``.toml`` is accepted as well: that is how a preset of a backend
defined outside the package is used (``--solver path/to/mine.toml``), its
``backend`` an installed entry-point name or ``"mypkg.solvers:MyBackend"``
(:func:`~rpbench.backends.registry.backend_class`).  Such a backend is
resolved when the preset is parsed, so a module that does not import is
reported at once, naming the preset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path

from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.registry import BACKEND_REGISTRY, backend_class, backend_plugin_names, honoured_options
from rpbench.exceptions import PresetError, one_line
from rpbench.files import parse_toml, require_regular
from rpbench.files.paths import source_root
from rpbench.model import Structure
from rpbench.plugins import is_spec

_TOP_KEYS = {"backend", "description", "options"}
_OPTION_KEYS = {"threads", "time_limit_s", "mip_rel_gap", "method", "solver", "extra"}
# Sanity bounds: beyond them a value is a typo, and a huge time limit overflows the timeouts derived from it.
MAX_THREADS = 1024
MAX_TIME_LIMIT_S = 1e6  # 11.6 days
# mip_rel_gap lies in [0, 1]: a relative gap of 1 already accepts any feasible solution.


@dataclass(frozen=True)
class Preset:
    """A named backend with its options (a ``solvers/NAME.toml`` file, or :meth:`of` a backend in code)."""

    name: str
    backend: str
    description: str
    options: SolveOptions
    path: str
    #: A backend object given in code (tests, notebooks); None: the registry's adapter for ``backend``.
    instance: Backend | None = field(default=None, compare=False, repr=False)

    @classmethod
    def of(cls, backend: Backend, options: SolveOptions | None = None) -> Preset:
        """An unnamed preset around a backend object (e.g. one that is not registered)."""
        return cls(
            name=backend.name,
            backend=backend.name,
            description=type(backend).__doc__ or "",
            options=options or SolveOptions(),
            path="<in code>",
            instance=backend,
        )

    def adapter(self) -> Backend:
        """The backend object that solves this preset's models (its solver library is not imported yet)."""
        if self.instance is not None:
            return self.instance
        try:
            return self._adapter_class()
        except ModuleNotFoundError as exc:  # a broken installation: an adapter module of the package is gone
            if not (exc.name or "").startswith("rpbench.backends."):
                raise
            raise PresetError(
                f"solver preset {self.name!r}: the adapter module {exc.name} of backend {self.backend!r} is "
                "missing from this installation; choose another --solver"
            ) from None

    @cached_property
    def _adapter_class(self) -> type[Backend]:
        """The registry's class for ``backend``, found once per preset: every solve asks for it."""
        return backend_class(self.backend)

    def is_installed(self) -> bool:
        return self.adapter().is_installed()

    def require(self, structure: Structure, *, needed_by: str | None = None) -> Backend:
        """The adapter, checked to solve ``structure`` models exactly and to be installed; else one line.

        This is the one place that decides "exact and installed": every solve goes through
        :func:`rpbench.backends.solve`, which asks it, and the harness asks before a run starts, so that a
        wrong ``--solver`` costs nothing.  ``needed_by`` names what needs it, for the message.
        """
        backend = self.adapter()
        if not backend.supports(structure):
            who = f", which {needed_by} needs" if needed_by else ""
            raise PresetError(
                f"solver preset {self.name!r} (backend {self.backend!r}) does not solve {structure.value} models "
                f"exactly{who}; choose another --solver"
            )
        backend.ensure_installed()
        return backend

    def recorded_path(self) -> str:
        """The preset's file as a results folder records it: ``solvers/NAME.toml`` for one of rpbench's
        presets (wherever it is installed), else the path as it was given."""
        entry = _preset_files().get(self.name)
        return f"solvers/{self.name}.toml" if entry is not None and str(entry) == self.path else self.path

    def as_dict(self) -> dict:
        o = self.options
        return {
            "name": self.name,
            "backend": self.backend,
            "description": self.description,
            "path": self.recorded_path(),
            "options": {
                "threads": o.threads,
                "time_limit_s": o.time_limit_s,
                "mip_rel_gap": o.mip_rel_gap,
                "method": o.method,
                "solver": o.solver,
                "extra": dict(o.extra),
            },
        }


def _preset_files() -> dict[str, Path | resources.abc.Traversable]:
    found: dict[str, Path | resources.abc.Traversable] = {}
    checkout = source_root() / "solvers"
    if checkout.is_dir():
        for p in sorted(checkout.glob("*.toml")):
            found[p.stem] = p
    if not found:
        try:
            pkg = resources.files("rpbench.presets")
            for entry in sorted(pkg.iterdir(), key=lambda e: e.name):
                if entry.name.endswith(".toml"):
                    found[entry.name[:-5]] = entry
        except ModuleNotFoundError:
            pass
    return found


def preset_names() -> list[str]:
    return list(_preset_files())


def load_preset(name: str) -> Preset:
    """Load a preset by name (or by path to a ``.toml`` file), validating it."""
    if name.endswith(".toml"):
        path = Path(name)
        require_regular(path, "solver preset file", PresetError)  # a folder or FIFO is named as such
        return parse_preset(path.stem, _read_text(path, str(path)), str(path))
    files = _preset_files()
    if name not in files:
        raise PresetError(
            f"unknown solver preset {name!r}; available: {', '.join(files) or 'none'} "
            "(presets live in solvers/NAME.toml)"
        )
    entry = files[name]
    return parse_preset(name, _read_text(entry, str(entry)), str(entry))


def _read_text(entry: Path | resources.abc.Traversable, where: str) -> str:
    """A preset file's text: TOML is UTF-8 by definition, so other bytes are an error naming the file."""
    try:
        return entry.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise PresetError(f"solver preset {where!r} is not UTF-8 text (byte {exc.start}); save it as UTF-8") from None
    except OSError as exc:
        raise PresetError(f"solver preset {where!r} cannot be read: {one_line(exc)}") from None


def parse_preset(name: str, text: str, where: str) -> Preset:
    data = parse_toml(text, f"solver preset {where!r}", PresetError)  # too deeply nested: one line too
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise PresetError(
            f"solver preset {where!r}: unknown key(s) {', '.join(sorted(unknown))}; "
            f"allowed: {', '.join(sorted(_TOP_KEYS))}"
        )
    backend = data.get("backend")
    if not isinstance(backend, str) or not (
        backend in BACKEND_REGISTRY or is_spec(backend) or backend.lower() in backend_plugin_names()
    ):
        raise PresetError(
            f"solver preset {where!r}: backend = {backend!r} is not one of "
            f"{', '.join([*BACKEND_REGISTRY, *backend_plugin_names()])} (installed plug-ins included) nor a "
            '"module:Class" spec'
        )
    if backend not in BACKEND_REGISTRY:
        try:
            backend_class(backend)
        except PresetError as exc:
            raise PresetError(f"solver preset {where!r}: {exc}") from None
    description = data.get("description", "")
    if not isinstance(description, str):
        raise PresetError(f"solver preset {where!r}: description = {description!r} must be a string")
    options = _parse_options(data.get("options", {}), where)
    _refuse_unhonoured(options, backend, where)
    return Preset(name=name, backend=backend, description=description, options=options, path=where)


def _refuse_unhonoured(options: SolveOptions, backend: str, where: str) -> None:
    """One line for an option set to anything but its default that ``backend`` would drop silently."""
    honoured = honoured_options(backend)
    default = SolveOptions()
    order = ("threads", "time_limit_s", "mip_rel_gap", "method", "solver", "extra")
    for key in order:
        value = getattr(options, key)
        if key not in honoured and value != getattr(default, key):
            keep = ", ".join(k for k in order if k in honoured)
            raise PresetError(
                f"solver preset {where!r}: backend {backend!r} does not honour option {key} = {value!r} "
                f"(it honours {keep}); remove it"
            )


def _parse_options(opts, where: str) -> SolveOptions:
    """The ``[options]`` table, every value checked for its type and range."""
    if not isinstance(opts, dict):
        raise PresetError(f"solver preset {where!r}: [options] must be a table")
    unknown = set(opts) - _OPTION_KEYS
    if unknown:
        raise PresetError(
            f"solver preset {where!r}: unknown option(s) {', '.join(sorted(unknown))}; "
            f"allowed: {', '.join(sorted(_OPTION_KEYS))}"
        )
    return SolveOptions(
        threads=_opt(opts, "threads", int, 1, where, low=1, high=MAX_THREADS),
        time_limit_s=_opt(opts, "time_limit_s", float, None, where, low=0.0, low_open=True, high=MAX_TIME_LIMIT_S),
        mip_rel_gap=_opt(opts, "mip_rel_gap", float, 0.0, where, low=0.0, high=1.0),
        method=_opt(opts, "method", str, None, where),
        solver=_opt(opts, "solver", str, None, where),
        extra=_extra(opts.get("extra", {}), where),
    )


def _opt(opts: dict, key: str, kind: type, default, where: str, *, low=None, high=None, low_open: bool = False):
    """``opts[key]`` checked to be a ``kind`` (an int is a float too; a bool is neither) within the bounds."""
    if key not in opts:
        return default
    value = opts[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise PresetError(f"solver preset {where!r}: option {key} = {value!r} must be of type {kind.__name__}")
    # TOML spells nan and inf; a NaN limit compares false with everything and would slip through.
    if isinstance(value, float) and not math.isfinite(value):
        raise PresetError(f"solver preset {where!r}: option {key} = {value!r} must be a finite number")
    if low is not None and (value <= low if low_open else value < low):
        raise PresetError(f"solver preset {where!r}: {key} must be {'>' if low_open else '>='} {low:g} (got {value!r})")
    if high is not None and value > high:
        raise PresetError(f"solver preset {where!r}: {key} must be <= {high:g} (got {value!r})")
    return value


def _extra(extra, where: str) -> dict[str, str | int | float | bool]:
    """``[options.extra]``: a table of scalar settings, passed to the backend verbatim."""
    if not isinstance(extra, dict):
        raise PresetError(
            f"solver preset {where!r}: [options.extra] must be a table of NAME = value settings, "
            f"not {type(extra).__name__} {extra!r}"
        )
    for key, value in extra.items():
        # Lists, tables and TOML dates would reach the solver as odd options: only scalars are settings.
        if isinstance(value, (bool, str, int)):
            continue
        if isinstance(value, float) and math.isfinite(value):
            continue
        raise PresetError(
            f"solver preset {where!r}: [options.extra] {key} = {value!r} must be a string, "
            "integer, finite number or boolean"
        )
    return dict(extra)
