"""``rpbench data fetch`` / ``verify`` against a local HTTP server serving a copy of the data folder.

Nothing here touches the internet nor the real data folders: the server serves a
temporary copy, the upstream (non-mirror) route is exercised by replacing the
URL opener, and ``$RPBENCH_DATA_HOME`` points into the test's tmp folder.  The
Manhattan tests (marked ``manhattan``) read a copy of ../shared/data/manhattan,
served as a ``file://`` mirror.
"""

from __future__ import annotations

import functools
import gzip
import hashlib
import io
import json
import re
import shutil
import socket
import threading
import tomllib
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from rpbench.cli import main
from rpbench.data import fetch as fetch_mod
from rpbench.data.fetch import REGISTRY_FILES, load_registry, mirror_base, source_urls, verify_data
from rpbench.data.hourly_counts import HOURLY_FILE
from rpbench.data.od_rates import AUTHORS_PREDICTION_FILE, DAY_OD_FILE, MONTH_OD_FILE
from rpbench.data.orders import GAIA_SAMPLE_FILE, PEAK_DIR, RAW_PEAK_FILE, TRACE_FILE
from rpbench.data.road import LINK_FILE, NODE_FILE, PRED_EDGE_FILE, PRED_VERTEX_FILE
from rpbench.exceptions import DataError, DataNotFoundError, ParameterError
from rpbench.files.paths import CITY_LABELS, default_data_candidates, describe_candidate, find_data_dir, locate_data_dir

REGISTRY = load_registry()
NAMES = [e.name for e in REGISTRY]
BY_NAME = {e.name: e for e in REGISTRY}
# The commits SOURCE.md pins, per repository.
PINNED_COMMITS = {
    "yangchen-seu/RL-ridepooling": {"16bdaef446ae9c73c3aa560f8d6081d66bf884f9"},
    "yangchen-seu/ridepooling-simulation-with-sumo": {"ed108f8508e0cadf450849d0774293311049a8a5"},
    "seanys/Predicting-the-Matching-Probability-and-Expected-Ride-shared-Distance-of-Enroute-Ridepooling-Orders": {
        "61538880f9ce99ea6a22113ec991e5d454470c91",
        "ac767e22467c1981f66e70cc5aacf4208c5e27c8",
    },
    "bazilong/Traffic-analysis": {"d719311210371f3993582462acfd846532304460"},
    "MYXue/CCF_2019_Haikou_traffic_analysis": {"fdf333be827174e90034f056bbd452170e97a645"},
    "jackye330/ridesharing": {"9003ffd2bcfdd8baad0e7f31e91a6e4762dd7a67"},
}
MANHATTAN = load_registry(city="manhattan")
MANHATTAN_NAMES = [e.name for e in MANHATTAN]
# The commits ../shared/data/manhattan/SOURCE.md pins, per repository.
MANHATTAN_COMMITS = {
    "jackye330/ridesharing": "a4625d6151468add477227f439efdc702c8a2c33",
    "a20r/nyc-taxi-analysis": "6d166f2b6cc22a8ded20ab0930db4ee9c2f54db7",
}
# Each pinned Manhattan file's repository and path upstream, as SOURCE.md gives them.
MANHATTAN_UPSTREAM = {
    "network/Manhattan.graphml.gz": ("jackye330/ridesharing", "network_data/Manhattan.graphml"),
    "demand/trips_fullday_by_node.csv.gz": ("jackye330/ridesharing", "order_data/trip_order_data.csv"),
    **{
        f"network_pnas2017/{n}.csv.gz": ("a20r/nyc-taxi-analysis", f"data/nyc-graph/{n}.csv")
        for n in ("points", "edges", "week", "sat", "sun")
    },
}
# The files of the Manhattan folder SOURCE.md derives from the graphml: no public URL serves them.
MANHATTAN_DERIVED = ["network/edges.csv.gz", "network/nodes.csv"]


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(err: str) -> str:
    """The CLI's error line (tqdm may have drawn a bar on stderr before it)."""
    assert err.endswith("\n")
    last = err.rstrip("\n").rsplit("\n", 1)[-1].rsplit("\r", 1)[-1]
    assert last.startswith("rpbench: error: "), err
    return last


