"""The documentation's links and pictures point at files that exist, and every chapter has
its page in English and in Chinese."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from ptlab.course import all_chapters

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page):
    broken = [
        target
        for target in LINK.findall(page.read_text())
        if "://" not in target and not (page.parent / target).exists()
    ]
    assert not broken, broken


@pytest.mark.parametrize("found", all_chapters(), ids=lambda c: c.stem)
def test_every_chapter_has_its_page_in_both_languages(found):
    for folder in (ROOT / "docs", ROOT / "docs" / "zh"):
        page = folder / found.doc
        assert page.is_file(), page
        assert (
            f"exercise check {found.number}" in page.read_text()
            or f"exercise check {found.number:02d}" in page.read_text()
        ), page


#: Terms the Chinese pages must not use, with the term that replaces each: the GAMES101 lectures'
#: or, where they have none, the usual one (Owen 置乱 for scrambling), one term per concept.
NOT_THE_LECTURES_TERMS = {
    "层次包围体": "层次包围盒",
    "克莱姆法则": "克拉默法则",
    "阴影痤疮": "自相交/阴影失真（shadow acne）",
    "个独立的遍": "轮次",
    "每遍": "每个轮次",
    "白白": "不费任何代价",
    "扰动": "置乱（scrambling，如 Owen 置乱）",
    "辐亮度": "辐射亮度",
    "对光源采样": "光源采样",
}


def _chinese_prose(page: Path) -> str:
    """The page without its code: fenced and indented blocks, and `code` spans."""
    lines, fenced = [], False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced and not line.startswith("    "):
            lines.append(line)
    return re.sub(r"`[^`]*`", "", "\n".join(lines))


@pytest.mark.parametrize("page", sorted((ROOT / "docs" / "zh").glob("*.md")), ids=lambda p: p.name)
def test_chinese_pages_use_the_lectures_terms_and_chinese_quotes(page):
    prose = _chinese_prose(page)
    wrong = {term: better for term, better in NOT_THE_LECTURES_TERMS.items() if term in prose}
    assert not wrong, wrong
    assert '"' not in prose, "straight quotes in Chinese prose: use “”"
    assert "throughput" not in prose or "吞吐量" in prose, "throughput is 路径吞吐量"
    passes = re.findall(r"[\u4e00-\u9fff，。（] *pass\b", prose)
    assert not passes, f"a render pass is 轮次: {passes}"
    films = re.findall(r"(?<![（A-Za-z])film(?![A-Za-z_])", prose)
    assert not films, "the film is 胶片 (胶片（film）where it is new)"
