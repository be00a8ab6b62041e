"""The first run on a machine without a data folder: the automatic fetch, its fall-back to the toy city, --offline.

Every test here is a fresh machine: no ``$RPBENCH_DATA``, no ``../shared``
beside the current folder or the checkout, ``$RPBENCH_DATA_HOME`` in the
test's tmp folder.  The success path reads a mirror (``$RPBENCH_DATA_MIRROR``,
a copy of the real data folder); nothing touches the internet.  The Manhattan
tests also move the checkout away (its ../shared holds Manhattan's folder).
"""

from __future__ import annotations

import json
import shutil
import socket
import threading
import urllib.request
from pathlib import Path

import pytest

from rpbench.cli import main
from rpbench.data import fetch as fetch_mod
from rpbench.data import first_run
from rpbench.data.fetch import load_registry, verify_data
from rpbench.data.first_run import ensure_data_dir, fetch_plan, obtain_data_dir
from rpbench.exceptions import DataNotFoundError, DownloadError
from rpbench.files import paths
from rpbench.files.paths import fetched_data_dir, find_data_dir

REGISTRY = load_registry()
NAMES = [e.name for e in REGISTRY]
CONTENT_MB = f"{sum(e.size for e in REGISTRY) / 1e6:.1f} MB"
MANHATTAN = load_registry(city="manhattan")
MANHATTAN_NAMES = [e.name for e in MANHATTAN]
MANHATTAN_MB = f"{sum(e.size for e in MANHATTAN) / 1e6:.1f} MB"
REFUSED = "http://127.0.0.1:9/"  # the discard port: nothing listens, the connection is refused at once
BANNER = "SYNTHETIC DATA: the numbers that follow are from the built-in toy city"


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def scenario_name(folder: Path) -> str:
    return json.loads((folder / "meta.json").read_text())["scenario"]["name"]


def files_under(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*")) if folder.exists() else []


@pytest.fixture(autouse=True)
def fresh_machine(tmp_path, monkeypatch) -> Path:
    """No data folder anywhere rpbench looks; returns the data home (not created)."""
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, REFUSED)  # never GitHub, whatever a test forgets
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    # ../shared beside the current folder and beside a checkout elsewhere (the real checkout holds the presets)
    shared = [(tmp_path / "shared" / "data" / "haikou").resolve(), (tmp_path / "x" / "shared").resolve()]
    monkeypatch.setattr("rpbench.files.paths.default_data_candidates", lambda: [*shared, fetched_data_dir().resolve()])
    home = tmp_path / "data-home"
    monkeypatch.setenv("RPBENCH_DATA_HOME", str(home))
    assert all(not c.exists() for c in paths.default_data_candidates()) and find_data_dir() is None
    return home


@pytest.fixture(scope="module")
def mirror_folder(data_dir, tmp_path_factory) -> Path:
    """A copy of the real data folder, served as a mirror (a local folder, as ``--mirror`` takes)."""
    if verify_data(data_dir).missing:
        pytest.skip(f"the data folder {data_dir} lacks registry files")
    copy = tmp_path_factory.mktemp("mirror") / "haikou"
    shutil.copytree(data_dir, copy)
    return copy


@pytest.fixture
def no_network(monkeypatch):
    """Any download, socket connection or fetch fails the test."""

    def refuse(*args, **kwargs):
        pytest.fail(f"the network was touched: {args!r}")

    monkeypatch.setattr(fetch_mod, "_open_url", refuse)
    monkeypatch.setattr(first_run, "fetch", refuse)
    monkeypatch.setattr(urllib.request, "urlopen", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)


# --------------------------------------------------------------------------- (a) the fetch succeeds