def part_files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*.part")] if folder.exists() else []


def flip_byte(path: Path, offset: int = 100) -> None:
    data = bytearray(path.read_bytes())
    data[offset] ^= 0x01
    path.write_bytes(bytes(data))


def change_content_byte(path: Path, offset: int = 100) -> None:
    """Change one byte of a stored file's *content* (re-gzipping a .gz file, so it stays valid gzip)."""
    if path.suffix != ".gz":
        flip_byte(path, offset)
        return
    data = bytearray(gzip.decompress(path.read_bytes()))
    data[offset] ^= 0x01
    path.write_bytes(gzip.compress(bytes(data)))


@pytest.fixture(autouse=True)
def private_data_home(tmp_path, monkeypatch) -> Path:
    """Never write into the real user data directory."""
    home = tmp_path / "data-home"
    monkeypatch.setenv("RPBENCH_DATA_HOME", str(home))
    return home


@pytest.fixture(scope="module")
def pristine(data_dir, tmp_path_factory) -> Path:
    """A copy of the real data folder (the served side; tests damage copies of it, never the folder itself)."""
    if verify_data(data_dir).missing:
        pytest.skip(f"the data folder {data_dir} lacks registry files")
    copy = tmp_path_factory.mktemp("served") / "haikou"
    shutil.copytree(data_dir, copy)
    return copy


@pytest.fixture
def served_dir(pristine, tmp_path) -> Path:
    copy = tmp_path / "served"
    shutil.copytree(pristine, copy)
    return copy


class _QuietHandler(SimpleHTTPRequestHandler):
    requests: list[str]

    def log_message(self, *args) -> None:
        pass

    def do_GET(self) -> None:
        self.requests.append(self.path)
        super().do_GET()


class _QuietServer(ThreadingHTTPServer):
    def handle_error(self, request, client_address) -> None:
        pass  # a client that stops reading a corrupt file breaks the pipe: not news


def start_server(root: Path):
    requests: list[str] = []
    handler = type("Handler", (_QuietHandler,), {"requests": requests})
    server = _QuietServer(("127.0.0.1", 0), functools.partial(handler, directory=str(root)))
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    return server, f"http://127.0.0.1:{server.server_address[1]}", requests


@pytest.fixture
def mirror(served_dir):
    """``(base URL, list of requested paths, served folder)`` of a local HTTP server."""
    server, url, requests = start_server(served_dir)
    yield url, requests, served_dir
    server.shutdown()
    server.server_close()


@pytest.fixture(scope="module")
def fetched_once(pristine, tmp_path_factory) -> Path:
    dest = tmp_path_factory.mktemp("fetched") / "haikou"
    fetch_mod.fetch(dest, pristine, progress=False)  # a local folder as mirror
    return dest


@pytest.fixture
def fetched(fetched_once, tmp_path) -> Path:
    copy = tmp_path / "fetched"
    shutil.copytree(fetched_once, copy)
    return copy


# --------------------------------------------------------------------------- the registry


def test_registry_covers_every_file_rpbench_reads():
    read = [
        NODE_FILE,
        LINK_FILE,
        PRED_VERTEX_FILE,
        PRED_EDGE_FILE,
        RAW_PEAK_FILE,
        GAIA_SAMPLE_FILE,
        TRACE_FILE,
        MONTH_OD_FILE,
        DAY_OD_FILE,
        AUTHORS_PREDICTION_FILE,
        HOURLY_FILE,
        *(PEAK_DIR / f"2017-05-{d:02d}.csv.gz" for d in range(1, 15)),
    ]
    assert {p.as_posix() for p in read} <= set(NAMES)
    assert all(e.transform == ("gzip" if e.name.endswith(".gz") else "none") for e in REGISTRY)


