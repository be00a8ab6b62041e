"""Download a city's data folder from its public sources, and verify a folder against them.

Each city with a pinned data folder has a registry, package data beside this
module (:data:`REGISTRY_FILES`: ``registry.toml`` for Haikou,
``registry-manhattan.toml`` for Manhattan), that pins every file: its name in
the data folder, its raw.githubusercontent.com URL at a fixed commit (from the
folder's SOURCE.md), the transform applied when storing it (``gzip``: the
folder keeps ``gzip -9n`` of the upstream bytes; ``none``) and the SHA-256 and
size of its *content*, i.e. the upstream bytes = the stored file decompressed.
The content is hashed, not the stored ``.gz``, because gzip output differs
between implementations and levels while the data does not.  Every function
here takes the city (default Haikou, :data:`rpbench.files.paths.DEFAULT_CITY`).

* :func:`fetch` without a mirror downloads each upstream file, hashes it while
  it streams and gzips it on the fly where the transform says so.  With a
  mirror (another copy of the data folder, ``http(s)://``, ``file://`` or a
  local folder; ``--mirror``, else ``$RPBENCH_DATA_MIRROR``; ``{city}`` in it
  stands for the city's name, so one mirror serves several cities) it
  downloads the stored names as they are (already gzipped) and only checks
  their content.
* :func:`verify_data` checks the registry files present in a folder, lists the
  missing ones and the files the registry does not know (another day's
  orders in the same format is normal: nothing in rpbench assumes the days).

Safety: a file streams into a temporary ``.NAME.XXXX.part`` in its own
destination folder and is renamed (``os.replace``, atomic on one file system)
to its final name only once its content hash matches, so an interrupted or
corrupt download never leaves a file under the final name.  Files already
present with the right content are skipped, which makes a second run free and
an interrupted one resumable (file by file; the largest file is 4.2 MB).

Sizes: a download is held to the registry.  Reading stops as soon as more
bytes arrive than the entry's content (``size``) can take: the content itself
from the pinned sources, the gzip of it from a mirror (:func:`gzip_bound`),
whose content is counted as it inflates, so an endless body or a gzip bomb is
refused after at most one chunk past the bound, never stored nor inflated
whole.  A full disk (``ENOSPC``, ``EDQUOT``) is a :class:`DiskFullError`
naming the folder, not a network error.

Connecting (and the TLS handshake) times out after :data:`CONNECT_TIMEOUT_S`,
so a host that does not answer fails in seconds; once connected, each read
may take :data:`READ_TIMEOUT_S` (a slow link is fine, a stalled one is not).

Why urllib and not pooch: pooch checks the hash of the bytes it downloads and
skips a file when the *stored* file's hash matches.  Neither is the hash pinned
here: from GitHub the stored file is the gzip of what was downloaded, from a
mirror the downloaded bytes are a gzip whose hash depends on the compressor.
Its processors (``Decompress``) also write their output under the final name
non-atomically.  Using pooch would mean ``known_hash=None`` plus our own skip
test, content check, compression and atomic rename: everything but the HTTP
GET, which urllib does in a few lines without pulling in ``requests``.
"""

from __future__ import annotations

import contextlib
import errno
import gzip
import hashlib
import http.client
import io
import os
import re
import sys
import tempfile
import tomllib
import urllib.error
import urllib.parse
import urllib.request
import zlib
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path, PurePosixPath
from typing import BinaryIO

from tqdm import tqdm

from rpbench.data.orders import PEAK_DIR
from rpbench.exceptions import ChecksumError, DataError, DownloadError, ParameterError, RpbenchError
from rpbench.files.paths import DATA_MIRROR_ENV, DEFAULT_CITY, fetch_command, fetched_data_dir
from rpbench.version import __version__

#: Each city's registry, a package resource beside this module: the cities `rpbench data fetch --city` knows.
REGISTRY_FILES = {"haikou": "registry.toml", "manhattan": "registry-manhattan.toml"}
#: What ``{city}`` in a mirror's URL or folder is replaced with: the name of the city being fetched.
MIRROR_CITY = "{city}"
TRANSFORMS = ("gzip", "none")
PINNED_PREFIX = "https://raw.githubusercontent.com/"
CHUNK = 1 << 16
CONNECT_TIMEOUT_S = 5.0
READ_TIMEOUT_S = 60.0
# Files of the data folder that are documentation of the folder, not data.
NOT_DATA = ("SOURCE.md",)

