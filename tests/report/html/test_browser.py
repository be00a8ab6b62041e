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

    # each run's pooled layer on the map holds the event log's pairs over the whole period
    counts = page.evaluate(
        """() => {
          const select = document.getElementById('map-run'), out = {};
          document.getElementById('map-window').value = '0';  // the whole period (it opens on a window)
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


# ---- a laptop's width ------------------------------------------------------------------------------------

#: Every Plotly text box a tick label must keep clear of: annotations (subplot titles among them), axis
#: titles, the figure's title and the legend; and the texts written on the plot (values over bars).
FIGURE_TEXTS = """() => {
  const box = (e) => { const r = e.getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom]; };
  const visible = (e) => { const r = e.getBoundingClientRect(); return r.width > 0 && r.height > 0; };
  return [...document.querySelectorAll('.js-plotly-plot')].map((gd) => ({
    id: gd.id,
    ticks: [...gd.querySelectorAll('g')].filter((g) => /^[xy]\\d*tick$/.test(g.getAttribute('class') || ''))
      .flatMap((g) => [...g.querySelectorAll('text')]).filter(visible).map((e) => [e.textContent, box(e)]),
    titles: [...gd.querySelectorAll('g.annotation, g.gtitle, g[class^="g-x"], g[class^="g-y"], g.legend g.traces')]
      .filter(visible).map((e) => [e.textContent, box(e)]),
    values: [...gd.querySelectorAll('text.bartext, g.textpoint text')].filter(visible)
      .map((e) => [e.textContent, parseFloat(getComputedStyle(e).fontSize)]),
  }));
}"""
#: No page-level sideways scrolling: the page is as wide as the window.
NO_OVERFLOW = "document.scrollingElement.scrollWidth <= window.innerWidth"


def overlapping(a: list[float], b: list[float]) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def label_clashes(page) -> list[tuple[str, str, str]]:
    """(figure, tick label, title) for every tick label whose box meets a title's, annotation's or legend's."""
    found = page.evaluate(FIGURE_TEXTS)
    assert found and all(fig["ticks"] and fig["titles"] for fig in found), found  # the selectors find them
    return [
        (fig["id"], tick, title)
        for fig in found
        for tick, a in fig["ticks"]
        for title, b in fig["titles"]
        if overlapping(a, b)
    ]


def small_values(page) -> list[tuple[str, str, float]]:
    """The values written on the plots in a font smaller than 9 px."""
    return [(fig["id"], text, size) for fig in page.evaluate(FIGURE_TEXTS) for text, size in fig["values"] if size < 9]


def test_a_run_page_reads_at_a_laptop_width(browser, toy_bracket, tmp_path):
    page, errors, _ = open_page(browser, toy_bracket / "report.html", tmp_path / "run.png")
    assert page.evaluate("document.documentElement.dataset.rpbench") == "ready" and errors == []
    assert page.evaluate(NO_OVERFLOW), page.evaluate("document.scrollingElement.scrollWidth")
    # the bracket's columns (Hindsight, the bound, Oracle-1) are in view beside the strategies'
    right = page.evaluate("innerWidth")
    heads = page.evaluate(
        "[...document.querySelectorAll('#comparison-table thead th')]"
        ".map(th => [th.textContent, th.getBoundingClientRect().right])"
    )
    assert len(heads) == 6 and all(edge <= right for _, edge in heads), heads
    assert label_clashes(page) == []
    assert small_values(page) == []
    # the ratio panel's title names what it draws: a diamond at saving / LB for every simulated run
    gd = "document.getElementById('fig-kpis')"
    assert page.evaluate(f"[...{gd}.querySelectorAll('g.annotation')].some(a => a.textContent.includes('◆'))")
    diamonds = page.evaluate(f"{gd}.data.filter(t => t.marker && t.marker.symbol === 'diamond').length")
    assert diamonds == 3  # MB, FL, Hindsight; the offline runs have no competitive ratio


def test_the_figures_are_drawn_by_the_load_event(browser, toy_run):
    """A headless screenshot (taken at the load event, without a virtual time budget) shows the figures."""
    context = browser.new_context(offline=True, viewport={"width": 1280, "height": 900})
    page = context.new_page()
    page.goto((toy_run / "report.html").as_uri(), wait_until="load")
    drawn = page.evaluate("[...document.querySelectorAll('.plot')].map(d => d.classList.contains('js-plotly-plot'))")
    assert drawn and all(drawn)
    assert page.evaluate("document.getElementById('rpbench-status')") is None  # no "loading" line left
    context.close()


def test_the_map_opens_on_the_best_online_strategy_in_a_short_window(browser, toy_bracket, tmp_path):
    page, _, _ = open_page(browser, toy_bracket / "report.html", tmp_path / "map.png")
    state = page.evaluate("window.rpbenchMap")
    saving = results.read_csv(toy_bracket / "kpis.csv").query("kpi == 'total_saving_km'").set_index("run")["value"]
    assert state["run"] == saving[["mb", "fl"]].idxmax()  # not Hindsight, which reads the future
    assert state["window"] != "the whole period" and page.evaluate("document.getElementById('map-window').value") != "0"


def test_an_evaluation_page_shows_its_figures_at_a_laptop_width(browser, toy_evaluation, tmp_path):
    page, errors, _ = open_page(browser, toy_evaluation / "report.html", tmp_path / "evaluation.png")
    assert page.evaluate("document.documentElement.dataset.rpbench") == "ready" and errors == []
    assert page.evaluate(NO_OVERFLOW), page.evaluate("document.scrollingElement.scrollWidth")
    drawn = page.evaluate(
        "[...document.querySelectorAll('.plot')].map(d => [d.id, d.classList.contains('js-plotly-plot'),"
        " d.querySelectorAll('.point, .bars path').length])"
    )
    assert [d[0] for d in drawn] == ["fig-leaderboard", "fig-by-day"], drawn
    assert all(ok and marks > 0 for _, ok, marks in drawn), drawn
    # drawn where report.md embeds their PNGs: right after the leaderboard table, before the paired tests
    order = page.evaluate(
        "[...document.querySelectorAll('main > *')].map(e => e.matches('figure') ? e.querySelector('.plot').id"
        " : e.tagName === 'H2' ? e.textContent : null).filter(Boolean)"
    )
    assert (
        order.index("fig-leaderboard")
        < order.index("fig-by-day")
        < order.index(next(h for h in order if h.startswith("Paired differences")))
    )
    assert "beside report.md" not in page.inner_text("main")
    assert label_clashes(page) == []
