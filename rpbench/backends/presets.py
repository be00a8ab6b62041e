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

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from rpbench.backends.base import Backend, SolveOptions
from rpbench.backends.registry import REGISTRY, backend_class, get_backend, plugin_names
from rpbench.exceptions import PresetError
from rpbench.paths import source_root
from rpbench.plugins import is_spec

_TOP_KEYS = {"backend", "description", "options"}
_OPTION_KEYS = {"threads", "time_limit_s", "mip_rel_gap", "method", "solver", "extra"}


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
    def of(cls, backend: Backend, options: SolveOptions | None = None) -> "Preset":
        """An unnamed preset around a backend object (e.g. one that is not registered)."""
        return cls(name=backend.name, backend=backend.name, description=type(backend).__doc__ or "",
                   options=options or SolveOptions(), path="<in code>", instance=backend)

    def backend_class(self) -> type[Backend]:
        return type(self.instance) if self.instance is not None else backend_class(self.backend)

    def is_installed(self) -> bool:
        return self.backend_class().is_installed()

    def make_backend(self) -> Backend:
        return self.instance if self.instance is not None else get_backend(self.backend)

    def as_dict(self) -> dict:
        o = self.options
        return {"name": self.name, "backend": self.backend, "description": self.description, "path": self.path,
                "options": {"threads": o.threads, "time_limit_s": o.time_limit_s, "mip_rel_gap": o.mip_rel_gap,
                            "method": o.method, "solver": o.solver, "extra": dict(o.extra)}}


def _preset_files() -> dict[str, Path | resources.abc.Traversable]:
    found: dict[str, object] = {}
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
        if not path.is_file():
            raise PresetError(f"solver preset file {name!r} does not exist")
        return parse_preset(path.stem, path.read_text(), str(path))
    files = _preset_files()
    if name not in files:
        raise PresetError(f"unknown solver preset {name!r}; available: {', '.join(files) or 'none'} "
                          "(presets live in solvers/NAME.toml)")
    entry = files[name]
    return parse_preset(name, entry.read_text(), str(entry))


def parse_preset(name: str, text: str, where: str) -> Preset:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"solver preset {where!r} is not valid TOML: {exc}") from None
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise PresetError(f"solver preset {where!r}: unknown key(s) {', '.join(sorted(unknown))}; "
                          f"allowed: {', '.join(sorted(_TOP_KEYS))}")
    backend = data.get("backend")
    if not isinstance(backend, str) or not (backend in REGISTRY or is_spec(backend)
                                            or backend.lower() in plugin_names()):
        raise PresetError(f"solver preset {where!r}: backend = {backend!r} is not one of "
                          f"{', '.join([*REGISTRY, *plugin_names()])} (installed plug-ins included) nor a "
                          "\"module:Class\" spec")
    if backend not in REGISTRY:
        try:
            backend_class(backend)
        except PresetError as exc:
            raise PresetError(f"solver preset {where!r}: {exc}") from None
    opts = data.get("options", {})
    if not isinstance(opts, dict):
        raise PresetError(f"solver preset {where!r}: [options] must be a table")
    unknown = set(opts) - _OPTION_KEYS
    if unknown:
        raise PresetError(f"solver preset {where!r}: unknown option(s) {', '.join(sorted(unknown))}; "
                          f"allowed: {', '.join(sorted(_OPTION_KEYS))}")
    try:
        options = SolveOptions(
            threads=_opt(opts, "threads", int, 1, where, positive=True),
            time_limit_s=_opt(opts, "time_limit_s", float, None, where, positive=True),
            mip_rel_gap=_opt(opts, "mip_rel_gap", float, 0.0, where),
            method=_opt(opts, "method", str, None, where),
            solver=_opt(opts, "solver", str, None, where),
            extra=dict(opts.get("extra", {})),
        )
    except TypeError as exc:
        raise PresetError(f"solver preset {where!r}: {exc}") from None
    if options.mip_rel_gap < 0:
        raise PresetError(f"solver preset {where!r}: mip_rel_gap must be >= 0")
    return Preset(name=name, backend=backend, description=str(data.get("description", "")),
                  options=options, path=where)


def _opt(opts: dict, key: str, kind: type, default, where: str, positive: bool = False):
    if key not in opts:
        return default
    value = opts[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise PresetError(f"solver preset {where!r}: option {key} = {value!r} must be of type {kind.__name__}")
    if positive and value <= 0:
        raise PresetError(f"solver preset {where!r}: option {key} = {value!r} must be > 0")
    return value