#: The errno values of a full device: no space left, or the user's disk quota used up.
DISK_FULL_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT})

_SHA256_RE = re.compile(r"^[0-9a-f]{64}$")
_PEAK_DAY_RE = re.compile(rf"^{re.escape(PEAK_DIR.as_posix())}/\d{{4}}-\d{{2}}-\d{{2}}\.csv\.gz$")


class DiskFullError(RpbenchError, OSError):
    """The device holding the data folder is full (or the disk quota is used up) while a file is stored."""


@dataclass(frozen=True)
class RegistryEntry:
    """One pinned file of the data folder."""

    name: str  # posix path inside the data folder, as stored (``.gz`` when transform is gzip)
    url: str  # the upstream file at a fixed commit
    transform: str  # "gzip" or "none"
    size: int  # bytes of the content (the upstream file)
    sha256: str  # SHA-256 of the content


@dataclass
class FetchReport:
    dest: Path
    source: str  # "registry" or the mirror's base URL
    city: str = DEFAULT_CITY
    downloaded: list[str] = field(default_factory=list)
    already_present: list[str] = field(default_factory=list)
    replaced: list[str] = field(default_factory=list)  # present with the wrong content, downloaded again
    content_bytes: int = 0

    def as_dict(self) -> dict:
        return {**asdict(self), "dest": str(self.dest)}


@dataclass
class VerifyReport:
    folder: Path
    city: str = DEFAULT_CITY
    ok: list[str] = field(default_factory=list)
    bad: dict[str, str] = field(default_factory=dict)  # name -> what is wrong
    missing: list[str] = field(default_factory=list)
    extra: dict[str, str] = field(default_factory=dict)  # name -> what it looks like

    def as_dict(self) -> dict:
        return {**asdict(self), "folder": str(self.folder)}


def registry_file(city: str) -> str:
    """The package resource holding ``city``'s registry; a city without one is a :class:`ParameterError`
    naming the cities that have one."""
    try:
        return REGISTRY_FILES[city]
    except (KeyError, TypeError):
        raise ParameterError(
            f"no data registry for the city {city!r}: rpbench fetches the data of {', '.join(REGISTRY_FILES)}; "
            "pass --city with one of them"
        ) from None


