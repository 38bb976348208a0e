"""The documentation's links and pictures point at files that exist, and every chapter has
its page in English and in Chinese."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ptlab.exercises import all_chapters

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page):
    broken = [target for target in LINK.findall(page.read_text())
              if "://" not in target and not (page.parent / target).exists()]
    assert not broken, broken


@pytest.mark.parametrize("found", all_chapters(), ids=lambda c: c.stem)
def test_every_chapter_has_its_page_in_both_languages(found):
    for folder in (ROOT / "docs", ROOT / "docs" / "zh"):
        page = folder / found.doc
        assert page.is_file(), page
        assert f"exercise check {found.number}" in page.read_text() or \
            f"exercise check {found.number:02d}" in page.read_text(), page
