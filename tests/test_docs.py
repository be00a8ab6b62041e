"""Every reference to docs/algorithms.md resolves: its sections (§2.4) and labels (A13, I4, O-T7, ...).

The code, its help texts and the documentation cite the algorithms page by section number and by
label.  This test collects what the page defines (its numbered headings and the labels it defines
in a table row, a bold bullet or an equation line) and what the scanned files cite, and names every
citation the page does not define.

A ``§`` reference counts as a reference to the algorithms page unless the nearest document named
before it on the same line is another one (``paper §4.1``, ``TR-B §5``).  Ranges (``A1-A24``,
``O-T1..O-T8``, ``(A1)-(A6)``) are expanded; section ranges (``§2.3-2.4``) are checked at both ends.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ALGORITHMS = ROOT / "docs" / "algorithms.md"
#: What is scanned for references: the package, the documentation and the READMEs a user reads.
SCANNED = (
    "rpbench",
    "docs",
    "solvers",
    "examples",
    "README.md",
    "CHANGELOG.md",
    "instances/README.md",
    "results/README.md",
    "results/replication/README.md",
)
SUFFIXES = {".py", ".md", ".toml", ".txt", ".rst"}

#: A label family: letters, then a number.  ``O-T`` before ``O`` so that O-T7 is not read as O.
FAMILIES = ("O-T", "A", "I", "L", "G", "R", "O")
_FAMILY = "|".join(re.escape(f) for f in FAMILIES)
_NUMBER = r"\d{1,2}"
#: One label, or a range of one family: A1, (A1), A15-A17, O-T1..O-T8, (A1)-(A6), I1–I9.
LABEL_RE = re.compile(
    rf"(?<![\w/.#%-])\(?(?P<fam>{_FAMILY})(?P<lo>{_NUMBER})\)?"
    rf"(?:\s*(?:-|–|\.\.)\s*\(?(?P=fam)(?P<hi>{_NUMBER})\)?)?(?![\w%])"
)
SECTION_RE = re.compile(r"§\s*(?P<lo>\d+(?:\.\d+)*)(?:\s*(?:-|–)\s*§?\s*(?P<hi>\d+(?:\.\d+)*))?")
#: Documents a § number can belong to; the nearest one named before the § on its line decides.
OTHER_DOCUMENTS = re.compile(r"\bpaper\b|\bpaper's\b|\bTR-B\b|\bPNAS\b")
THIS_DOCUMENT = re.compile(r"algorithms\.md")
URL_RE = re.compile(r"\w+://\S+")

HEADING_RE = re.compile(r"^#{2,4}\s+(?P<num>\d+(?:\.\d+)*)\.?\s")
#: Where the page defines a label: a table row's first cell, a bullet opening with the bold label
#: (``* **I4.**``, ``* **(O1) Time.**``, ``* **L3 (one OD ...).**``), or an equation line ``(A1) ...``.
DEFINITION_RES = (
    re.compile(rf"^\|\s*(?P<label>(?:{_FAMILY}){_NUMBER})\s*\|"),
    re.compile(rf"^\s*[*-]\s+\*\*\(?(?P<label>(?:{_FAMILY}){_NUMBER})\)?[\s.*]"),
    re.compile(rf"^\((?P<label>(?:{_FAMILY}){_NUMBER})\)\s"),
)


def defined(text: str) -> tuple[set[str], set[str]]:
    """The section numbers and the labels the algorithms page defines."""
    sections: set[str] = set()
    labels: set[str] = set()
    for line in text.splitlines():
        heading = HEADING_RE.match(line)
        if heading:
            sections.add(heading["num"])
        for pattern in DEFINITION_RES:
            found = pattern.match(line)
            if found:
                labels.add(found["label"])
    return sections, labels


def cited(text: str) -> list[tuple[int, str]]:
    """(line number, reference) for every section and label ``text`` cites, ranges expanded."""
    refs: list[tuple[int, str]] = []
    for number, raw in enumerate(text.splitlines(), 1):
        line = URL_RE.sub(" ", raw)
        for m in LABEL_RE.finditer(line):
            lo = int(m["lo"])
            hi = int(m["hi"]) if m["hi"] else lo
            refs.extend((number, f"{m['fam']}{k}") for k in range(lo, max(lo, hi) + 1))
        for m in SECTION_RE.finditer(line):
            before = line[: m.start()]
            other = [o.end() for o in OTHER_DOCUMENTS.finditer(before)]
            this = [t.end() for t in THIS_DOCUMENT.finditer(before)]
            if other and (not this or max(other) > max(this)):
                continue  # a section of the paper (or of another source), not of this page
            refs.extend((number, f"§{s}") for s in (m["lo"], m["hi"]) if s)
    return refs


def unresolved(text: str, sections: set[str], labels: set[str]) -> list[tuple[int, str]]:
    """The citations of ``text`` the page does not define."""
    return [
        (n, ref) for n, ref in cited(text) if (ref[1:] not in sections if ref.startswith("§") else ref not in labels)
    ]


def scanned_files() -> list[Path]:
    files: list[Path] = []
    for name in SCANNED:
        path = ROOT / name
        if path.is_file():
            files.append(path)
        elif path.is_dir():
            files.extend(p for p in sorted(path.rglob("*")) if p.is_file() and p.suffix in SUFFIXES)
    return files


@pytest.fixture(scope="module")
def page() -> tuple[set[str], set[str]]:
    return defined(ALGORITHMS.read_text(encoding="utf-8"))


def test_the_page_defines_its_sections_and_labels(page):
    sections, labels = page
    assert {"1.1", "2.4", "3.3", "4.2", "5"} <= sections
    expected = {f"A{k}" for k in range(1, 25)} | {f"I{k}" for k in range(1, 10)} | {f"L{k}" for k in range(1, 9)}
    expected |= {f"G{k}" for k in range(1, 5)} | {f"R{k}" for k in range(1, 10)} | {f"O-T{k}" for k in range(1, 9)}
    expected |= {f"O{k}" for k in range(1, 5)}
    assert expected <= labels, sorted(expected - labels)


def test_every_reference_resolves(page):
    sections, labels = page
    assert scanned_files(), "nothing scanned"
    missing = [
        f"{path.relative_to(ROOT)}:{n}: {ref}"
        for path in scanned_files()
        for n, ref in unresolved(path.read_text(encoding="utf-8", errors="replace"), sections, labels)
    ]
    assert not missing, "docs/algorithms.md does not define:\n" + "\n".join(missing)


#: Markdown files whose links to each other must resolve.
LINKED = ("README.md", "CHANGELOG.md", "docs", "instances", "results", "solvers", "examples")
LINK_RE = re.compile(r"\[[^\]]*\]\((?P<target>[^)\s]+)\)")


def slug(heading: str) -> str:
    """A heading's anchor as GitHub renders it (lower case, punctuation dropped, spaces to hyphens)."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    return {slug(m[1]) for m in re.finditer(r"^#+\s+(.*)$", path.read_text(encoding="utf-8"), re.M)}