def test_urls_without_mirror_are_the_pinned_raw_github_ones(monkeypatch):
    monkeypatch.delenv("RPBENCH_DATA_MIRROR", raising=False)  # the test session's refusing mirror
    urls = dict(source_urls())
    assert list(urls) == NAMES
    assert urls["network/node.csv"] == (
        "https://raw.githubusercontent.com/yangchen-seu/RL-ridepooling/"
        "16bdaef446ae9c73c3aa560f8d6081d66bf884f9/input/node.csv"
    )
    for name, url in urls.items():
        m = re.match(r"^https://raw\.githubusercontent\.com/([^/]+/[^/]+)/([0-9a-f]{40})/\S+$", url)
        assert m, (name, url)
        assert m.group(2) in PINNED_COMMITS[m.group(1)], (name, url)
    # with a mirror: the stored names (already gzipped) under the mirror's URL
    mirrored = dict(source_urls("http://example.invalid/haikou/"))
    assert mirrored["network/link.csv.gz"] == "http://example.invalid/haikou/network/link.csv.gz"


def test_dry_run_prints_urls_and_downloads_nothing(capsys, monkeypatch, private_data_home):
    monkeypatch.setattr(fetch_mod, "_open_url", lambda url: pytest.fail(f"downloaded {url}"))
    code, out, _ = run_cli(capsys, "data", "fetch", "--dry-run", "--json")
    assert code == 0 and json.loads(out)["files"] == dict(source_urls())
    assert not private_data_home.exists()


def test_bad_registry_is_a_data_error():
    good = (
        '[[file]]\nname = "{name}"\nurl = "https://raw.githubusercontent.com/a/b/' + "0" * 40 + '/x.csv"\n'
        'transform = "none"\nsize = 1\nsha256 = "' + "a" * 64 + '"\n'
    )
    assert load_registry(good.format(name="x.csv"))[0].name == "x.csv"
    with pytest.raises(DataError, match="relative path"):
        load_registry(good.format(name="../escape.csv"))
    with pytest.raises(DataError, match="twice"):
        load_registry(good.format(name="x.csv") * 2)


def test_registry_checksums_match_the_shared_data_folder(data_dir):
    report = verify_data(data_dir)
    assert report.bad == {}
    if report.missing:
        pytest.skip(f"the data folder {data_dir} lacks registry files")


# --------------------------------------------------------------------------- fetch


def test_fetch_from_mirror_then_again_downloads_nothing(capsys, mirror, tmp_path):
    url, requests, served = mirror
    dest = tmp_path / "dest"
    code, out, _ = run_cli(capsys, "data", "fetch", "--dest", dest, "--mirror", url, "--json")
    assert code == 0
    assert json.loads(out)["downloaded"] == NAMES
    assert sorted(requests) == sorted(f"/{n}" for n in NAMES)
    for name in NAMES:  # a mirror's files are stored as served
        assert (dest / name).read_bytes() == (served / name).read_bytes()
    report = verify_data(dest)
    assert report.ok == NAMES and not report.bad and not report.missing and not report.extra
    assert part_files(dest) == []

    requests.clear()
    code, out, _ = run_cli(capsys, "data", "fetch", "--dest", dest, "--mirror", url)
    assert code == 0 and requests == []
    assert f"{len(NAMES)} file(s) already present and verified" in out


def test_fetch_without_mirror_gzips_the_upstream_content(monkeypatch, served_dir, tmp_path):
    """The pinned route, offline: the opener serves each upstream file (the stored file decompressed)."""
    monkeypatch.delenv("RPBENCH_DATA_MIRROR", raising=False)  # the test session's refusing mirror
    by_url = {e.url: e for e in REGISTRY}
    opened: list[str] = []

    def upstream(url):
        opened.append(url)
        stored = (served_dir / by_url[url].name).read_bytes()
        return io.BytesIO(gzip.decompress(stored) if by_url[url].transform == "gzip" else stored)

    monkeypatch.setattr(fetch_mod, "_open_url", upstream)
    # Small files only: gzip -9 of all 25 MB takes seconds and shows nothing more.
    few = [e for e in REGISTRY if e.size < 250_000]
    assert {e.transform for e in few} == {"gzip", "none"}
    report = fetch_mod.fetch(tmp_path / "dest", entries=few, progress=False)
    assert opened == [e.url for e in few] and report.downloaded == [e.name for e in few]
    assert verify_data(tmp_path / "dest", entries=few).ok == [e.name for e in few]
    head = (tmp_path / "dest" / "predecessor_trb2021_network" / "all_vertexes.csv.gz").read_bytes()[:10]
    assert head[:3] == b"\x1f\x8b\x08" and head[3] == 0 and head[4:8] == b"\0\0\0\0"  # `gzip -n`: no name, no time