def load_registry(text: str | None = None, *, city: str = DEFAULT_CITY) -> list[RegistryEntry]:
    """The pinned files of ``city``'s data folder (its registry shipped with rpbench, :func:`registry_file`),
    or of ``text`` in that format."""
    if text is None:
        text = resources.files("rpbench.data").joinpath(registry_file(city)).read_text(encoding="utf-8")
    try:
        rows = tomllib.loads(text).get("file", [])
    except tomllib.TOMLDecodeError as exc:
        raise DataError(f"the data registry is not valid TOML: {exc}") from None
    entries: list[RegistryEntry] = []
    for row in rows:
        try:
            entry = RegistryEntry(
                name=str(row["name"]),
                url=str(row["url"]),
                transform=str(row["transform"]),
                size=int(row["size"]),
                sha256=str(row["sha256"]).lower(),
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise DataError(f"data registry entry {row.get('name', row)!r} lacks or mangles {exc}") from None
        _check_entry(entry)
        entries.append(entry)
    names = [e.name for e in entries]
    if len(set(names)) != len(names):
        raise DataError(
            "the data registry names a file twice: " + ", ".join(sorted({n for n in names if names.count(n) > 1}))
        )
    return entries


def _registry(city: str) -> list[RegistryEntry]:
    # Haikou's registry is asked for without an argument, as before rpbench knew other cities, so that a
    # replacement of load_registry that takes no city (tests serve made-up entries so) keeps serving it.
    return load_registry() if city == DEFAULT_CITY else load_registry(city=city)


def _check_entry(entry: RegistryEntry) -> None:
    path = PurePosixPath(entry.name)
    # The name becomes a path under --dest: never let it climb out of it.
    if path.is_absolute() or ".." in path.parts or not entry.name or "\\" in entry.name:
        raise DataError(f"data registry entry {entry.name!r}: the name must be a relative path inside the folder")
    if entry.transform not in TRANSFORMS:
        raise DataError(
            f"data registry entry {entry.name!r}: transform {entry.transform!r} is not one of " + ", ".join(TRANSFORMS)
        )
    if entry.transform == "gzip" and not entry.name.endswith(".gz"):
        raise DataError(f"data registry entry {entry.name!r}: a gzip transform needs a name ending in .gz")
    if not _SHA256_RE.match(entry.sha256):
        raise DataError(f"data registry entry {entry.name!r}: sha256 {entry.sha256!r} is not 64 hex digits")
    if not entry.url.startswith(PINNED_PREFIX):
        raise DataError(f"data registry entry {entry.name!r}: url {entry.url!r} is not a {PINNED_PREFIX} URL")


def mirror_base(mirror: str | os.PathLike | None, city: str = DEFAULT_CITY) -> str | None:
    """The mirror of ``city``'s data folder as a base URL: ``http(s)://`` and ``file://`` as given, a local
    folder as ``file://``.

    Without ``mirror``, ``$RPBENCH_DATA_MIRROR`` (unset or empty: ``None``, the
    pinned upstream URLs).  A mirror serves the folder of the city being
    fetched; ``{city}`` in it is replaced with the city's name, so that one
    value (``https://host/data/{city}``) serves every city.
    """
    option = "--mirror"
    if mirror is None:
        mirror = os.environ.get(DATA_MIRROR_ENV) or None
        option = f"${DATA_MIRROR_ENV}"
    if mirror is None:
        return None
    given = os.fspath(mirror)
    text = given.replace(MIRROR_CITY, city)
    scheme = urllib.parse.urlsplit(text).scheme.lower()
    if scheme in ("http", "https", "file"):
        return text.rstrip("/")
    folder = Path(text).expanduser()
    if len(scheme) <= 1 and folder.is_dir():  # no scheme, or a Windows drive letter
        return folder.resolve().as_uri()
    value = repr(text) if text == given else f"{given!r} ({text!r} for {city})"
    raise ParameterError(f"{option} {value} is neither an http(s):// or file:// URL nor an existing folder")


def source_url(entry: RegistryEntry, mirror: str | None = None) -> str:
    """Where ``entry`` is downloaded from: its pinned URL, or its stored name under the mirror's base URL."""
    if mirror is None:
        return entry.url
    return f"{mirror.rstrip('/')}/{urllib.parse.quote(entry.name)}"


def source_urls(
    mirror: str | os.PathLike | None = None,
    entries: list[RegistryEntry] | None = None,
    *,
    city: str = DEFAULT_CITY,
) -> list[tuple[str, str]]:
    """``(name, url)`` of every file of ``city``'s registry (or of ``entries``), as :func:`fetch` would
    download them."""
    entries = _registry(city) if entries is None else entries
    base = mirror_base(mirror, city)
    return [(e.name, source_url(e, base)) for e in entries]


def content_problem(path: Path, entry: RegistryEntry) -> str | None:
    """What is wrong with the stored file ``path`` (``None`` when its content matches the registry)."""
    digest, size = hashlib.sha256(), 0
    try:
        with gzip.open(path, "rb") if entry.transform == "gzip" else open(path, "rb") as fh:
            # Never read (or inflate) past the registered size: a bigger file is wrong whatever follows.
            while size <= entry.size and (chunk := fh.read(min(CHUNK, entry.size - size + 1))):
                digest.update(chunk)
                size += len(chunk)
    except (gzip.BadGzipFile, EOFError, zlib.error) as exc:
        return f"not a valid gzip file ({_one_line(exc)})"
    except OSError as exc:
        return f"unreadable ({_one_line(exc)})"
    if size > entry.size:
        return f"its content is longer than the registry's {entry.size:,} bytes"
    return _mismatch(entry, digest.hexdigest(), size)


def _mismatch(entry: RegistryEntry, sha256: str, size: int) -> str | None:
    if sha256 == entry.sha256:
        return None
    return (
        f"content SHA-256 {sha256} ({size:,} bytes) differs from the registry's {entry.sha256} ({entry.size:,} bytes)"
    )


def fetch(
    dest: str | os.PathLike | None = None,
    mirror: str | os.PathLike | None = None,
    *,
    entries: list[RegistryEntry] | None = None,
    city: str = DEFAULT_CITY,
    progress: bool = True,
) -> FetchReport:
    """Download every file of ``city``'s registry (or of ``entries``) missing from ``dest`` (default:
    :func:`rpbench.files.paths.fetched_data_dir` of ``city``), from ``mirror`` (see :func:`mirror_base`).

    Files already there with the right content are skipped; a file with the
    wrong content is downloaded again.  The first network error, checksum
    mismatch (or body longer than the registry allows) or full disk stops the
    run with a :class:`DownloadError`, :class:`ChecksumError` or
    :class:`DiskFullError` naming the file; the files stored before it are
    kept, so rerunning resumes.  A city without a registry is a
    :class:`ParameterError` before anything is created.
    """
    entries = _registry(city) if entries is None else entries
    folder = Path(dest).expanduser() if dest is not None else fetched_data_dir(city)
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"--dest {str(folder)!r} is a file, not a folder")
    base = mirror_base(mirror, city)
    report = FetchReport(dest=folder.resolve(), source=base or "registry", city=city)
    todo: list[RegistryEntry] = []
    for entry in entries:
        path = folder / entry.name
        if path.is_file():
            if content_problem(path, entry) is None:
                report.already_present.append(entry.name)
                continue
            report.replaced.append(entry.name)
        todo.append(entry)
    created: list[Path] = []
    try:
        with tqdm(
            total=sum(e.size for e in todo),
            unit="B",
            unit_scale=True,
            unit_divisor=1000,  # MB as the summaries and the first-run announcement print them
            desc="rpbench data fetch",
            file=sys.stderr,
            disable=not (progress and todo),
            dynamic_ncols=True,
            leave=False,
        ) as bar:
            for entry in todo:
                bar.set_postfix_str(entry.name)
                target = folder / entry.name
                try:
                    _make_dirs(target.parent, created)
                    download(entry, source_url(entry, base), target, served_as_stored=base is not None, bar=bar)
                except DownloadError as exc:
                    # The network's error names the file; what to run again depends on the city.
                    raise DownloadError(f"{exc}{rerun_hint(city)}") from None
                except OSError as exc:
                    if exc.errno not in DISK_FULL_ERRNOS:
                        raise
                    raise DiskFullError(
                        f"no space left on the device holding {str(folder)!r} while storing {entry.name} "
                        f"({_one_line(exc.strerror or exc)}); nothing half-written was kept{disk_full_hint(city)}"
                    ) from None
                report.downloaded.append(entry.name)
                report.content_bytes += entry.size
    except BaseException:
        # A fetch that stored nothing leaves no empty folder behind: an empty
        # fetched folder would otherwise be picked as the default data folder.
        for path in reversed(created):
            with contextlib.suppress(OSError):
                path.rmdir()
        raise
    return report


