"""report.html in a real browser: headless Chromium, network off, driven by Playwright.

The page must draw every figure without a console error, show the table of kpis.csv, put on the map as
many pooled pairs as the event log holds, fetch nothing, and still work when copied alone elsewhere.
Skips, saying why, where no Chromium or no Playwright is installed (``.ci/run`` installs both).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from rpbench import results
from rpbench.report.comparison import fmt
from tests.report.html.test_mapdata import direct_layers

playwright = pytest.importorskip(
    "playwright.sync_api", reason="Playwright is not installed (pip install -e '.[browser]')"
)

CHROMIUM_ARGS = [
    "--no-sandbox",  # CI runs as root
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
READY_TIMEOUT_MS = 60_000  # a generous cap on a loaded shared machine, not a performance claim


def chromium() -> str:
    for candidate in (os.environ.get("RPBENCH_CHROMIUM"), "chromium", "chromium-browser", "google-chrome"):
        if candidate and (path := shutil.which(candidate)):
            return path
    pytest.skip("no Chromium found (Debian: apt-get install chromium; or set RPBENCH_CHROMIUM)")


@pytest.fixture(scope="module")
def browser():
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
        yield b
        b.close()


def open_page(browser, path: Path, screenshot: Path):
    """The page loaded offline until it says ready (or error); returns (page, console errors, requests)."""
    context = browser.new_context(offline=True, viewport={"width": 1280, "height": 900})
    page = context.new_page()
    errors: list[str] = []
    requests: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url}"))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(path.as_uri())
    page.wait_for_function("document.documentElement.dataset.rpbench !== 'loading'", timeout=READY_TIMEOUT_MS)
    page.screenshot(path=str(screenshot), full_page=True)
    return page, errors, requests


def test_the_page_draws_offline_with_the_folders_numbers(browser, toy_run, tmp_path):
    page, errors, requests = open_page(browser, toy_run / "report.html", tmp_path / "page.png")
    assert page.evaluate("document.documentElement.dataset.rpbench") == "ready", page.inner_text("#rpbench-status")
    assert errors == []
    assert [u for u in requests if not u.startswith(("file:", "data:", "blob:"))] == []
    assert (tmp_path / "page.png").stat().st_size > 10_000
    # every figure slot holds a drawn plot
    drawn = page.evaluate(
        "[...document.querySelectorAll('.plot')].map(d => [d.id, d.classList.contains('js-plotly-plot')])"
    )
    assert drawn and all(ok for _, ok in drawn), drawn

    # the comparison table shows kpis.csv, formatted as the report prints it
    cells = page.evaluate(
        "[...document.querySelectorAll('#comparison-table td[data-run]')]"
        ".map(td => [td.dataset.run, td.dataset.kpi, td.dataset.value, td.textContent])"
    )
    tidy = results.read_csv(toy_run / "kpis.csv").set_index(["run", "kpi"])["value"]
    compared = 0
    for run, kpi, raw, shown in cells:
        if (run, kpi) not in tidy.index:
            continue  # the ratio rows are computed from two of these
        value = tidy[(run, kpi)]
        assert shown == fmt(kpi, value)
        if raw:
            assert float(raw) == pytest.approx(float(value), rel=1e-12, abs=1e-12)
        compared += 1
    assert compared >= 20

    # each run's pooled layer on the map holds the event log's pairs
    counts = page.evaluate(
        """() => {
          const select = document.getElementById('map-run'), out = {};
          for (const option of select.options) {
            select.value = option.value;
            select.dispatchEvent(new Event('input'));
            const gd = document.getElementById('map-plot');
            const firsts = gd.data.find(t => t.meta && t.meta.role === 'first_pickup');
            out[window.rpbenchMap.run] = firsts.x.length;
          }
          return out;
        }"""
    )
    expected = {}
    for run in ("np", "mb", "fl"):
        pairs, _, _ = direct_layers(results.read_csv(toy_run / "runs" / run / "events.csv.gz"))
        expected[run] = len(pairs)
    assert counts == expected and expected["fl"] > 0

    # the time slider narrows the map to a window
    narrowed = page.evaluate(
        """() => {
          const s = document.getElementById('map-window');
          s.value = '2'; s.dispatchEvent(new Event('input'));
          return window.rpbenchMap;
        }"""
    )
    assert narrowed["window"] != "the whole period"
    assert narrowed["layers"]["pooled"]["in_window"] <= expected[narrowed["run"]]


def test_the_page_renders_copied_alone(browser, toy_run, tmp_path):
    alone = tmp_path / "elsewhere" / "copied.html"
    alone.parent.mkdir()
    shutil.copyfile(toy_run / "report.html", alone)
    page, errors, _ = open_page(browser, alone, tmp_path / "alone.png")
    assert page.evaluate("document.documentElement.dataset.rpbench") == "ready" and errors == []
