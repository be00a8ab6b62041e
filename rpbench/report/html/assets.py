"""What every ``report.html`` embeds: the plotting library's script (once, compressed), the page's own
script and style sheet.

Plotly's Python wheel ships one bundle, ``plotly.min.js`` (4.8 MB).  A page embeds it gzip-compressed and
base64-encoded (2.0 MB) and ``page.js`` inflates it synchronously, so that the figures are drawn before the
page's load event: the page stays one self-contained file without a network, at under half the size.  The
compressed text is deterministic (no time stamp in the gzip header), so the same folder gives the same page
byte for byte.  Compressing it takes about half a second, so the compressed bytes are kept in the user cache
folder, named by a digest of the script and checked against it (inflated and compared) on every read.
"""

from __future__ import annotations

import base64
import gzip
import hashlib
import os
import zlib
from functools import cache, lru_cache
from importlib import resources

from rpbench.exceptions import CacheError
from rpbench.files.paths import cache_dir, temporary_file


@lru_cache(maxsize=1)
def plotly_bundle() -> str:
    """Plotly's script, gzip-compressed and base64-encoded (computed once per process, compressed once per
    script: :func:`compressed`)."""
    from plotly.offline import get_plotlyjs

    return base64.b64encode(compressed(get_plotlyjs().encode())).decode("ascii")


def compressed(raw: bytes) -> bytes:
    """``raw`` gzip-compressed at level 9 without a time stamp, from the cache when a kept copy inflates to
    ``raw``; else compressed and kept.  Without a usable cache folder it is compressed each time: a page
    must not fail for want of a half-second saving."""
    try:
        path = cache_dir() / f"plotly-{hashlib.sha256(raw).hexdigest()[:16]}.js.gz"
    except CacheError:
        return _gzip(raw)
    try:
        kept = path.read_bytes()
        if gzip.decompress(kept) == raw:
            return kept
    except (OSError, EOFError, zlib.error):  # absent, unreadable, or damaged: write it anew
        pass
    data = _gzip(raw)
    tmp = temporary_file(path)
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
    return data


def _gzip(raw: bytes) -> bytes:
    return gzip.compress(raw, compresslevel=9, mtime=0)


def plotly_version() -> str:
    import plotly

    return str(plotly.__version__)


@cache
def text(name: str) -> str:
    """A file shipped beside this module (``page.js``, ``page.css``)."""
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")
