"""Fixtures of the backend conformance suite: every preset in solvers/, skipped only when its library is missing."""

from __future__ import annotations

import pytest

from rpbench.backends import get_backend
from rpbench.backends.presets import load_preset, preset_names

PRESETS = preset_names()
#: Presets whose first use costs seconds (OGDF is loaded and a C++ shim compiled once per process).
SLOW_PRESETS = ("blossom-v",)


def make(name: str):
    """(backend, options) of a preset; skips the test when the preset's library is not installed."""
    preset = load_preset(name)
    cls = preset.adapter()
    if not cls.is_installed():
        pytest.skip(f"preset {name!r}: {', '.join(cls.missing_libraries())} not installed")
    return get_backend(preset.backend), preset.options


@pytest.fixture(params=[pytest.param(n, marks=pytest.mark.slow) if n in SLOW_PRESETS else n for n in PRESETS])
def preset(request):
    """(name, backend, options) for each preset."""
    backend, options = make(request.param)
    return request.param, backend, options
