"""What every ``report.html`` embeds: the plotting library's script (once, compressed), the page's own
script and style sheet.

Plotly's Python wheel ships one bundle, ``plotly.min.js`` (4.8 MB).  A page embeds it gzip-compressed and
base64-encoded (2.0 MB) and ``page.js`` inflates it synchronously, so that the figures are drawn before the
page's load event: the page stays one self-contained file without a network, at under half the size.  The
compressed text is deterministic (no time stamp in the gzip header), so the same folder gives the same page
byte for byte.
"""

from __future__ import annotations

import base64
import gzip
from functools import cache, lru_cache
from importlib import resources


@lru_cache(maxsize=1)
def plotly_bundle() -> str:
    """Plotly's script, gzip-compressed and base64-encoded (computed once per process)."""
    from plotly.offline import get_plotlyjs

    raw = get_plotlyjs().encode()
    return base64.b64encode(gzip.compress(raw, compresslevel=9, mtime=0)).decode("ascii")


def plotly_version() -> str:
    import plotly

    return str(plotly.__version__)


@cache
def text(name: str) -> str:
    """A file shipped beside this module (``page.js``, ``page.css``)."""
    return resources.files(__package__).joinpath(name).read_text(encoding="utf-8")