def test_the_first_run_fetches_from_the_mirror_and_later_commands_find_it(
    capsys, monkeypatch, fresh_machine, mirror_folder, tmp_path
):
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, str(mirror_folder))
    out = tmp_path / "run"
    code, stdout, err = run_cli(capsys, "run", "--strategies", "mb", "--sample", "0.1", "--out", out, "--no-progress")
    assert code == 0, err
    dest = (fresh_machine / "haikou").resolve()
    announce, done = [line for line in err.splitlines() if "Haikou data" in line or "fetched" in line][:2]
    assert announce == (
        f"rpbench: no Haikou data folder found: fetching it once ({len(NAMES)} files, {CONTENT_MB} of content, "
        f"served gzipped, SHA-256 checked) from the mirror {mirror_folder.as_uri()} into {dest}"
    )
    assert done.startswith(f"rpbench: fetched {len(NAMES)} files ({CONTENT_MB} of content, checksums verified)")
    assert BANNER not in err
    report = verify_data(dest)
    assert report.ok == NAMES and not report.bad and not report.extra  # complete, no .part file left
    for name in NAMES:  # a mirror's files are stored as served
        assert (dest / name).read_bytes() == (mirror_folder / name).read_bytes()
    assert scenario_name(out) == "haikou-peak" and "Haikou 2017-05-01 08:00-09:00" in stdout

    # From now on the folder is found: no fetch, even with the mirror gone.
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, REFUSED)
    code, stdout, err = run_cli(capsys, "list", "--json")
    info = json.loads(stdout)
    assert info["data_dir"] == str(dest) and info["data_fetch_pending"] is None
    code, stdout, err = run_cli(capsys, "scenario", "haikou-peak", "--sample", "0.1", "--json")
    assert code == 0 and err == "" and json.loads(stdout)["scenario"] == "haikou-peak"
    assert ensure_data_dir(what="rpbench predict") == dest


def test_a_cut_fetch_is_resumed_by_the_next_command(capsys, monkeypatch, fresh_machine, mirror_folder):
    dest = fresh_machine / "haikou"
    first = [e for e in REGISTRY if e.name.startswith("network/")]
    fetch_mod.fetch(dest, mirror_folder, entries=first, progress=False)  # what a cut fetch leaves
    code, stdout, err = run_cli(capsys, "list")
    assert f"lacks {len(NAMES) - len(first)} of its {len(NAMES)} files" in stdout

    # Offline, the partial folder is not used: the toy city runs, saying what is missing.
    code, stdout, err = run_cli(capsys, "scenario", "toy", "--json")  # named: no banner, no fetch
    assert code == 0 and err == ""
    code, stdout, err = run_cli(capsys, "run", "--offline", "--strategies", "mb", "--no-progress", "--json")
    assert code == 0 and BANNER in err
    assert f"lacks {len(NAMES) - len(first)} of its {len(NAMES)} files and --offline skips fetching them" in err
    assert json.loads(stdout)["scenario"].startswith("SYNTHETIC toy city")

    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, mirror_folder.as_uri())
    code, stdout, err = run_cli(capsys, "scenario", "haikou-peak", "--sample", "0.1", "--json")
    assert code == 0, err
    assert f"resuming the fetch ({len(NAMES) - len(first)} files" in err
    assert f"rpbench: fetched {len(NAMES) - len(first)} files" in err
    assert verify_data(dest).ok == NAMES


def test_ensure_data_dir_fetches_for_commands_that_need_the_data(capsys, monkeypatch, fresh_machine, mirror_folder):
    """`rpbench predict` and `rpbench replicate` take their folder from ensure_data_dir."""
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, str(mirror_folder))
    assert ensure_data_dir(what="rpbench predict") == (fresh_machine / "haikou").resolve()
    assert "fetching it once" in capsys.readouterr().err
    assert ensure_data_dir(what="rpbench predict") == (fresh_machine / "haikou").resolve()
    assert capsys.readouterr().err == ""


# --------------------------------------------------------------------------- (b) the fetch fails


def test_a_refused_fetch_runs_the_toy_city_under_a_banner(capsys, fresh_machine, tmp_path):
    out = tmp_path / "run"
    code, stdout, err = run_cli(capsys, "run", "--strategies", "mb", "--sample", "0.1", "--out", out, "--no-progress")
    assert code == 0, err
    lines = err.splitlines()
    assert lines[0].startswith("rpbench: no Haikou data folder found: fetching it once")
    banner = lines[1:4]
    assert banner[0] == f"rpbench: {BANNER} (a small grid generated in code), not from Haikou"
    assert banner[1] == (
        f"rpbench:   why: no Haikou data folder found and fetching it failed: could not download {NAMES[0]} "
        f"from {REFUSED}{NAMES[0]}: [Errno 111] Connection refused"
    )
    assert banner[2] == "rpbench:   to get the real data: rpbench data fetch"
    assert scenario_name(out) == "toy" and "SYNTHETIC toy city" in stdout
    assert files_under(fresh_machine) == []  # nothing half-written, not even an empty folder


