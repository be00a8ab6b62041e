"""Malformed JSON and TOML files, paths that are not regular files, non-UTF-8 paths, bad instance metadata
and meta.json without what a report shows: one line naming the file, exit status 2, nothing written."""

from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from rpbench.model import PairingModel
from rpbench.model.instances import save_instance

from .test_inputs_helpers import PEAK, TOY_RUN, cli_error, cli_ok

DEEP = 100_000  # far beyond the parsers' recursion limit


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def toy_folder(tmp_path_factory) -> Path:
    """A complete toy results folder (copy it before damaging it)."""
    from rpbench.cli import main

    out = tmp_path_factory.mktemp("toy") / "run"
    assert main([*TOY_RUN, "--out", str(out)]) == 0
    return out


def copy_of(folder: Path, tmp_path: Path, name: str = "copy") -> Path:
    dest = tmp_path / name
    shutil.copytree(folder, dest)
    return dest


def edit_meta(folder: Path, change) -> None:
    path = folder / "meta.json"
    meta = json.loads(path.read_text())
    change(meta)
    path.write_text(json.dumps(meta))


# ------------------------------------------------------------------ deeply nested JSON and TOML
@pytest.mark.parametrize("command", ["check", "report"])
def test_deeply_nested_meta_json_is_one_line(capsys, tmp_path, toy_folder, command):
    folder = copy_of(toy_folder, tmp_path)
    (folder / "meta.json").write_text("[" * DEEP + "]" * DEEP)
    before = sorted(p.name for p in folder.iterdir())
    line = cli_error(capsys, command, folder)
    assert "meta.json" in line and "nested too deeply" in line
    assert sorted(p.name for p in folder.iterdir()) == before


def test_deeply_nested_preset_toml_is_one_line(capsys, tmp_path):
    preset = tmp_path / "deep.toml"
    preset.write_text('backend = "highs"\n[options]\nextra = {a = ' + "[" * DEEP + "]" * DEEP + "}\n")
    out = tmp_path / "out"
    line = cli_error(capsys, *TOY_RUN, "--solver", preset, "--out", out)
    assert str(preset) in line and "not valid TOML" in line and "nested too deeply" in line
    assert not out.exists()


def test_deeply_nested_protocol_toml_is_one_line(capsys, tmp_path):
    protocol = tmp_path / "deep.toml"
    protocol.write_text('name = "x"\nseeds = ' + "[" * DEEP + "]" * DEEP + "\n")
    out = tmp_path / "out"
    line = cli_error(capsys, "evaluate", protocol, "--out", out)
    assert str(protocol) in line and "not valid TOML" in line and "nested too deeply" in line
    assert not out.exists()


# ------------------------------------------------------------------ paths that are not regular files
def _folder(path: Path) -> None:
    path.mkdir()


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _loop(path: Path) -> None:
    path.symlink_to(path.name)  # a link to itself


KINDS = {
    "a folder": (_folder, "is a folder"),
    "a FIFO": (_fifo, "is not a regular file (a FIFO)"),
    "a symbolic link loop": (_loop, "is a symbolic link loop"),
}


@pytest.mark.parametrize("kind", list(KINDS))
def test_order_file_of_the_wrong_kind_is_named_as_such(capsys, tmp_path, fake_data, kind):
    make, said = KINDS[kind]
    orders = fake_data / PEAK
    orders.unlink()
    make(orders)
    out = tmp_path / "out"
    line = cli_error(
        capsys, "run", "--scenario", "haikou-peak", "--data", fake_data, "--strategies", "np", "--no-progress",
        "--out", out,
    )  # fmt: skip
    assert said in line and str(orders) in line and "does not exist" not in line
    assert not out.exists()


@pytest.mark.parametrize("kind", list(KINDS))
def test_network_file_of_the_wrong_kind_is_named_as_such(capsys, tmp_path, fake_data, kind):
    make, said = KINDS[kind]
    nodes = fake_data / "network" / "node.csv"
    nodes.unlink()
    make(nodes)
    line = cli_error(capsys, "scenario", "haikou-peak", "--data", fake_data)
    assert said in line and "node.csv" in line


