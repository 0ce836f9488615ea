"""The user docs hold together: every relative link and anchor resolves inside the repository,
every picture is used, the README stays short, and no page is a dated journal."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", ROOT / "CHANGELOG.md", *(ROOT / "docs").rglob("*.md")])
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
ANCHOR = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def _text(page: Path) -> str:
    """A page without its fenced code blocks (their brackets are code, not links)."""
    return FENCE.sub("", page.read_text())


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[`*_]", "", heading).strip().lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    text = _text(page)
    out, seen = set(), {}
    for heading in re.findall(r"^#{1,6} (.+)$", text, re.M):
        slug = _slug(heading)
        n = seen.get(slug, 0)
        out.add(slug if n == 0 else f"{slug}-{n}")
        seen[slug] = n + 1
    return out | set(ANCHOR.findall(text))


def _links(page: Path) -> list[str]:
    return [t for t in LINK.findall(_text(page)) if not re.match(r"[a-z]+:", t)]


def test_the_pages_are_there():
    names = {p.relative_to(ROOT).as_posix() for p in PAGES}
    for page in ("README.md", "CHANGELOG.md", "docs/quickstart.md", "docs/spec.md",
                 "docs/validation.md", "docs/batches.md", "docs/reports.md",
                 "docs/runtime.md", "docs/reference.md"):
        assert page in names
    assert any(n.startswith("docs/models/") for n in names)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves_inside_the_repository(page):
    bad = []
    for target in _links(page):
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if ROOT not in dest.parents and dest != ROOT:
            bad.append(f"{target}: outside the repository")
        elif not dest.exists():
            bad.append(f"{target}: no such file")
        elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
            bad.append(f"{target}: no such anchor in {dest.relative_to(ROOT)}")
    assert not bad, f"{page.relative_to(ROOT)}: " + "; ".join(bad)


def test_every_picture_in_docs_img_is_used():
    used = {(page.parent / t.partition("#")[0]).resolve() for page in PAGES
            for t in _links(page)}
    unused = [p.name for p in sorted((ROOT / "docs" / "img").iterdir()) if p.resolve() not in used]
    assert not unused, f"pictures no page shows (git rm them): {unused}"


def test_the_readme_is_short():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) < 150, f"README.md has {len(lines)} lines"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_page_is_a_dated_journal_or_points_outside(page):
    text = page.read_text()
    if page.name != "CHANGELOG.md":     # release headings carry dates there
        dated = re.findall(r"^#{1,6} .*\d{4}-\d{2}-\d{2}.*$", text, re.M)
        assert not dated, f"dated headings: {dated}"
    for outside in ("ball_on_disc.md", "/shared/", "bench/states/", "bench/results/"):
        hits = [line for line in text.splitlines()
                if outside in line and "git show" not in line and "5ad327e" not in line]
        assert not hits, f"points outside the repository ({outside}): {hits[:2]}"
