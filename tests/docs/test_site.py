"""The documentation site in a real browser: built from mkdocs.yml, served on 127.0.0.1, opened in headless
Chromium through Playwright.

The home page has its title, the API reference shows ``RunSpec`` with its heading and signature, and the
search box finds a page; no page fetches anything from elsewhere or logs a console error.  Skips, saying
why, where MkDocs (``pip install -e '.[docs]'``), Playwright or Chromium is not installed, as the browser
test of report.html does (tests/report/html/test_browser.py, whose Chromium lookup this reuses).
"""

from __future__ import annotations

import functools
import importlib.util
import os
import re
import subprocess
import sys
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

playwright = pytest.importorskip(
    "playwright.sync_api", reason="Playwright is not installed (pip install -e '.[browser]')"
)

from tests.report.html.test_browser import CHROMIUM_ARGS, READY_TIMEOUT_MS, chromium  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
#: What mkdocs.yml needs: MkDocs, its theme and the API reference's plug-in (the `docs` extra).
DOCS_MODULES = ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers.python")


def missing_docs_modules() -> list[str]:
    missing = []
    for name in DOCS_MODULES:
        try:
            found = importlib.util.find_spec(name) is not None
        except ModuleNotFoundError:  # a parent package is missing
            found = False
        if not found:
            missing.append(name)
    return missing


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site as ``mkdocs build --strict`` writes it (warnings are errors)."""
    missing = missing_docs_modules()
    if missing:
        pytest.skip(f"MkDocs is not installed ({', '.join(missing)} missing; pip install -e '.[docs]')")
    out = tmp_path_factory.mktemp("docs") / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", str(ROOT / "mkdocs.yml")]
        + ["--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    assert (out / "index.html").is_file()
    return out


@pytest.fixture(scope="module")
def served(site):
    """The site's address on a local HTTP server (the search's worker needs http, not file:)."""

    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(site)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=10)


@pytest.fixture(scope="module")
def browser():
    with playwright.sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def visit(browser, served):
    """Open a page of the site; every request elsewhere is refused and recorded, as is every console error."""
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    context.set_default_timeout(READY_TIMEOUT_MS)
    errors: list[str] = []
    elsewhere: list[str] = []

    def route(r):
        if r.request.url.startswith(served + "/"):
            r.continue_()
        else:
            elsewhere.append(r.request.url)
            r.abort()

    context.route("**/*", route)

    def open_page(path: str):
        page = context.new_page()
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(f"{served}/{path}")
        page.wait_for_load_state("load")
        return page

    yield open_page
    context.close()
    assert elsewhere == [], f"the site fetched from elsewhere: {elsewhere}"
    assert errors == [], errors


def test_the_home_page_says_what_rpbench_is(visit):
    page = visit("")
    assert page.title().startswith("rpbench")
    assert page.locator("article h1").first.inner_text().startswith("rpbench")
    assert "ride-pooling" in page.locator("article").inner_text()
    # the navigation leads to the getting-started path and the API reference
    nav = page.locator("nav.md-nav--primary").inner_text()
    assert "Getting started" in nav and "API reference" in nav


def test_the_api_reference_shows_runspec_with_its_signature(visit):
    page = visit("api/")
    heading = page.locator('[id="rpbench.spec.RunSpec"]')
    assert heading.is_visible()
    assert "RunSpec" in heading.inner_text()
    # the signature, generated from the dataclass's fields, right below the heading
    signature = page.locator('[id="rpbench.spec.RunSpec"] + .doc-signature').inner_text()
    assert signature.startswith("RunSpec(") and "request: ScenarioRequest" in signature, signature
    assert "preset: str = " in signature
    # and its docstring, and those of the plug-in author's pieces
    text = page.locator("article").inner_text()
    assert "A comparison of runs on one scenario" in text
    for anchor in (
        "rpbench.strategies.base.Strategy",
        "rpbench.strategies.candidates.VacantOptions",
        "rpbench.strategies.candidates.JoinOptions",
        "rpbench.strategies.candidates.assignment_round",
        "rpbench.strategies.candidates.NO_WAIT_UTILITY_M",
    ):
        assert page.locator(f'[id="{anchor}"]').count() == 1, anchor
    # the docstrings' Sphinx cross-references read as code, not as ":class:" text
    assert not re.search(r":(class|func|meth|mod|attr|data|exc):", text), re.search(
        r".{40}:(class|func|meth):.{40}", text
    )


def test_the_search_finds_a_page(visit, served):
    page = visit("")
    box = page.locator("input.md-search__input")
    box.click()
    box.fill("competitive ratio")
    results = page.locator(".md-search-result__item")
    results.first.wait_for(state="visible")
    assert results.count() >= 1
    links = page.eval_on_selector_all(".md-search-result__link", "links => links.map(a => a.href)")
    assert links and all(link.startswith(served + "/") for link in links), links
    page.goto(links[0])
    assert page.locator("article h1").count() == 1