def test_a_named_haikou_scenario_is_not_swapped_for_the_toy_city(capsys, fresh_machine, tmp_path):
    out = tmp_path / "run"
    code, stdout, err = run_cli(capsys, "run", "--scenario", "haikou-peak", "--strategies", "mb", "--out", out)
    assert code == 2 and stdout == "" and not out.exists() and BANNER not in err
    line = err.splitlines()[-1]
    assert line.startswith(
        "rpbench: error: no Haikou data for scenario 'haikou-peak': no Haikou data folder found and fetching it "
        f"failed: could not download {NAMES[0]}"
    )
    assert "get it with `rpbench data fetch`" in line and "check the network" not in line


def test_a_host_that_does_not_answer_fails_within_the_read_timeout(monkeypatch, tmp_path):
    """A server that accepts the connection and never answers: the download stops at the read timeout."""
    connect_timeouts: list[float | None] = []
    real_connect = socket.create_connection

    def connect(address, timeout=None, *args, **kwargs):
        connect_timeouts.append(timeout)
        return real_connect(address, timeout, *args, **kwargs)

    monkeypatch.setattr(socket, "create_connection", connect)
    monkeypatch.setattr(fetch_mod, "READ_TIMEOUT_S", 0.2)
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        accepted: list[socket.socket] = []
        thread = threading.Thread(target=lambda: accepted.append(server.accept()[0]), daemon=True)
        thread.start()
        url = f"http://127.0.0.1:{server.getsockname()[1]}"
        with pytest.raises(DownloadError, match=f"could not download {NAMES[0]} from {url}.*timed out"):
            fetch_mod.fetch(tmp_path / "dest", url, progress=False)
        thread.join()
        for conn in accepted:
            conn.close()
    assert connect_timeouts == [fetch_mod.CONNECT_TIMEOUT_S]
    assert not (tmp_path / "dest").exists()


# --------------------------------------------------------------------------- (c) --offline, (d) --scenario toy


def test_offline_runs_the_toy_city_without_touching_the_network(capsys, no_network, fresh_machine, tmp_path):
    out = tmp_path / "run"
    code, stdout, err = run_cli(
        capsys, "run", "--offline", "--strategies", "mb", "--sample", "0.1", "--out", out, "--no-progress"
    )
    assert code == 0, err
    assert err.splitlines()[:3] == [
        f"rpbench: {BANNER} (a small grid generated in code), not from Haikou",
        "rpbench:   why: no Haikou data folder found and --offline skips fetching it",
        "rpbench:   to get the real data: rpbench data fetch",
    ]
    assert scenario_name(out) == "toy"
    assert not fresh_machine.exists()

    code, stdout, err = run_cli(capsys, "scenario", "haikou-peak", "--offline")
    assert code == 2 and err == (
        "rpbench: error: no Haikou data for scenario 'haikou-peak': no Haikou data folder found and --offline "
        f"skips fetching it (folders tried: {', '.join(str(c) for c in paths.default_data_candidates())}); get it with "
        "`rpbench data fetch` (it resumes a cut fetch; $RPBENCH_DATA_MIRROR names a mirror), pass --data DIR "
        "or set $RPBENCH_DATA\n"
    )
    with pytest.raises(DataNotFoundError, match="--offline skips fetching it"):
        ensure_data_dir(what="rpbench predict", offline=True)


@pytest.mark.parametrize("command", ["run", "oracle", "snapshot", "sweep", "scenario"])
def test_every_command_with_scenario_arguments_takes_offline(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0 and "--offline" in capsys.readouterr().out


def test_the_toy_city_asked_for_by_name_fetches_nothing_and_shows_no_banner(
    capsys, no_network, fresh_machine, tmp_path
):
    out = tmp_path / "run"
    code, stdout, err = run_cli(
        capsys, "run", "--scenario", "toy", "--strategies", "mb", "--sample", "0.1", "--out", out, "--no-progress"
    )
    assert code == 0, err
    assert "SYNTHETIC DATA" not in err and "fetch" not in err
    assert scenario_name(out) == "toy"
    assert not fresh_machine.exists()


# --------------------------------------------------------------------------- the mirror variable, list, verify


def test_rpbench_data_fetch_reads_the_mirror_variable(capsys, monkeypatch, fresh_machine, mirror_folder):
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, str(mirror_folder))
    code, stdout, _ = run_cli(capsys, "data", "fetch", "--dry-run", "--json")
    assert code == 0 and json.loads(stdout)["files"][NAMES[0]] == f"{mirror_folder.as_uri()}/{NAMES[0]}"
    code, stdout, _ = run_cli(capsys, "data", "fetch", "--json")
    assert code == 0 and json.loads(stdout)["source"] == mirror_folder.as_uri()
    assert verify_data(fresh_machine / "haikou").ok == NAMES

    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, "no-such-folder")
    code, _, err = run_cli(capsys, "data", "fetch", "--dest", fresh_machine / "other")
    assert code == 2 and "$RPBENCH_DATA_MIRROR 'no-such-folder' is neither" in err


