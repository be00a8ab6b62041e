"""A page is one self-contained file: the library embedded once and inflatable, nothing from the network."""

from __future__ import annotations

import base64
import gzip
import re

import plotly.graph_objects as go

from rpbench.report.html import assets
from rpbench.report.html.page import Cell, Page


def built_page() -> str:
    page = Page("a </script> title")
    page.heading("Heading <b>", 1)
    page.paragraph("text with </script><script>alert(1)</script>")
    page.table(["a", "b"], [["x", Cell("1.5", {"value": "1.5"}, numeric=True)]], ident="t")
    page.figure("fig", go.Figure(go.Bar(x=["a"], y=[1.0], name="</script>")), "caption")
    return page.render()


def test_the_library_is_embedded_once_and_inflates_to_plotly():
    text = built_page()
    bundles = re.findall(r'<script type="application/gzip\+base64" id="rpbench-plotly">([^<]*)</script>', text)
    assert len(bundles) == 1
    from plotly.offline import get_plotlyjs

    assert gzip.decompress(base64.b64decode(bundles[0])).decode() == get_plotlyjs()


def test_nothing_is_fetched_and_text_is_escaped():
    text = built_page()
    tags = re.findall(r"<[a-z]+\b[^>]*>", text.split('id="rpbench-plotly">')[0])
    assert not [t for t in tags if re.search(r"\b(src|href)\s*=\s*[\"']?(https?:)?//", t)]
    assert "<link" not in text and "@import" not in text and "@font-face" not in text
    assert text.count("<script>alert(1)</script>") == 0  # user text never becomes markup
    data = text.split('id="rpbench-data">')[1].split("</script>")[0]
    assert "</" not in data  # a name holding "</script>" cannot close the data block


def test_a_page_is_deterministic():
    assert built_page() == built_page()
    assert assets.plotly_bundle() == assets.plotly_bundle()


def test_the_compressed_library_is_kept_and_checked(tmp_path, monkeypatch):
    monkeypatch.setenv("RPBENCH_CACHE", str(tmp_path))
    raw = b"var plotly = 1;" * 1000
    first = assets.compressed(raw)
    (kept,) = tmp_path.glob("plotly-*.js.gz")
    assert kept.read_bytes() == first and gzip.decompress(first) == raw
    assert assets.compressed(raw) == first
    kept.write_bytes(gzip.compress(b"another script", mtime=0))  # a copy that no longer inflates to the script
    assert assets.compressed(raw) == first and kept.read_bytes() == first
    kept.write_bytes(b"not gzip")
    assert assets.compressed(raw) == first and kept.read_bytes() == first


def test_the_library_compresses_without_a_cache_folder(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv("RPBENCH_CACHE", str(blocker))
    raw = b"var plotly = 2;" * 100
    assert gzip.decompress(assets.compressed(raw)) == raw