@pytest.mark.parametrize(
    "name, damage",
    [
        ("network/node.csv", flip_byte),
        ("demand_0800_0900/orders/2017-05-03.csv.gz", change_content_byte),  # valid gzip, other content
        ("demand_0800_0900/orders/2017-05-03.csv.gz", flip_byte),  # broken gzip stream
    ],
)
def test_one_byte_change_on_the_server_is_a_checksum_error(capsys, mirror, tmp_path, name, damage):
    url, _, served = mirror
    damage(served / name)
    dest = tmp_path / "dest"
    code, out, err = run_cli(capsys, "data", "fetch", "--dest", dest, "--mirror", url, "--quiet")
    assert code == 2 and out == ""
    line = one_error_line(err)
    assert name in line and ("checksum mismatch" in line or "not a valid gzip file" in line)
    assert err.count("\n") == 1
    assert not (dest / name).exists() and part_files(dest) == []


def test_server_down_is_one_line_and_leaves_no_folder(capsys, tmp_path):
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    dest = tmp_path / "dest"
    code, out, err = run_cli(capsys, "data", "fetch", "--dest", dest, "--mirror", f"http://127.0.0.1:{port}")
    assert code == 2 and out == ""
    line = one_error_line(err)
    assert f"could not download {NAMES[0]} from http://127.0.0.1:{port}/{NAMES[0]}" in line
    assert not dest.exists()


def test_connection_cut_leaves_no_partial_file_and_a_rerun_resumes(monkeypatch, pristine, tmp_path):
    victim = "demand_0800_0900/orders/2017-05-02.csv.gz"
    real_open = fetch_mod._open_url

    class Cut(io.BytesIO):
        def read(self, n=-1):
            if self.tell() > 1000:
                raise ConnectionResetError("connection reset by peer")
            return super().read(min(n, 500) if n and n > 0 else 500)

    def flaky(url):
        return Cut((pristine / victim).read_bytes()) if url.endswith(victim) else real_open(url)

    monkeypatch.setattr(fetch_mod, "_open_url", flaky)
    dest = tmp_path / "dest"
    with pytest.raises(fetch_mod.DownloadError, match=f"could not download {re.escape(victim)}.*connection reset"):
        fetch_mod.fetch(dest, pristine, progress=False)
    assert not (dest / victim).exists() and part_files(dest) == []
    before = {p for p in dest.rglob("*") if p.is_file()}
    assert before and verify_data(dest).bad == {}

    monkeypatch.setattr(fetch_mod, "_open_url", real_open)
    report = fetch_mod.fetch(dest, pristine, progress=False)
    assert len(report.already_present) == len(before) and victim in report.downloaded
    assert verify_data(dest).ok == NAMES


def test_a_wrong_file_already_present_is_downloaded_again(pristine, fetched):
    change_content_byte(fetched / "network/links.csv.gz")
    report = fetch_mod.fetch(fetched, pristine, progress=False)
    assert report.replaced == report.downloaded == ["network/links.csv.gz"]
    assert verify_data(fetched).ok == NAMES


# --------------------------------------------------------------------------- verify