def test_list_says_what_the_first_command_will_fetch(capsys, no_network, monkeypatch, fresh_machine):
    monkeypatch.setattr("rpbench.commands.list.preset_names", list)  # no presets: skip importing solver libraries
    monkeypatch.delenv(first_run.DATA_MIRROR_ENV)
    code, stdout, _ = run_cli(capsys, "list")
    dest = fresh_machine / "haikou"
    assert code == 0 and "data folder: none found\n" in stdout
    assert (
        f"the first command that needs the data fetches {len(NAMES)} files ({CONTENT_MB} of content) from the "
        f"pinned GitHub sources into {dest}"
    ) in stdout
    code, stdout, _ = run_cli(capsys, "list", "--json")
    pending = json.loads(stdout)["data_fetch_pending"]
    assert pending == {
        "dest": str(dest),
        "source": "registry",
        "files": len(NAMES),
        "registry_files": len(NAMES),
        "content_bytes": sum(e.size for e in REGISTRY),
    }
    code, _, err = run_cli(capsys, "data", "verify")
    assert code == 2 and "no Haikou data folder found to verify" in err and not fresh_machine.exists()


# --------------------------------------------------------------------------- Manhattan


@pytest.fixture
def no_shared_manhattan(monkeypatch, tmp_path, fresh_machine) -> Path:
    """No Manhattan folder either: the checkout (whose ../shared holds one) is elsewhere; returns its fetched
    folder (not created)."""
    monkeypatch.setattr("rpbench.files.paths.source_root", lambda: tmp_path / "x" / "checkout")
    monkeypatch.setattr("rpbench.commands.list.preset_names", list)  # no presets: skip importing solver libraries
    assert find_data_dir(city="manhattan") is None
    return fresh_machine / "manhattan"


@pytest.fixture
def city_mirrors(manhattan_data_dir, tmp_path) -> Path:
    """``mirrors/{city}``: a folder holding a copy of the Manhattan data folder as ``mirrors/manhattan``."""
    shutil.copytree(manhattan_data_dir, tmp_path / "mirrors" / "manhattan")
    return tmp_path / "mirrors" / "{city}"


@pytest.mark.manhattan
def test_the_first_use_of_manhattan_fetches_it_from_the_city_mirror(
    capsys, monkeypatch, no_shared_manhattan, city_mirrors
):
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, str(city_mirrors))  # one value for every city: {city}
    dest = no_shared_manhattan.resolve()
    served = Path(str(city_mirrors).replace("{city}", "manhattan"))
    assert ensure_data_dir(what="scenario 'manhattan-peak'", city="manhattan") == dest
    announce, done = capsys.readouterr().err.splitlines()
    assert announce == (
        f"rpbench: no Manhattan data folder found: fetching it once ({len(MANHATTAN)} files, {MANHATTAN_MB} of "
        f"content, served gzipped, SHA-256 checked) from the mirror {served.as_uri()} into {dest}"
    )
    assert done.startswith(f"rpbench: fetched {len(MANHATTAN)} files ({MANHATTAN_MB} of content, checksums verified)")
    report = verify_data(dest, city="manhattan")
    assert report.ok == MANHATTAN_NAMES and not report.bad and not report.extra  # complete, no .part file left
    assert not (dest.parent / "haikou").exists()  # the other city's folder is not touched

    # Found from now on, even with the mirror gone.
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, REFUSED)
    assert ensure_data_dir(what="scenario 'manhattan-peak'", city="manhattan") == dest
    assert capsys.readouterr().err == ""


