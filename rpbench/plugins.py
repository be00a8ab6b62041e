"""Classes named from outside the package: installed entry points and ``module:Class`` specs.

A strategy or backend name is resolved in this order (:func:`resolve`):

1. a built-in name (the package's own registry) — built-ins always win;
2. a name with a ``:`` — a ``module:Class`` spec (``mypkg.rules:Greedy``):
   the module is imported by its absolute name, so it must be installed or
   on ``sys.path`` / ``PYTHONPATH`` (in worker processes too), and the class
   is read off it;
3. an installed entry point of the group (``rpbench.strategies``,
   ``rpbench.backends``: ``name = "module:Class"``), its name compared
   case-insensitively.  An entry point named like a built-in is ignored —
   installing a package never changes what ``mb`` or ``highs`` means — and
   two installed distributions that declare one name for different classes
   are an error when that name is used.

Every failure is one line of the caller's error class: a malformed spec,
a module that cannot be imported (with the ImportError's message), a missing
attribute, an object that is not a subclass of the expected base, an
abstract class, or a class lacking an attribute the harness reads.  Any
other exception raised while a plug-in module is imported (a SyntaxError,
say) is a bug in the plug-in and propagates with its traceback, which points
at it.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Mapping
from importlib import metadata

#: Entry-point classes already loaded, by (group, lower-case name): backends are resolved once per solved
#: round, and scanning the installed distributions costs milliseconds each time.
_LOADED: dict[tuple[str, str], type] = {}


def is_spec(name: str) -> bool:
    """Whether ``name`` is a ``module:Class`` spec rather than a registered name."""
    return ":" in name


def entry_points(group: str) -> dict[str, list[metadata.EntryPoint]]:
    """Installed entry points of ``group`` by lower-case name (a name may be declared more than once)."""
    out: dict[str, list[metadata.EntryPoint]] = {}
    for ep in metadata.entry_points(group=group):
        out.setdefault(ep.name.lower(), []).append(ep)
    return out


def plugin_names(group: str, builtin: Mapping[str, str]) -> list[str]:
    """Names of the installed entry points of ``group`` that a built-in name does not shadow."""
    return sorted(name for name in entry_points(group) if name not in builtin)


def resolve(
    name: str,
    *,
    builtin: Mapping[str, str],
    package: str,
    group: str,
    base: type,
    what: str,
    required: tuple[str, ...],
    error: type[Exception],
) -> type:
    """The class ``name`` stands for (see the module docstring), or one ``error`` line.

    ``builtin`` maps built-in names to ``"module:Class"`` under ``package``;
    ``what`` names the kind in messages ("strategy"); ``required`` are the
    class attributes a plug-in class must have.
    """
    target = builtin.get(name)
    if target is not None:
        module_name, class_name = target.split(":")
        return getattr(importlib.import_module(f"{package}.{module_name}"), class_name)
    if is_spec(name):
        module_name, _, attr = name.partition(":")
        if not (all(part.isidentifier() for part in module_name.split(".")) and attr.isidentifier()):
            raise error(
                f"{what} {name!r} is not MODULE:CLASS (a dotted module path, a colon, a class name), "
                "e.g. mypkg.rules:Greedy"
            )
        return load_class(
            module_name, attr, label=f"{what} {name!r}", base=base, what=what, required=required, error=error
        )
    key = name.lower()
    if (group, key) in _LOADED:
        return _LOADED[(group, key)]
    found = entry_points(group).get(key) if key not in builtin else None
    if not found:
        plugins = plugin_names(group, builtin)
        known = ", ".join(builtin) + (f"; installed plug-ins: {', '.join(plugins)}" if plugins else "")
        raise error(f"unknown {what} {name!r}; known {what}s: {known}; or give MODULE:CLASS (e.g. mypkg.rules:MyClass)")
    values = sorted({ep.value for ep in found})
    if len(values) > 1:
        raise error(
            f"{what} {name!r} is ambiguous: installed distributions declare it in entry point group "
            f"{group} as {' and '.join(values)}; uninstall one, or name the class as MODULE:CLASS"
        )
    ep = found[0]
    dist = getattr(ep, "dist", None)
    origin = f" of {dist.name}" if dist is not None else ""
    cls = load_class(
        ep.module,
        ep.attr,
        label=f"{what} {name!r} (entry point {ep.name} = {ep.value}{origin})",
        base=base,
        what=what,
        required=required,
        error=error,
    )
    _LOADED[(group, key)] = cls
    return cls


def load_class(
    module_name: str, attr: str, *, label: str, base: type, what: str, required: tuple[str, ...], error: type[Exception]
) -> type:
    """``module_name``'s attribute ``attr`` (dotted for nested classes), checked to be a usable ``base`` class."""
    try:
        obj = importlib.import_module(module_name)
    except ImportError as exc:
        reason = " ".join(str(exc).split())  # one line, whatever the module raised
        raise error(
            f"{label}: cannot import module {module_name!r} ({reason}); install it or put its folder on PYTHONPATH"
        ) from None
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise error(f"{label}: module {module_name!r} has no attribute {attr!r}") from None
    path = f"{module_name}.{attr}"
    base_path = f"{base.__module__}.{base.__qualname__}"
    if not (isinstance(obj, type) and issubclass(obj, base)):
        kind = "a class" if isinstance(obj, type) else f"a {type(obj).__name__}"
        raise error(f"{label}: {path} is {kind}, not a subclass of {base_path}")
    if inspect.isabstract(obj):
        raise error(f"{label}: {path} is abstract; implement {', '.join(sorted(obj.__abstractmethods__))}")
    missing = [a for a in required if not hasattr(obj, a)]
    if missing:
        raise error(f"{label}: {path} lacks the class attribute(s) {', '.join(missing)} every {what} declares")
    return obj
