"""Downloads held to the registry: an endless or too long body, a gzip bomb and a full disk, each one line and
exit status 2 naming the cause, with nothing left behind.

A local HTTP server serves each body; the registry is replaced by small made-up entries (their content is
made here, its SHA-256 computed), so nothing needs the real data folder nor the network.
"""

from __future__ import annotations

import errno
import gzip
import hashlib
import os
import random
import threading
import zlib
from collections.abc import Callable, Iterator
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from rpbench.cli import main
from rpbench.data import _table, first_run
from rpbench.data import fetch as fetch_mod
from rpbench.data.fetch import RegistryEntry

from .test_inputs_helpers import cli_error, cli_ok

#: Made-up content: random digits, so that its gzip is not much smaller than it (a full disk strikes mid-file).
CONTENT = "".join(random.Random(0).choices("0123456789,\n", k=20_000)).encode()
PLAIN = RegistryEntry(
    name="network/plain.csv",
    url="https://raw.githubusercontent.com/a/b/" + "0" * 40 + "/plain.csv",
    transform="none",
    size=len(CONTENT),
    sha256=hashlib.sha256(CONTENT).hexdigest(),
)
GZ = RegistryEntry(
    name="network/packed.csv.gz",
    url="https://raw.githubusercontent.com/a/b/" + "0" * 40 + "/packed.csv",
    transform="gzip",
    size=len(CONTENT),
    sha256=hashlib.sha256(CONTENT).hexdigest(),
)
#: As large as the registry's files (its bomb, a few hundred KB, is within the gzip bound: only inflating tells).
BIG_GZ = RegistryEntry(
    name="network/big.csv.gz",
    url="https://raw.githubusercontent.com/a/b/" + "0" * 40 + "/big.csv",
    transform="gzip",
    size=1_000_000,
    sha256="0" * 64,
)
#: What the endless bodies send at most (the server must stop by itself): far past every bound here.
ENDLESS_CAP = 64 << 20
BOMB_INFLATED = 200 << 20


def gzip_bomb(inflated: int) -> bytes:
    """A gzip of ``inflated`` zero bytes, built in 1 MiB steps (200 MiB give about 200 KB)."""
    packer = zlib.compressobj(9, zlib.DEFLATED, 31)  # wbits 31: the gzip wrapper
    zeros = bytes(1 << 20)
    parts = [packer.compress(zeros) for _ in range(inflated >> 20)]
    return b"".join([*parts, packer.flush()])


@pytest.fixture(scope="module")
def bomb() -> bytes:
    return gzip_bomb(BOMB_INFLATED)


