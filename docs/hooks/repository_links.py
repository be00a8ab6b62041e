"""MkDocs hook: links from a page to a file of the repository outside docs/ (results/, instances/).

On GitHub such a link (``[results/full-day](../results/full-day/report.md)``) opens the file; the site holds
only docs/, so MkDocs cannot resolve it.  This hook rewrites each one whose target exists: to a link to the
file in the repository when ``repo_url`` is set in mkdocs.yml, else to its text in code (the text names the
path already).  A link to a file that does not exist is left as it is, so ``mkdocs build --strict`` fails
on it as on any broken link.
"""

from __future__ import annotations

import re
from pathlib import Path

LINK_RE = re.compile(r"(?<!!)\[(?P<text>[^\]]*)\]\((?P<target>[^)\s]+)\)")


def on_page_markdown(markdown, page, config, files):
    docs = Path(config["docs_dir"]).resolve()
    top = docs.parent
    here = Path(page.file.abs_src_path).parent
    repo_url = (config.get("repo_url") or "").rstrip("/")

    def rewrite(m: re.Match) -> str:
        target = m["target"]
        if re.match(r"[a-z][a-z0-9+.-]*:", target) or target.startswith(("#", "/")):
            return m[0]  # a web address, an anchor of this page, an absolute path
        path, _, anchor = target.partition("#")
        dest = (here / path).resolve()
        if dest.is_relative_to(docs) or not dest.is_relative_to(top) or not dest.exists():
            return m[0]  # a page of the site, or a broken link MkDocs reports
        rel = dest.relative_to(top).as_posix()
        if repo_url:
            kind = "tree" if dest.is_dir() else "blob"
            return f"[{m['text']}]({repo_url}/{kind}/HEAD/{rel}{'#' + anchor if anchor else ''})"
        text = m["text"].strip("`")
        return f"`{text}`"

    # links inside fenced code blocks are text: rewrite only between the fences
    parts = re.split(r"(^```.*?^```[ \t]*$)", markdown, flags=re.M | re.S)
    return "".join(part if part.startswith("```") else LINK_RE.sub(rewrite, part) for part in parts)