def markdown_files() -> list[Path]:
    files: list[Path] = []
    for name in LINKED:
        path = ROOT / name
        if path.is_file():
            files.append(path)
        elif path.is_dir():
            files.extend(p for p in sorted(path.rglob("*.md")) if p.name != "report.md")  # reports are generated
    return files


def broken_links(path: Path) -> list[str]:
    """Links of ``path`` to a file or heading of the repository that does not exist."""
    broken = []
    for m in LINK_RE.finditer(path.read_text(encoding="utf-8")):
        target = m["target"]
        if re.match(r"[a-z]+:", target):
            continue  # a web address
        file_part, _, anchor = target.partition("#")
        dest = (path.parent / file_part).resolve() if file_part else path
        if not dest.exists():
            broken.append(f"{path.relative_to(ROOT)}: {target} (no such file)")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{path.relative_to(ROOT)}: {target} (no such heading)")
    return broken


def test_links_between_documents_resolve():
    """Documents link to each other by relative paths that exist, headings included."""
    files = markdown_files()
    assert ALGORITHMS in files
    broken = [b for path in files for b in broken_links(path)]
    assert not broken, "\n".join(broken)


def test_a_broken_link_is_named(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "a.md").write_text("# Top\n\n## The model\n", encoding="utf-8")
    page = tmp_path / "b.md"
    page.write_text("[ok](a.md#the-model) [gone](c.md) [no heading](a.md#accuracy) [web](https://x.org/y)\n")
    assert broken_links(page) == ["b.md: c.md (no such file)", "b.md: a.md#accuracy (no such heading)"]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("resolution A25 of docs/algorithms.md", [(1, "A25")]),
        ("see docs/algorithms.md §2.11", [(1, "§2.11")]),
        ("properties I1-I10", [(1, "I10")]),
        ("O-T1..O-T9 and §7", [(1, "O-T9"), (1, "§7")]),
        ("(paper §4.7; docs/algorithms.md §9.9)", [(1, "§9.9")]),
        ("the paper's §4.7, A4, R9 and G4", []),
        ("TR-B §5, https://example.org/A99#L77", []),
    ],
)
def test_an_undefined_reference_is_named(page, text, expected):
    """The scan fails on what the page does not define, and only on that."""
    sections, labels = page
    assert unresolved(text, sections, labels) == expected