def repeat(chunk: bytes) -> Callable[[], Iterator[bytes]]:
    """An endless body (up to :data:`ENDLESS_CAP`): ``chunk`` again and again."""

    def body() -> Iterator[bytes]:
        for _ in range(ENDLESS_CAP // len(chunk)):
            yield chunk

    return body


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    block_on_close = False

    def handle_error(self, request, client_address) -> None:
        pass  # the client hangs up on a refused body: not news


@pytest.fixture
def server():
    """``(base URL, routes)``: ``routes[path] = (body, content_length)``, ``body`` bytes or a chunk generator."""
    routes: dict[str, tuple[bytes | Callable[[], Iterator[bytes]], int | None]] = {}

    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.0"  # a body without Content-Length ends when the connection closes

        def log_message(self, *args) -> None:
            pass

        def do_GET(self) -> None:
            if self.path not in routes:
                self.send_error(404)
                return
            body, length = routes[self.path]
            self.send_response(200)
            if length is not None:
                self.send_header("Content-Length", str(length))
            self.end_headers()
            for chunk in [body] if isinstance(body, bytes) else body():
                self.wfile.write(chunk)

    httpd = _Server(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}", routes
    httpd.shutdown()
    httpd.server_close()


@pytest.fixture(autouse=True)
def private_data_home(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("RPBENCH_DATA_HOME", str(tmp_path / "data-home"))


def registry(monkeypatch, *entries: RegistryEntry) -> None:
    for module in (fetch_mod, first_run):
        monkeypatch.setattr(module, "load_registry", lambda text=None: list(entries))


def fetch_fails(capsys, dest: Path, mirror: str) -> str:
    """``rpbench data fetch`` into ``dest``: one line, exit 2, and nothing left behind (not even ``dest``)."""
    line = cli_error(capsys, "data", "fetch", "--dest", dest, "--mirror", mirror, "--quiet")
    assert not dest.exists(), sorted(dest.rglob("*"))
    return line


# --------------------------------------------------------------------------- bodies longer than registered


@pytest.mark.parametrize("length", [None, 1 << 40], ids=["no Content-Length", "a huge Content-Length"])
def test_an_endless_body_is_refused_at_the_registered_size(capsys, monkeypatch, tmp_path, server, length):
    url, routes = server
    registry(monkeypatch, PLAIN)
    routes[f"/{PLAIN.name}"] = (repeat(CONTENT[:4096]), length)
    line = fetch_fails(capsys, tmp_path / "dest", url)
    verb = "sent more than" if length is None else f"declares {length:,} bytes, more than"
    assert line == (
        f"{PLAIN.name} from {url}/{PLAIN.name} {verb} the registered {PLAIN.size:,} bytes; refused "
        "(the file was not stored)"
    )


@pytest.mark.parametrize("declared", [False, True], ids=["read past the size", "Content-Length says so"])
def test_a_body_one_byte_longer_than_registered_is_refused(capsys, monkeypatch, tmp_path, server, declared):
    url, routes = server
    registry(monkeypatch, PLAIN)
    body = CONTENT + b"\n"
    routes[f"/{PLAIN.name}"] = (body, len(body) if declared else None)
    line = fetch_fails(capsys, tmp_path / "dest", url)
    assert f"more than the registered {PLAIN.size:,} bytes; refused" in line and "check the network" not in line


def test_the_exact_body_is_stored(capsys, monkeypatch, tmp_path, server):
    """The bounds refuse nothing the registry allows: the same server and entries, the right bodies."""
    url, routes = server
    registry(monkeypatch, PLAIN, GZ)
    routes[f"/{PLAIN.name}"] = (CONTENT, None)
    routes[f"/{GZ.name}"] = (gzip.compress(CONTENT), None)
    cli_ok(capsys, "data", "fetch", "--dest", tmp_path / "dest", "--mirror", url, "--quiet")
    assert (tmp_path / "dest" / PLAIN.name).read_bytes() == CONTENT
    assert gzip.decompress((tmp_path / "dest" / GZ.name).read_bytes()) == CONTENT


def test_endless_empty_gzip_members_are_refused_at_the_gzip_bound(capsys, monkeypatch, tmp_path, server):
    """Empty gzip members inflate to nothing: the bytes on the wire are bounded too."""
    url, routes = server
    registry(monkeypatch, GZ)
    routes[f"/{GZ.name}"] = (repeat(gzip.compress(b"") * 200), None)
    line = fetch_fails(capsys, tmp_path / "dest", url)
    bound = fetch_mod.gzip_bound(GZ.size)
    assert line == (
        f"{GZ.name} from {url}/{GZ.name} sent more than the {bound:,} bytes a gzip of the registered "
        f"{GZ.size:,} bytes can take; refused (the file was not stored)"
    )


# --------------------------------------------------------------------------- gzip bombs


def test_a_gzip_bomb_from_a_mirror_is_refused_once_it_inflates_past_the_registered_size(
    capsys, monkeypatch, tmp_path, server, bomb
):
    url, routes = server
    registry(monkeypatch, BIG_GZ)
    routes[f"/{BIG_GZ.name}"] = (bomb, len(bomb))
    assert len(bomb) < fetch_mod.gzip_bound(BIG_GZ.size)
    inflated: list[int] = []
    real_read = gzip.GzipFile.read

    def counting_read(self, size=-1):
        data = real_read(self, size)
        inflated.append(len(data))
        return data

    monkeypatch.setattr(gzip.GzipFile, "read", counting_read)
    line = fetch_fails(capsys, tmp_path / "dest", url)
    assert line == (
        f"{BIG_GZ.name} from {url}/{BIG_GZ.name} inflates to more than the registered {BIG_GZ.size:,} bytes; "
        "refused (the file was not stored)"
    )
    assert BIG_GZ.size < sum(inflated) <= BIG_GZ.size + 1  # one byte past the size, not 200 MiB


def test_a_gzip_bomb_in_the_data_folder_is_refused_by_verify_and_replaced_by_fetch(
    capsys, monkeypatch, tmp_path, server, bomb
):
    url, routes = server
    registry(monkeypatch, GZ)
    folder = tmp_path / "data"
    (folder / GZ.name).parent.mkdir(parents=True)
    (folder / GZ.name).write_bytes(bomb)
    line = cli_error(capsys, "data", "verify", "--data", folder)
    assert f"{GZ.name}: its content is longer than the registry's {GZ.size:,} bytes" in line
    routes[f"/{GZ.name}"] = (gzip.compress(CONTENT), None)
    out, _ = cli_ok(capsys, "data", "fetch", "--dest", folder, "--mirror", url, "--quiet")
    assert "replaced (their content was wrong): network/packed.csv.gz" in out
    assert gzip.decompress((folder / GZ.name).read_bytes()) == CONTENT


def test_a_gzip_bomb_read_as_data_is_refused_before_it_is_inflated_whole(
    capsys, monkeypatch, tmp_path, fake_data, bomb
):
    """Loading a data folder: a .gz that inflates past its bound is one line (the floor lowered to keep it quick)."""
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(_table, "INFLATE_FLOOR", 1 << 20)
    links = fake_data / "network" / "link.csv.gz"
    links.write_bytes(bomb)
    limit = max(1 << 20, _table.INFLATE_RATIO * len(bomb))
    assert limit < BOMB_INFLATED
    out = tmp_path / "results"
    line = cli_error(
        capsys, "run", "--scenario", "haikou-peak", "--data", fake_data, "--strategies", "np", "--no-progress",
        "--out", out,
    )  # fmt: skip
    assert line.startswith(f"network link file {str(links)!r} inflates to more than {limit:,} bytes")
    assert "refused as a gzip bomb" in line and not out.exists()


# --------------------------------------------------------------------------- a full disk


class _FullDisk:
    """A file opened for writing on a device that fills up after ``budget`` bytes (then raises ``code``)."""

    def __init__(self, real, state: dict[str, int], budget: int, code: int) -> None:
        self._real, self._state, self._budget, self._code = real, state, budget, code

    def write(self, data) -> int:
        self._state["written"] += len(data)
        if self._state["written"] > self._budget:
            raise OSError(self._code, os.strerror(self._code))
        return self._real.write(data)

    def __getattr__(self, name):
        return getattr(self._real, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self._real.close()


def fill_disk(monkeypatch, budget: int = 1000, code: int = errno.ENOSPC) -> None:
    real_fdopen = os.fdopen
    state = {"written": 0}

    def fdopen(fd, mode="r", *args, **kwargs):
        opened = real_fdopen(fd, mode, *args, **kwargs)
        return _FullDisk(opened, state, budget, code) if "w" in mode else opened

    monkeypatch.setattr(os, "fdopen", fdopen)


@pytest.mark.parametrize(
    "entry, code",
    [(PLAIN, errno.ENOSPC), (GZ, errno.ENOSPC), (GZ, errno.EDQUOT)],
    ids=["plain file", "gzip from a mirror", "disk quota"],
)
def test_a_full_disk_is_named_as_such_not_as_the_network(capsys, monkeypatch, tmp_path, server, entry, code):
    url, routes = server
    registry(monkeypatch, entry)
    routes[f"/{entry.name}"] = (CONTENT if entry.transform == "none" else gzip.compress(CONTENT), None)
    fill_disk(monkeypatch, code=code)
    dest = tmp_path / "dest"
    line = fetch_fails(capsys, dest, url)
    assert line.startswith(f"no space left on the device holding {str(dest)!r} while storing {entry.name} ")
    assert os.strerror(code) in line and "nothing half-written was kept" in line
    assert "check the network" not in line and "could not download" not in line


def test_a_full_disk_while_gzipping_the_upstream_file(capsys, monkeypatch, tmp_path, server):
    """The pinned route (no mirror): the upstream content is gzipped here, the disk fills on the gzip's writes."""
    url, routes = server
    registry(monkeypatch, GZ)
    routes["/packed.csv"] = (CONTENT, None)
    monkeypatch.delenv("RPBENCH_DATA_MIRROR", raising=False)
    real_open = fetch_mod._open_url
    monkeypatch.setattr(fetch_mod, "_open_url", lambda pinned: real_open(f"{url}/{pinned.rsplit('/', 1)[1]}"))
    fill_disk(monkeypatch)
    dest = tmp_path / "dest"
    line = cli_error(capsys, "data", "fetch", "--dest", dest, "--quiet")
    assert line.startswith(f"no space left on the device holding {str(dest)!r} while storing {GZ.name} ")
    assert not dest.exists()


def test_a_full_disk_keeps_the_files_stored_before_it(capsys, monkeypatch, tmp_path, server):
    url, routes = server
    registry(monkeypatch, PLAIN, GZ)
    routes[f"/{PLAIN.name}"] = (CONTENT, None)
    routes[f"/{GZ.name}"] = (gzip.compress(CONTENT), None)
    fill_disk(monkeypatch, budget=len(CONTENT) + 1000)  # the first file fits, the second does not
    dest = tmp_path / "dest"
    line = cli_error(capsys, "data", "fetch", "--dest", dest, "--mirror", url, "--quiet")
    assert line.startswith(f"no space left on the device holding {str(dest)!r} while storing {GZ.name} ")
    assert sorted(p.relative_to(dest).as_posix() for p in dest.rglob("*")) == ["network", PLAIN.name]
    assert (dest / PLAIN.name).read_bytes() == CONTENT


def test_the_first_run_fetch_names_a_full_disk(capsys, monkeypatch, tmp_path, server):
    """The automatic fetch of a command that needs the data says the disk is full, not that the network is down."""
    url, routes = server
    registry(monkeypatch, PLAIN)
    routes[f"/{PLAIN.name}"] = (CONTENT, None)
    monkeypatch.delenv("RPBENCH_DATA", raising=False)
    monkeypatch.setenv("RPBENCH_DATA_MIRROR", url)
    home = tmp_path / "data-home"
    monkeypatch.setattr("rpbench.files.paths.default_data_candidates", lambda: [home / "haikou"])
    fill_disk(monkeypatch)
    code = main(["scenario", "haikou-peak", "--json"])
    out, err = capsys.readouterr()
    announce, line = err.splitlines()  # what it fetches, then the one error line
    assert code == 2 and out == "" and announce.startswith("rpbench: no Haikou data folder found: fetching it once")
    assert f"fetching it failed: no space left on the device holding {str(home / 'haikou')!r}" in line
    assert "check the network" not in line and not (home / "haikou").exists()