def test_verify_lists_another_day_and_reports_missing_files(capsys, fetched):
    orders = fetched / "demand_0800_0900" / "orders"
    shutil.copy(orders / "2017-05-01.csv.gz", orders / "2017-05-15.csv.gz")
    (fetched / "docs" / "haikou_didi_data_dictionary.pdf").unlink()
    code, out, err = run_cli(capsys, "data", "verify", "--data", fetched)
    assert code == 0 and err == ""
    assert f"verified: {len(NAMES) - 1} of {len(NAMES)}" in out
    assert "missing (1): docs/haikou_didi_data_dictionary.pdf" in out
    assert "demand_0800_0900/orders/2017-05-15.csv.gz: peak-hour orders of another day" in out


@pytest.mark.parametrize("name", ["network/node.csv", "predecessor_trb2021_network/all_edges.csv.gz"])
def test_verify_detects_a_one_byte_change(capsys, fetched, name):
    change_content_byte(fetched / name)
    code, out, err = run_cli(capsys, "data", "verify", "--data", fetched)
    assert code == 2
    assert f"BAD      {name}" in out
    assert err.count("\n") == 1 and name in one_error_line(err) and "fail verification" in err


# --------------------------------------------------------------------------- default data location


def test_default_data_location_picks_up_the_fetch_destination(
    capsys, monkeypatch, pristine, tmp_path, private_data_home
):
    # A fresh machine: no $RPBENCH_DATA, no ../shared beside the current folder or the checkout.
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("rpbench.files.paths.source_root", lambda: tmp_path / "checkout")
    monkeypatch.setattr("rpbench.commands.list.preset_names", list)  # no presets: skip importing solver libraries
    assert find_data_dir() is None

    code, _, _ = run_cli(capsys, "data", "fetch", "--mirror", pristine.as_uri(), "--quiet")
    assert code == 0
    expected = (private_data_home / "haikou").resolve()
    assert find_data_dir() == expected
    assert "rpbench data fetch" in locate_data_dir()[1]

    code, out, _ = run_cli(capsys, "list", "--json")
    info = json.loads(out)
    assert info["data_dir"] == str(expected) and "rpbench data fetch" in info["data_dir_source"]
    assert len(info["peak_dates"]) == 14
    code, out, _ = run_cli(capsys, "list")
    assert f"data folder: {expected} (from downloaded by `rpbench data fetch`" in out


def test_a_fresh_machine_fetches_from_a_local_mirror_and_runs_the_paper_scenario(
    capsys, monkeypatch, mirror, tmp_path, private_data_home
):
    """The README's path for a machine without ../shared: fetch over HTTP, then `rpbench run` finds the data
    by default and runs the paper's haikou-peak comparison (MB only, a small sample: the path, not the numbers)."""
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(
        "rpbench.files.paths.default_data_candidates", lambda: [tmp_path / "no-shared", (private_data_home / "haikou")]
    )
    url, _, _ = mirror
    code, _, _ = run_cli(capsys, "data", "fetch", "--mirror", url, "--quiet")
    assert code == 0
    out = tmp_path / "run"
    code, stdout, _ = run_cli(
        capsys, "run", "--strategies", "mb", "--sample", "0.05", "--out", str(out), "--no-progress"
    )
    assert code == 0 and "Haikou 2017-05-01 08:00-09:00" in stdout
    meta = json.loads((out / "meta.json").read_text())
    assert meta["scenario"]["name"] == "haikou-peak"
    code, stdout, _ = run_cli(capsys, "check", str(out))
    assert code == 0 and "mb: OK" in stdout


# --------------------------------------------------------------------------- Manhattan


def registry_rows(city: str) -> list[dict]:
    """The rows of a city's registry file as written (with the ``git_blob`` the entries do not keep)."""
    path = Path(fetch_mod.__file__).parent / REGISTRY_FILES[city]
    return tomllib.loads(path.read_text(encoding="utf-8"))["file"]


def content_of(path: Path) -> bytes:
    """A stored file's content: the upstream bytes (a ``.gz`` decompressed)."""
    data = path.read_bytes()
    return gzip.decompress(data) if path.suffix == ".gz" else data