@pytest.mark.parametrize("kind", list(KINDS))
def test_preset_and_protocol_files_of_the_wrong_kind_are_named_as_such(capsys, tmp_path, kind):
    make, said = KINDS[kind]
    path = tmp_path / "thing.toml"
    make(path)
    out = tmp_path / "out"
    assert said in cli_error(capsys, *TOY_RUN, "--solver", path, "--out", out)
    assert said in cli_error(capsys, "evaluate", path, "--out", out)
    assert not out.exists()


# ------------------------------------------------------------------ non-UTF-8 paths
def as_typed(monkeypatch, *argv) -> list[str]:
    """``argv`` as the command line meta.json records (the report quotes it)."""
    args = [str(a) for a in argv]
    monkeypatch.setattr(sys, "argv", ["rpbench", *args])
    return args


def test_non_utf8_out_folder_is_written_with_the_path_escaped(capsys, tmp_path, monkeypatch):
    out = Path(os.fsdecode(bytes(tmp_path) + b"/run\xff"))
    cli_ok(capsys, *as_typed(monkeypatch, *TOY_RUN, "--json", "--out", out))
    report = (out / "report.md").read_text(encoding="utf-8")  # UTF-8, the name's byte escaped
    assert "run\\xff" in report
    assert "run\\xff" in (out / "report.html").read_text(encoding="utf-8")
    checked, _ = cli_ok(capsys, "check", out)
    assert "(folder): OK" in checked
    text, _ = cli_ok(capsys, "report", out)
    assert "run\\xff" in text


def test_a_report_to_a_non_utf8_file_name_is_written(capsys, tmp_path, toy_folder, monkeypatch):
    target = Path(os.fsdecode(bytes(tmp_path) + b"/report\xff.md"))
    printed, _ = cli_ok(capsys, *as_typed(monkeypatch, "report", toy_folder, "--out", target))
    assert "report\\xff.md" in printed and target.read_text(encoding="utf-8").startswith("# rpbench")


def test_a_strict_terminal_encoding_prints_a_non_utf8_path_escaped(tmp_path):
    """Under an ASCII stdout (a strict locale), the path's byte is printed as an escape, not a crash."""
    import subprocess

    out = bytes(tmp_path) + b"/run\xff"
    env = {**os.environ, "PYTHONIOENCODING": "ascii", "RPBENCH_CACHE": str(tmp_path / "cache")}
    cli = "import sys; from rpbench.cli import main; sys.exit(main(sys.argv[1:]))"
    argv = ["run", "--scenario", "toy", "--sample", "0.1", "--strategies", "np", "--no-progress", "--out", out]
    done = subprocess.run([sys.executable, "-c", cli, *argv], env=env, capture_output=True, check=False)
    assert done.returncode == 0, done.stderr.decode(errors="replace")
    assert b"Traceback" not in done.stderr and b"results written to " in done.stdout
    assert b"run\\udcff" in done.stdout and os.path.isdir(out)


def test_non_utf8_data_folder_path_is_quoted_escaped(capsys, tmp_path, fake_data, monkeypatch):
    data = Path(os.fsdecode(bytes(tmp_path) + b"/data\xff"))
    fake_data.rename(data)
    out = tmp_path / "out"
    argv = ("run", "--scenario", "haikou-peak", "--data", data, "--strategies", "np", "--no-progress", "--out", out)
    cli_ok(capsys, *as_typed(monkeypatch, *argv))
    assert "data\\xff" in (out / "report.md").read_text(encoding="utf-8")
    missing = Path(os.fsdecode(bytes(tmp_path) + b"/none\xfe"))
    line = cli_error(capsys, "run", "--scenario", "haikou-peak", "--data", missing, "--out", tmp_path / "o2")
    assert "\\udcfe" in line and not (tmp_path / "o2").exists()