def _make_dirs(path: Path, created: list[Path]) -> None:
    missing = [p for p in (path, *path.parents) if not p.exists()]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        if exc.errno in DISK_FULL_ERRNOS:
            raise  # fetch names the full device
        raise ParameterError(
            f"cannot create the folder {str(path)!r} ({_one_line(exc)}); pass --dest DIR with a writable folder"
        ) from None
    created.extend(reversed(missing))  # outermost first, so reversed() removes innermost first


def download(entry: RegistryEntry, url: str, target: Path, *, served_as_stored: bool, bar: tqdm | None = None) -> None:
    """Download ``url`` into ``target``, checking the content against ``entry`` before the file gets its name.

    ``served_as_stored``: the URL serves the file as the data folder stores it
    (a mirror: gzipped where the transform is gzip); otherwise it serves the
    upstream content and the transform is applied here.  A full device raises
    its ``OSError`` (``errno`` in :data:`DISK_FULL_ERRNOS`) as it is, the
    partial file removed: :func:`fetch` names the folder.  A network error is a
    :class:`DownloadError` naming the file and the URL; :func:`fetch` adds the
    command to run again (:func:`rerun_hint`).
    """
    try:
        fd, tmp_name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".part")
    except OSError as exc:
        if exc.errno in DISK_FULL_ERRNOS:
            raise
        raise ParameterError(
            f"cannot write into {str(target.parent)!r} ({_one_line(exc)}); pass --dest DIR with a writable folder"
        ) from None
    tmp = Path(tmp_name)
    try:
        with os.fdopen(fd, "wb") as out:
            sha256, size = _stream(entry, url, out, served_as_stored=served_as_stored, bar=bar)
            out.flush()
            os.fsync(out.fileno())
        problem = _mismatch(entry, sha256, size)
        if problem:
            raise ChecksumError(
                f"checksum mismatch for {entry.name} downloaded from {url}: {problem}; the file was not stored"
            )
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _stream(
    entry: RegistryEntry, url: str, out: BinaryIO, *, served_as_stored: bool, bar: tqdm | None
) -> tuple[str, int]:
    """Copy ``url`` into ``out`` as the folder stores it; return the content's SHA-256 and size.

    Raises a :class:`ChecksumError` as soon as the body is longer than the
    registry allows (see the module's docstring), before storing the excess.
    """
    digest, size = hashlib.sha256(), 0
    gzipped = entry.transform == "gzip" and served_as_stored
    wire_limit = gzip_bound(entry.size) if gzipped else entry.size
    try:
        # The stack closes the gzip wrappers before ``out`` is closed (closing a
        # writer adds the gzip trailer to ``out`` and leaves ``out`` open).
        with _open_url(url) as response, contextlib.ExitStack() as stack:
            declared = _content_length(response)
            if declared is not None and declared > wire_limit:
                raise _too_long(entry, url, wire_limit, gzipped=gzipped, declared=declared)
            content: gzip.GzipFile | BinaryIO
            sink: gzip.GzipFile | BinaryIO | None
            if gzipped:
                # Store the served gzip bytes as they are, hash what they decompress to.
                tee = _Tee(
                    response, out, limit=wire_limit, refuse=lambda: _too_long(entry, url, wire_limit, gzipped=True)
                )
                content = stack.enter_context(gzip.GzipFile(fileobj=tee, mode="rb"))
                sink = None
            elif entry.transform == "gzip":
                # filename="" and mtime=0: no temp-file name nor time in the header, as `gzip -9n`.
                content = response
                sink = stack.enter_context(gzip.GzipFile(filename="", mode="wb", fileobj=out, compresslevel=9, mtime=0))
            else:
                content, sink = response, out
            # One byte past the registered size is enough to refuse: never ask for more.
            while chunk := content.read(min(CHUNK, entry.size - size + 1)):
                size += len(chunk)
                if size > entry.size:
                    raise _too_long(entry, url, entry.size, gzipped=gzipped, inflated=gzipped)
                digest.update(chunk)
                if sink is not None:
                    sink.write(chunk)
                if bar is not None:
                    bar.update(len(chunk))
    except (gzip.BadGzipFile, EOFError, zlib.error) as exc:
        # Before OSError: BadGzipFile is one.
        raise ChecksumError(
            f"{entry.name} downloaded from {url} is not a valid gzip file ({_one_line(exc)}); the file was not stored"
        ) from None
    except urllib.error.HTTPError as exc:
        raise DownloadError(
            f"could not download {entry.name} from {url}: HTTP {exc.code} {_one_line(exc.reason)}"
        ) from None
    except urllib.error.URLError as exc:
        raise DownloadError(f"could not download {entry.name} from {url}: {_one_line(exc.reason)}") from None
    except (http.client.HTTPException, OSError) as exc:
        if isinstance(exc, OSError) and exc.errno in DISK_FULL_ERRNOS:
            raise  # writing failed, not the network: fetch names the full device
        raise DownloadError(
            f"could not download {entry.name} from {url}: {_one_line(exc) or type(exc).__name__}"
        ) from None
    return digest.hexdigest(), size