@pytest.mark.manhattan
def test_a_cut_manhattan_fetch_is_resumed(capsys, monkeypatch, no_shared_manhattan, city_mirrors):
    served = Path(str(city_mirrors).replace("{city}", "manhattan"))
    first = [e for e in MANHATTAN if e.name.startswith("network/")]
    fetch_mod.fetch(no_shared_manhattan, served, entries=first, progress=False)  # what a cut fetch leaves
    todo = len(MANHATTAN) - len(first)
    lacks = f"the fetched Manhattan data folder {no_shared_manhattan} lacks {todo} of its {len(MANHATTAN)} files"
    assert obtain_data_dir(offline=True, city="manhattan") == (None, f"{lacks} and --offline skips fetching them")
    monkeypatch.setenv(first_run.DATA_MIRROR_ENV, str(city_mirrors))
    folder, why = obtain_data_dir(city="manhattan")
    assert folder == no_shared_manhattan.resolve() and why == ""
    assert f"rpbench: {lacks}: resuming the fetch ({todo} files" in capsys.readouterr().err
    assert verify_data(folder, city="manhattan").ok == MANHATTAN_NAMES


def test_without_manhattan_data_the_errors_name_manhattan(capsys, monkeypatch, no_shared_manhattan, tmp_path):
    # $RPBENCH_DATA names Haikou's folder: it is no Manhattan folder.
    monkeypatch.setenv("RPBENCH_DATA", str(tmp_path))
    tried = ", ".join(str(c) for c in paths.candidate_data_dirs("manhattan"))
    assert tried.endswith(str(no_shared_manhattan.resolve()))
    with pytest.raises(DataNotFoundError) as offline:
        ensure_data_dir(what="scenario 'manhattan-peak'", offline=True, city="manhattan")
    assert str(offline.value) == (
        "no Manhattan data for scenario 'manhattan-peak': no Manhattan data folder found and --offline skips "
        f"fetching it (folders tried: {tried}); get it with `rpbench data fetch --city manhattan` (it resumes a "
        "cut fetch; $RPBENCH_DATA_MIRROR names a mirror), or pass --data DIR"
    )
    first = MANHATTAN_NAMES[0]
    with pytest.raises(DataNotFoundError) as refused:  # the session's mirror refuses
        ensure_data_dir(what="scenario 'manhattan-peak'", city="manhattan")
    assert (
        "no Manhattan data folder found and fetching it failed: could not download "
        f"{first} from {REFUSED}{first}: [Errno 111] Connection refused (folders tried:"
    ) in str(refused.value)
    assert "check the network" not in str(refused.value)  # the error says what to run itself
    assert capsys.readouterr().err.startswith("rpbench: no Manhattan data folder found: fetching it once")
    assert files_under(no_shared_manhattan.parent) == []  # nothing half-written, not even an empty folder
    with pytest.raises(DataNotFoundError, match="point --data at the Manhattan data folder"):
        obtain_data_dir(tmp_path / "nothing", city="manhattan")


def test_list_and_verify_say_where_each_city_is(capsys, no_network, monkeypatch, no_shared_manhattan):
    monkeypatch.delenv(first_run.DATA_MIRROR_ENV)
    code, stdout, _ = run_cli(capsys, "list")
    assert code == 0 and "\ndata folder: none found\n" in f"\n{stdout}"
    assert "\nManhattan data folder: none found\n" in stdout
    assert (
        f"the first command that needs the data fetches {len(MANHATTAN)} files ({MANHATTAN_MB} of content) from "
        f"the pinned GitHub sources into {no_shared_manhattan} (now: `rpbench data fetch --city manhattan`)"
    ) in stdout
    code, stdout, _ = run_cli(capsys, "list", "--json")
    info = json.loads(stdout)
    assert list(info["data_folders"]) == ["haikou", "manhattan"]
    assert info["data_folders"]["haikou"] == {
        "label": "Haikou",
        **{k: info[k] for k in ("data_dir", "data_dir_source", "data_dir_candidates", "data_fetch_pending")},
    }
    manhattan = info["data_folders"]["manhattan"]
    assert manhattan["data_dir"] is None and manhattan["label"] == "Manhattan"
    assert manhattan["data_dir_candidates"] == [str(c) for c in paths.candidate_data_dirs("manhattan")]
    assert manhattan["data_fetch_pending"] == {**fetch_plan("manhattan").as_dict(), "files": len(MANHATTAN)}
    code, _, err = run_cli(capsys, "data", "verify", "--city", "manhattan")
    assert code == 2 and "no Manhattan data folder found to verify" in err
    assert "fetch it with `rpbench data fetch --city manhattan`, or pass --data DIR\n" in err
    assert not no_shared_manhattan.parent.exists()
