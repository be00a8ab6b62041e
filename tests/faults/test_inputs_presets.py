"""Bad solver presets (``--solver FILE.toml``): every malformed value or file is one line naming the file.

The presets go through ``rpbench bench --synthetic --solver FILE --csv OUT``, which loads them
before building any model: the tests check that nothing is written either.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rpbench.backends.presets import parse_preset

from .test_inputs_helpers import cli_error

GOOD = 'backend = "highs"\ndescription = "HiGHS"\n[options]\nthreads = 1\ntime_limit_s = 60.0\nmip_rel_gap = 0.0\n'


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


def bench_with(capsys, tmp_path: Path, preset: bytes | str) -> str:
    """``rpbench bench`` with a preset file holding ``preset``; returns the error line."""
    path = tmp_path / "bad.toml"
    path.write_bytes(preset.encode() if isinstance(preset, str) else preset)
    csv = tmp_path / "out.csv"
    line = cli_error(capsys, "bench", "--synthetic", "--sizes", "tiny", "--solver", path, "--csv", csv, "--no-isolate")
    assert str(path) in line, line  # the line names the file
    assert not csv.exists()
    return line


BAD_PRESETS = {
    # what the preset holds: (TOML text or bytes, what the line says)
    "extra is a string": (GOOD + 'extra = "abc"\n', r"\[options.extra\] must be a table"),
    "extra is a list": (GOOD + "extra = [1, 2]\n", r"\[options.extra\] must be a table"),
    "extra holds a list": (GOOD + "[options.extra]\npresolve = [1, 2]\n", "presolve = \\[1, 2\\] must be a string"),
    "extra holds a table": (GOOD + "[options.extra.sub]\nx = 1\n", "sub = .* must be a string"),
    "extra holds a date": (GOOD + "[options.extra]\nwhen = 1979-05-27\n", "when = .* must be a string"),
    "extra holds nan": (GOOD + "[options.extra]\ntol = nan\n", "tol = nan must be a string, integer, finite"),
    "time limit nan": (GOOD.replace("60.0", "nan"), "time_limit_s = nan must be a finite number"),
    "time limit inf": (GOOD.replace("60.0", "inf"), "time_limit_s = inf must be a finite number"),
    "time limit -inf": (GOOD.replace("60.0", "-inf"), "time_limit_s = -inf must be a finite number"),
    "time limit zero": (GOOD.replace("60.0", "0"), "time_limit_s must be > 0"),
    "time limit absurd": (GOOD.replace("60.0", "1e300"), "time_limit_s must be <= 1e\\+06"),
    "gap nan": (GOOD.replace("mip_rel_gap = 0.0", "mip_rel_gap = nan"), "mip_rel_gap = nan must be a finite"),
    "gap inf": (GOOD.replace("mip_rel_gap = 0.0", "mip_rel_gap = inf"), "mip_rel_gap = inf must be a finite"),
    "gap above 1": (GOOD.replace("mip_rel_gap = 0.0", "mip_rel_gap = 2.5"), "mip_rel_gap must be <= 1"),
    "gap negative": (GOOD.replace("mip_rel_gap = 0.0", "mip_rel_gap = -0.1"), "mip_rel_gap must be >= 0"),
    "threads zero": (GOOD.replace("threads = 1", "threads = 0"), "threads must be >= 1"),
    "threads absurd": (GOOD.replace("threads = 1", "threads = 100000"), "threads must be <= 1024"),
    "threads fractional": (GOOD.replace("threads = 1", "threads = 1.5"), "threads = 1.5 must be of type int"),
    "threads boolean": (GOOD.replace("threads = 1", "threads = true"), "threads = True must be of type int"),
    "method a number": (GOOD + "method = 3\n", "method = 3 must be of type str"),
    "description a table": ('backend = "highs"\n[description]\nx = 1\n', "description = .* must be a string"),
    "options a string": ('backend = "highs"\noptions = "fast"\n', r"\[options\] must be a table"),
    "no backend": ("[options]\nthreads = 1\n", "backend = None is not one of"),
    "not TOML": ("this is not toml at all\n", "is not valid TOML"),
    "binary garbage": (bytes(range(1, 40)) * 3, "is not valid TOML"),
    "latin-1 text": ('backend = "highs"\ndescription = "d\xe9j\xe0 vu"\n'.encode("latin-1"), "is not UTF-8"),
    "utf-16 text": (GOOD.encode("utf-16"), "is not UTF-8"),
}


@pytest.mark.parametrize("case", BAD_PRESETS)
def test_bad_preset_is_one_line_naming_the_file(capsys, tmp_path, case):
    text, message = BAD_PRESETS[case]
    line = bench_with(capsys, tmp_path, text)
    assert re.search(message, line), line


def test_preset_that_is_a_folder(capsys, tmp_path):
    folder = tmp_path / "dir.toml"
    folder.mkdir()
    line = cli_error(capsys, "bench", "--synthetic", "--solver", folder)
    assert "is a folder" in line and str(folder) in line  # named for what it is, not "missing"


def test_valid_preset_values_still_parse():
    text = (
        GOOD + 'method = "lp"\n[options.extra]\npresolve = "off"\nmip_feasibility_tolerance = 1e-7\n'
        "random_seed = 3\nlog_to_console = false\n"
    )
    preset = parse_preset("good", text, "good.toml")
    assert preset.options.extra == {
        "presolve": "off",
        "mip_feasibility_tolerance": 1e-7,
        "random_seed": 3,
        "log_to_console": False,
    }
    assert (preset.options.threads, preset.options.time_limit_s, preset.options.mip_rel_gap) == (1, 60.0, 0.0)


UNHONOURED = {
    # backend, [options] line, what the line names
    "matching method": ("matching", 'method = "simplex"', "option method = 'simplex'"),
    "matching solver": ("matching", 'solver = "HIGHS"', "option solver = 'HIGHS'"),
    "matching gap": ("matching", "mip_rel_gap = 0.01", "option mip_rel_gap = 0.01"),
    "blossom method": ("blossom", 'method = "lp"', "option method = 'lp'"),
    "highs solver": ("highs", 'solver = "gurobi"', "option solver = 'gurobi'"),
    "ortools solver": ("ortools", 'solver = "scip"', "option solver = 'scip'"),
    "scipy threads": ("scipy", "threads = 4", "option threads = 4"),
}


@pytest.mark.parametrize("case", UNHONOURED)
def test_an_option_the_backend_cannot_honour_is_refused(capsys, tmp_path, case):
    backend, line, message = UNHONOURED[case]
    text = f'backend = "{backend}"\n[options]\n{line}\n'
    error = bench_with(capsys, tmp_path, text)
    assert f"backend {backend!r} does not honour {message}" in error, error


def test_a_run_with_an_unhonoured_preset_option_writes_nothing(capsys, tmp_path):
    preset = tmp_path / "m.toml"
    preset.write_text('backend = "matching"\n[options]\nmethod = "simplex"\n')
    out = tmp_path / "out"
    argv = ("run", "--scenario", "toy", "--sample", "0.1", "--strategies", "mb", "--solver", preset, "--out", out)
    line = cli_error(capsys, *argv)
    assert "backend 'matching' does not honour option method" in line
    assert not out.exists()


@pytest.mark.parametrize("backend", ["matching", "blossom", "scipy"])
def test_default_values_of_unhonoured_options_still_parse(backend):
    """``mip_rel_gap = 0`` asks an exact backend for nothing it does not do; ``threads = 1`` neither."""
    preset = parse_preset("p", f'backend = "{backend}"\n[options]\nthreads = 1\nmip_rel_gap = 0.0\n', "p.toml")
    assert preset.options.mip_rel_gap == 0.0


def test_every_shipped_preset_still_parses():
    from rpbench.backends.presets import load_preset, preset_names

    assert {load_preset(name).name for name in preset_names()} == set(preset_names())