@pytest.fixture
def manhattan_copy(manhattan_data_dir, tmp_path) -> Path:
    """A writable copy of the Manhattan data folder (the mirror side; tests damage it, never the folder)."""
    copy = tmp_path / "mirrors" / "manhattan"
    shutil.copytree(manhattan_data_dir, copy)
    for path in copy.rglob("*"):
        path.chmod(0o755 if path.is_dir() else 0o644)  # the shared folder is read-only
    return copy


@pytest.fixture
def fresh_manhattan(monkeypatch, tmp_path) -> None:
    """No Manhattan folder where rpbench looks: no ../shared beside the current folder nor the checkout."""
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setattr("rpbench.files.paths.source_root", lambda: tmp_path / "checkout")
    monkeypatch.setattr("rpbench.commands.list.preset_names", list)  # no presets: skip importing solver libraries


def test_every_city_with_a_registry_has_a_label_and_ships_it():
    assert set(REGISTRY_FILES) == set(CITY_LABELS)
    package_data = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert set(REGISTRY_FILES.values()) <= set(package_data["package-data"]["rpbench.data"])
    assert load_registry(city="haikou") == REGISTRY  # the default city


def test_the_manhattan_registry_pins_the_public_files_of_source_md():
    assert list(MANHATTAN_UPSTREAM) == MANHATTAN_NAMES
    assert not set(MANHATTAN_DERIVED) & set(MANHATTAN_NAMES)
    for entry, row in zip(MANHATTAN, registry_rows("manhattan"), strict=True):
        repo, path = MANHATTAN_UPSTREAM[entry.name]
        assert entry.url == f"https://raw.githubusercontent.com/{repo}/{MANHATTAN_COMMITS[repo]}/{path}"
        assert entry.transform == "gzip" and re.fullmatch(r"[0-9a-f]{40}", row["git_blob"]), row
    mirrored = dict(source_urls("http://example.invalid/m/", city="manhattan"))
    assert mirrored["network/Manhattan.graphml.gz"] == "http://example.invalid/m/network/Manhattan.graphml.gz"


@pytest.mark.manhattan
def test_the_manhattan_registry_agrees_with_the_shared_folder(capsys, manhattan_data_dir):
    """Each entry's content SHA-256, size and git blob id are those of the stored file decompressed."""
    for entry, row in zip(MANHATTAN, registry_rows("manhattan"), strict=True):
        content = content_of(manhattan_data_dir / entry.name)
        assert (hashlib.sha256(content).hexdigest(), len(content)) == (entry.sha256, entry.size), entry.name
        blob = hashlib.sha1(b"blob %d\0" % len(content) + content).hexdigest()
        assert blob == row["git_blob"], entry.name
    report = verify_data(manhattan_data_dir, city="manhattan")
    assert report.ok == MANHATTAN_NAMES and not report.bad and not report.missing
    assert sorted(report.extra) == MANHATTAN_DERIVED  # not in the registry: listed, not failed
    code, out, err = run_cli(capsys, "data", "verify", "--city", "manhattan", "--data", manhattan_data_dir)
    assert code == 0 and err == "" and f"verified: {len(MANHATTAN)} of {len(MANHATTAN)}" in out
    assert "extra    network/nodes.csv: not in the registry (not checked)" in out


