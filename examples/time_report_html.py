"""Time report.html: writing it from a results folder, and loading it in headless Chromium offline.

    python examples/time_report_html.py RESULTS_DIR [--repeat 5]

Prints, per repeat, the seconds ``write_html`` took (in this process, the first repeat paying for
compressing Plotly's script once) and the milliseconds from navigation to every figure drawn, as the
page measures it (``data-ready-ms``), plus the page's size.  Needs the ``browser`` extra and Chromium.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from rpbench.report.html import write_html

ARGS = ["--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
        for i in range(args.repeat):
            start = time.perf_counter()
            page_path = write_html(args.folder, args.folder.name, dest=Path(tmp))
            written = time.perf_counter() - start
            context = browser.new_context(offline=True, viewport={"width": 1280, "height": 900})
            page = context.new_page()
            page.goto(page_path.as_uri())
            page.wait_for_function("document.documentElement.dataset.rpbench !== 'loading'", timeout=120_000)
            state, ready = page.evaluate(
                "[document.documentElement.dataset.rpbench, document.documentElement.dataset.readyMs]"
            )
            context.close()
            size = page_path.stat().st_size / 1e6
            print(f"repeat {i + 1}: write {written:.2f} s, load {ready} ms ({state}), {size:.2f} MB")
        browser.close()


if __name__ == "__main__":
    main()
