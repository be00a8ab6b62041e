"""MkDocs hook: the docstrings' Sphinx roles (``:class:`~rpbench.x.Outcome```) shown as code, not as text.

rpbench's docstrings cross-reference in Sphinx's notation, which Python's own tools and editors read; the
API reference renders them with mkdocstrings, which leaves the role's name in the text
(``:class:<code>~rpbench.x.Outcome</code>``).  This hook drops the role and, as Sphinx does for a target
that starts with ``~``, shows only its last component.
"""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const|ref):<code>(~?)([^<]*)</code>")


def shown(match: re.Match) -> str:
    tilde, target = match[1], match[2]
    return f"<code>{target.rsplit('.', 1)[-1] if tilde else target}</code>"


def on_page_content(html, page, config, files):
    return ROLE.sub(shown, html)