# ------------------------------------------------------------------ meta.json without what a report shows
META_FAULTS = {
    "no scenario": (lambda m: m.pop("scenario"), "lacks 'scenario'"),
    "no scenario label": (lambda m: m["scenario"].pop("label"), "lacks 'scenario.label'"),
    "scenario a string": (lambda m: m.update(scenario="toy"), "scenario is a string, not an object"),
    "orders a string": (
        lambda m: m["scenario"]["summary"].update(orders="40"),
        "scenario.summary.orders = '40' is a string, not an integer",
    ),
    "seed a boolean": (lambda m: m["scenario"].update(seed=True), "scenario.seed = True is a boolean"),
    "no preset": (lambda m: m.pop("preset"), "lacks 'preset'"),
    "runs a list": (lambda m: m.update(runs=[]), "runs = [] is a list, not an object"),
}


@pytest.mark.parametrize("fault", list(META_FAULTS))
def test_report_of_meta_json_lacking_a_key_is_one_line(capsys, tmp_path, toy_folder, fault):
    change, said = META_FAULTS[fault]
    folder = copy_of(toy_folder, tmp_path)
    edit_meta(folder, change)
    before = (folder / "report.md").read_bytes()
    line = cli_error(capsys, "report", folder)
    assert "meta.json" in line and said in line
    assert (folder / "report.md").read_bytes() == before


def test_check_of_meta_json_without_scenario_skips_the_report_check_naming_why(capsys, tmp_path, toy_folder):
    folder = copy_of(toy_folder, tmp_path)
    edit_meta(folder, lambda m: m.pop("scenario"))
    from rpbench.cli import main

    main(["check", str(folder)])
    out, _ = capsys.readouterr()
    assert "[report] skipped" in out and "lacks 'scenario'" in out


# ------------------------------------------------------------------ instance metadata
def instance(tmp_path: Path, meta: dict) -> Path:
    model = PairingModel(4, [0, 1, 2], [1, 2, 3], [10, 20, 30], name="p")
    return save_instance(tmp_path / "p.npz", model, meta)


INSTANCE_FAULTS = {
    "text objective": ({"status": "optimal", "objective": "abc"}, "objective = 'abc' is a string, not a number"),
    "text round": ({"round": "7"}, "round = '7' is a string, not an integer"),
    "list status": ({"status": ["optimal"]}, "status = ['optimal'] is a list, not a string"),
    "unknown status": ({"status": "great"}, "status = 'great' is not one of"),
    "infinite objective": ({"status": "optimal", "objective": float("inf")}, "objective = inf is not a finite"),
    "boolean seed": ({"seed": False}, "seed = False is a boolean"),
}


@pytest.mark.parametrize("fault", list(INSTANCE_FAULTS))
def test_instance_metadata_of_the_wrong_type_is_one_line(capsys, tmp_path, fault):
    meta, said = INSTANCE_FAULTS[fault]
    path = instance(tmp_path, meta)
    csv = tmp_path / "bench.csv"
    line = cli_error(capsys, "bench", path, "--solver", "highs", "--repeat", "1", "--no-isolate", "--csv", csv)
    assert str(path) in line and said in line
    assert not csv.exists()


def test_deeply_nested_instance_metadata_is_one_line(capsys, tmp_path):
    path = instance(tmp_path, {})
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["meta_json"] = np.array("[" * DEEP + "]" * DEEP)
    np.savez_compressed(path, **arrays)
    line = cli_error(capsys, "bench", path, "--solver", "highs", "--repeat", "1", "--no-isolate")
    assert str(path) in line and "nested too deeply" in line


def test_instance_metadata_rpbench_writes_still_loads(capsys, tmp_path):
    meta = {"scenario": "toy", "scenario_name": "toy", "seed": 0, "strategy": "mb", "round": 3, "t_s": 30.0,
            "preset": "highs", "objective": None, "status": "time_limit", "size": {"rows": 4}}  # fmt: skip
    cli_ok(capsys, "bench", instance(tmp_path, meta), "--solver", "highs", "--repeat", "1", "--no-isolate")
