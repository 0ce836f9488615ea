"""The docs the code cites are there: every ``docs/PAGE.md`` or ``docs/PAGE.md#section`` that a
comment, docstring, notice, template or example spec names (under src/, examples/, bench/ and
tests/) is a page of the repository with that section, and none names a page the docs no
longer have."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.test_docs_links import ROOT, _anchors

#: where citations live: the package (its templates included), the example specs, the
#: benchmarks and the tests
TREES = ("src", "examples", "bench", "tests")
#: pages that are gone, with where their knowledge went
REMOVED = {
    "docs/cases.md": "docs/models/interface.md, docs/validation.md",
    "docs/cavitation.md": "docs/models/cavitating.md, docs/models/gas-release.md",
    "docs/ehl_precalc.md": "docs/models/contact.md",
    "docs/models.md": "docs/models/<scene>.md",
    "ball_on_disc.md": "docs/reference.md",
}
CITATION = re.compile(r"docs/[A-Za-z0-9_./-]+\.md(?:#[A-Za-z0-9_-]+)?")
#: a section named by its title after the page (``docs/PAGE.md, "Title"``), as the removed
#: pages were cited, instead of by its anchor
BY_TITLE = re.compile(CITATION.pattern + r',? +"')
#: a placeholder in capitals, as in an error message's "docs/FILE.md#section"
PLACEHOLDER = re.compile(r"docs/[A-Z_]+\.md")
#: files whose own lists name the removed pages on purpose: this one, and the docs-links
#: test's list of paths the docs must not point to
GUARDS = {Path(__file__).resolve(), ROOT / "tests" / "test_docs_links.py"}


def _text_files(tree: str) -> list[Path]:
    files = []
    for path in sorted((ROOT / tree).rglob("*")):
        parts = path.relative_to(ROOT).parts
        if not path.is_file() or "__pycache__" in parts or \
                any(p.endswith(".egg-info") for p in parts):
            continue
        files.append(path)
    return files


def _lines(path: Path) -> list[str]:
    try:
        return path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:      # a binary file cites nothing
        return []


def _where(path: Path, number: int) -> str:
    return f"{path.relative_to(ROOT).as_posix()}:{number}"


@pytest.mark.parametrize("tree", TREES)
def test_every_cited_page_and_section_exists(tree):
    bad = []
    for path in _text_files(tree):
        if path.resolve() == Path(__file__).resolve():
            continue
        for number, line in enumerate(_lines(path), start=1):
            for citation in CITATION.findall(line):
                page, _, anchor = citation.partition("#")
                if PLACEHOLDER.fullmatch(page):
                    continue
                target = ROOT / page
                if not target.is_file():
                    bad.append(f"{_where(path, number)}: {citation}: no such page")
                elif anchor and anchor not in _anchors(target):
                    bad.append(f"{_where(path, number)}: {citation}: no such section")
            bad += [f"{_where(path, number)}: {m[0]}: name the section by its anchor, "
                    "docs/PAGE.md#section" for m in BY_TITLE.finditer(line)]
    assert not bad, f"{len(bad)} citations do not resolve:\n" + "\n".join(bad)


@pytest.mark.parametrize("tree", TREES)
def test_no_removed_page_is_cited(tree):
    hits = [f"{_where(path, number)}: {page} (now {REMOVED[page]})"
            for path in _text_files(tree) if path.resolve() not in GUARDS
            for number, line in enumerate(_lines(path), start=1)
            for page in REMOVED if page in line]
    assert not hits, f"{len(hits)} citations of removed pages:\n" + "\n".join(hits)


def test_the_scan_sees_citations_and_their_sections():
    """The scan is not vacuous: it finds the notices' pointers, and the anchor check tells a
    section from a missing one."""
    warnings = ROOT / "src" / "ehlfoam" / "run" / "warnings.py"
    found = {c for line in _lines(warnings) for c in CITATION.findall(line)}
    assert "docs/models/interface.md#rear-meniscus-cells" in found
    anchors = _anchors(ROOT / "docs" / "models" / "interface.md")
    assert "rear-meniscus-cells" in anchors and "rear-meniscus" not in anchors
    assert "v-films" in _anchors(ROOT / "docs" / "validation.md")
    assert PLACEHOLDER.fullmatch("docs/FILE.md") and not PLACEHOLDER.fullmatch("docs/spec.md")
    assert BY_TITLE.search('(docs/validation.md, "The films")')
    assert not BY_TITLE.search("(docs/validation.md#v-films)")