@pytest.mark.manhattan
def test_a_manhattan_fetch_from_a_file_mirror_fills_a_fresh_data_home(
    capsys, fresh_manhattan, manhattan_copy, private_data_home
):
    assert find_data_dir(city="manhattan") is None
    mirror = manhattan_copy.as_uri()
    code, out, _ = run_cli(capsys, "data", "fetch", "--city", "manhattan", "--mirror", mirror, "--json")
    assert code == 0
    dest = (private_data_home / "manhattan").resolve()
    report = json.loads(out)
    assert (report["dest"], report["city"], report["source"]) == (str(dest), "manhattan", mirror)
    assert report["downloaded"] == MANHATTAN_NAMES
    assert report["content_bytes"] == sum(e.size for e in MANHATTAN)
    for name in MANHATTAN_NAMES:  # a mirror's files are stored as served
        assert (dest / name).read_bytes() == (manhattan_copy / name).read_bytes()
    verified = verify_data(dest, city="manhattan")
    assert verified.ok == MANHATTAN_NAMES and not verified.bad and not verified.missing and not verified.extra
    assert part_files(dest) == [] and not (private_data_home / "haikou").exists()

    # rpbench finds it there from now on; Haikou's folder is another matter.
    folder, origin = locate_data_dir(city="manhattan")
    assert folder == dest and origin.startswith("downloaded by `rpbench data fetch --city manhattan`")
    assert find_data_dir() is None
    code, out, err = run_cli(capsys, "data", "verify", "--city", "manhattan")
    assert code == 0 and err == "" and f"verified: {len(MANHATTAN)} of {len(MANHATTAN)}" in out
    code, out, _ = run_cli(capsys, "list", "--json")
    info = json.loads(out)
    assert info["data_folders"]["manhattan"]["data_dir"] == str(dest)
    assert info["data_folders"]["manhattan"]["data_fetch_pending"] is None
    assert info["data_dir"] is None and info["data_folders"]["haikou"]["data_dir"] is None

    code, out, _ = run_cli(capsys, "data", "fetch", "--city", "manhattan", "--mirror", mirror)
    assert code == 0 and f"{len(MANHATTAN)} file(s) already present and verified in {dest}" in out


@pytest.mark.manhattan
@pytest.mark.parametrize("damage", [change_content_byte, flip_byte], ids=["other content", "broken gzip"])
def test_a_one_byte_change_on_a_manhattan_mirror_stores_nothing(capsys, manhattan_copy, tmp_path, damage):
    name = "network_pnas2017/points.csv.gz"
    damage(manhattan_copy / name)
    dest = tmp_path / "dest"
    code, out, err = run_cli(
        capsys, "data", "fetch", "--city", "manhattan", "--dest", dest, "--mirror", manhattan_copy, "--quiet"
    )
    assert code == 2 and out == "" and err.count("\n") == 1
    line = one_error_line(err)
    assert name in line and ("checksum mismatch" in line or "not a valid gzip file" in line)
    assert not (dest / name).exists() and part_files(dest) == []


@pytest.mark.manhattan
def test_a_manhattan_fetch_without_mirror_gzips_the_pinned_upstream_content(monkeypatch, manhattan_data_dir, tmp_path):
    """The pinned route, offline: the opener serves each upstream file (the stored file decompressed)."""
    monkeypatch.delenv("RPBENCH_DATA_MIRROR", raising=False)  # the test session's refusing mirror
    by_url = {e.url: e for e in MANHATTAN}
    opened: list[str] = []

    def upstream(url):
        opened.append(url)
        return io.BytesIO(content_of(manhattan_data_dir / by_url[url].name))

    monkeypatch.setattr(fetch_mod, "_open_url", upstream)
    few = [e for e in MANHATTAN if e.size < 150_000]  # the two small PNAS files: gzip -9 of 10 MB shows no more
    assert [e.name for e in few] == ["network_pnas2017/points.csv.gz", "network_pnas2017/edges.csv.gz"]
    report = fetch_mod.fetch(tmp_path / "dest", entries=few, city="manhattan", progress=False)
    assert opened == [e.url for e in few] and report.downloaded == [e.name for e in few]
    assert verify_data(tmp_path / "dest", entries=few).ok == [e.name for e in few]