def rerun_hint(city: str = DEFAULT_CITY) -> str:
    """The end of a download error's message: what to check, and the command that resumes the fetch."""
    return (
        f"; check the network (or the mirror: --mirror, ${DATA_MIRROR_ENV}) and run `{fetch_command(city)}` again "
        "(stored files are kept)"
    )


def disk_full_hint(city: str = DEFAULT_CITY) -> str:
    """The end of a full disk's message: where to make room, and the command that resumes the fetch."""
    return f"; free space there (or pass --dest DIR on another device) and run `{fetch_command(city)}` again"


def gzip_bound(size: int) -> int:
    """The most bytes a gzip of ``size`` content bytes takes, generously.

    Deflate's worst case adds 5 bytes per 16 KiB stored block (zlib's
    ``deflateBound``); 1/256 of the size plus 64 KiB also leaves room for a
    header with a file name, or a few gzip members.
    """
    return size + size // 256 + (64 << 10)


def _content_length(response) -> int | None:
    headers = getattr(response, "headers", None)
    value = headers.get("Content-Length") if headers is not None else None
    try:
        return int(value) if value is not None else None
    except ValueError:
        return None


def _too_long(
    entry: RegistryEntry, url: str, limit: int, *, gzipped: bool, inflated: bool = False, declared: int | None = None
) -> ChecksumError:
    """The refusal of a body longer than ``limit``, the most the registry allows (``declared``: its Content-Length)."""
    verb = f"declares {declared:,} bytes, more than" if declared is not None else "sent more than"
    if inflated:
        what = f"inflates to more than the registered {limit:,} bytes"
    elif gzipped:
        what = f"{verb} the {limit:,} bytes a gzip of the registered {entry.size:,} bytes can take"
    else:
        what = f"{verb} the registered {limit:,} bytes"
    return ChecksumError(f"{entry.name} from {url} {what}; refused (the file was not stored)")