@pytest.mark.parametrize(
    "argv",
    [
        ["data", "fetch", "--city", "atlantis"],
        ["data", "fetch", "--city", "atlantis", "--dry-run", "--json"],
        ["data", "fetch", "--city", "../haikou", "--mirror", "http://127.0.0.1:9/"],
        ["data", "verify", "--city", "atlantis"],
        ["data", "verify", "--city", "Manhattan", "--data", "."],
    ],
)
def test_an_unknown_city_is_one_line_exit_2_and_creates_nothing(capsys, monkeypatch, tmp_path, private_data_home, argv):
    monkeypatch.setattr(fetch_mod, "_open_url", lambda url: pytest.fail(f"downloaded {url}"))
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, *argv)
    city = argv[argv.index("--city") + 1]
    assert code == 2 and out == ""
    assert err == (
        f"rpbench: error: no data registry for the city {city!r}: rpbench fetches the data of haikou, manhattan; "
        "pass --city with one of them\n"
    )
    assert list(tmp_path.iterdir()) == []  # not even the data home
    with pytest.raises(ParameterError, match="rpbench fetches the data of haikou, manhattan"):
        load_registry(city=city)


def test_city_in_the_mirror_stands_for_the_city_being_fetched(capsys, monkeypatch, tmp_path):
    assert mirror_base("https://host/data/{city}/", "manhattan") == "https://host/data/manhattan"
    assert mirror_base("https://host/data/{city}") == "https://host/data/haikou"  # the default city
    assert mirror_base("https://host/haikou") == "https://host/haikou"  # no {city}: as given
    (tmp_path / "mirrors" / "manhattan").mkdir(parents=True)
    assert mirror_base(str(tmp_path / "mirrors" / "{city}"), "manhattan") == (tmp_path / "mirrors/manhattan").as_uri()
    with pytest.raises(ParameterError, match=r"'.*/mirrors/\{city\}' \('.*/mirrors/haikou' for haikou\) is neither"):
        mirror_base(str(tmp_path / "mirrors" / "{city}"))

    # One value of $RPBENCH_DATA_MIRROR serves every city.
    monkeypatch.setenv("RPBENCH_DATA_MIRROR", "http://mirror.invalid/data/{city}")
    for city, names in (("haikou", NAMES), ("manhattan", MANHATTAN_NAMES)):
        code, out, _ = run_cli(capsys, "data", "fetch", "--city", city, "--dry-run", "--json")
        assert code == 0
        assert json.loads(out)["files"] == {n: f"http://mirror.invalid/data/{city}/{n}" for n in names}
    code, out, _ = run_cli(capsys, "data", "fetch", "--dry-run", "--json")  # Haikou without --city
    assert json.loads(out)["files"][NAMES[0]] == f"http://mirror.invalid/data/haikou/{NAMES[0]}"
    with pytest.raises(SystemExit):
        main(["data", "fetch", "--help"])
    assert "{city} in it stands for the city's name" in " ".join(capsys.readouterr().out.split())


def test_each_city_has_its_own_default_folders(monkeypatch, tmp_path, private_data_home):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setattr("rpbench.files.paths.source_root", lambda: tmp_path / "checkout")
    shared, home = (tmp_path / "shared" / "data").resolve(), private_data_home.resolve()
    # ../shared/data/<city> beside the current folder and beside the checkout (here the same), then the data home
    assert default_data_candidates("manhattan") == [shared / "manhattan", home / "manhattan"]
    assert default_data_candidates() == [shared / "haikou", home / "haikou"]
    assert (
        describe_candidate(shared / "manhattan", "manhattan") == "../shared/data/manhattan beside the current directory"
    )
    with pytest.raises(
        ParameterError, match="unknown city 'atlantis': rpbench knows the data folders of haikou, manhattan"
    ):
        default_data_candidates("atlantis")

    # $RPBENCH_DATA is Haikou's folder only; --data is the folder of the city the command is about.
    haikou = tmp_path / "haikou-elsewhere"
    haikou.mkdir()
    monkeypatch.setenv("RPBENCH_DATA", str(haikou))
    assert locate_data_dir() == (haikou.resolve(), "$RPBENCH_DATA")
    assert locate_data_dir(city="manhattan") == (None, "none found")
    assert locate_data_dir(haikou, "manhattan") == (haikou.resolve(), "--data")
    with pytest.raises(DataNotFoundError, match="point --data at the Manhattan data folder"):
        locate_data_dir(tmp_path / "nothing", "manhattan")