def _open_url(url: str):
    """Open ``url`` for reading (a seam for tests: they replace it to serve bytes without a network)."""
    request = urllib.request.Request(url, headers={"User-Agent": f"rpbench/{__version__}"})
    # The opener's own HTTP(S) handlers replace urllib's defaults; proxies and file:// work as with urlopen.
    opener = urllib.request.build_opener(_HTTPHandler, _HTTPSHandler)
    return opener.open(request, timeout=CONNECT_TIMEOUT_S)


class _HTTPConnection(http.client.HTTPConnection):
    """Connects within the timeout it is given (:data:`CONNECT_TIMEOUT_S`), then reads with :data:`READ_TIMEOUT_S`."""

    def connect(self) -> None:
        super().connect()
        self.sock.settimeout(READ_TIMEOUT_S)


class _HTTPSConnection(http.client.HTTPSConnection):
    """:class:`_HTTPConnection` for HTTPS: the TLS handshake is part of connecting."""

    def connect(self) -> None:
        super().connect()
        self.sock.settimeout(READ_TIMEOUT_S)


class _HTTPHandler(urllib.request.HTTPHandler):
    def http_open(self, req: urllib.request.Request) -> http.client.HTTPResponse:
        return self.do_open(_HTTPConnection, req)


class _HTTPSHandler(urllib.request.HTTPSHandler):
    def https_open(self, req: urllib.request.Request) -> http.client.HTTPResponse:
        # No context: http.client builds its default one (certificates and host name checked), as urlopen does.
        return self.do_open(_HTTPSConnection, req)


class _Tee(io.RawIOBase):
    """A readable stream that copies every byte read from ``source`` into ``copy``, at most ``limit`` of them.

    Past ``limit`` it raises ``refuse()`` instead of reading further or copying the excess.
    """

    def __init__(self, source: BinaryIO, copy: BinaryIO, *, limit: int, refuse: Callable[[], Exception]) -> None:
        self._source, self._copy = source, copy
        self._limit, self._refuse, self._seen = limit, refuse, 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        data = self._source.read(min(len(buffer), self._limit - self._seen + 1))
        self._seen += len(data)
        if self._seen > self._limit:
            raise self._refuse()
        buffer[: len(data)] = data
        if data:
            self._copy.write(data)
        return len(data)


def _one_line(value: object) -> str:
    return " ".join(str(value).split())


def verify_data(
    folder: str | os.PathLike, *, entries: list[RegistryEntry] | None = None, city: str = DEFAULT_CITY
) -> VerifyReport:
    """Check every file of ``city``'s registry (or of ``entries``) present in ``folder``, a data folder of
    ``city``; list missing and unregistered files."""
    entries = _registry(city) if entries is None else entries
    root = Path(folder).expanduser().resolve()
    report = VerifyReport(folder=root, city=city)
    for entry in entries:
        path = root / entry.name
        if not path.is_file():
            report.missing.append(entry.name)
        elif (problem := content_problem(path, entry)) is not None:
            report.bad[entry.name] = problem
        else:
            report.ok.append(entry.name)
    known = {e.name for e in entries} | set(NOT_DATA)
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        name = path.relative_to(root).as_posix()
        if name not in known:
            report.extra[name] = _extra_kind(name)
    return report


def _extra_kind(name: str) -> str:
    if _PEAK_DAY_RE.match(name):
        return "peak-hour orders of another day (same format; not pinned, not checked)"
    base = PurePosixPath(name).name
    if base.startswith(".") and base.endswith(".part"):
        return "left over by an interrupted download (safe to delete)"
    return "not in the registry (not checked)"


def check_verified(report: VerifyReport) -> None:
    """Raise one :class:`ChecksumError` naming every bad file of ``report``."""
    if not report.bad:
        return
    listed = "; ".join(f"{name}: {problem}" for name, problem in report.bad.items())
    raise ChecksumError(
        f"{len(report.bad)} file(s) in {str(report.folder)!r} fail verification: {listed}; "
        f"run `{fetch_command(report.city)} --dest {report.folder}` to download them again"
    )
