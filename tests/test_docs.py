"""The documentation's links and pictures point at files that exist, every `ptlab` command it
shows is one the command line accepts, the README's test command is the one CI runs, every
chapter has its page in English and in Chinese, and each Chinese page keeps in step with its
English one."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from ptlab.cli import build_parser
from ptlab.course import all_chapters

ROOT = Path(__file__).parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
CHINESE_PAGES = sorted((ROOT / "docs" / "zh").glob("*.md"))


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page):
    broken = [
        target
        for target in LINK.findall(page.read_text())
        if "://" not in target and not (page.parent / target).exists()
    ]
    assert not broken, broken


def _code_lines(page: Path) -> list[str]:
    """The lines of the page's code: fenced blocks, and blocks indented by four spaces."""
    lines, fenced = [], False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif fenced or line.startswith("    "):
            lines.append(line.strip())
    return lines


def _ptlab_commands(page: Path) -> list[list[str]]:
    """The words after `ptlab` (or `python -m ptlab`) of every command in the page's code,
    a shell prompt `$ ` and a trailing `# comment` taken off."""
    commands = []
    for line in _code_lines(page):
        for program in ("ptlab ", "python -m ptlab "):
            if line.removeprefix("$ ").startswith(program):
                words = shlex.split(line.removeprefix("$ "), comments=True)
                commands.append(words[len(program.split()) :])
    return commands


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_ptlab_command_shown_is_one_the_command_line_accepts(page, capsys):
    """Each command parses as `ptlab` parses it (a misspelt option or a command that moved
    fails here): the docs may be read and copied, not only looked at."""
    refused = []
    for words in _ptlab_commands(page):
        try:
            build_parser(words[0] if words else None).parse_args(words)
        except SystemExit as stop:  # (--help and --version exit 0, after printing)
            if stop.code != 0:
                refused.append(shlex.join(["ptlab", *words]))
    assert not refused, f"{refused}: {capsys.readouterr().err}"


def test_there_are_commands_to_check():
    """The command test above looks at the README's commands (a change in how they are
    found, or written, would leave it nothing to check)."""
    assert len(_ptlab_commands(ROOT / "README.md")) >= 8


def test_the_readme_gives_the_test_command_that_ci_runs():
    """`.ci/run` runs the README's test command verbatim: the same line in both."""
    readme = [line.split("#")[0].strip() for line in _code_lines(ROOT / "README.md")]
    tests = [line for line in readme if line.endswith("&& pytest")]
    assert tests == ["pip install '.[test]' && pytest"], tests
    ci = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert tests[0] in ci


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


@pytest.mark.parametrize("page", CHINESE_PAGES, ids=lambda p: p.name)
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


def _outline(page: Path) -> tuple[list[int], int]:
    """The levels of the page's headings, in order, and the number of its fenced code blocks."""
    levels, blocks, fenced = [], 0, False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            blocks += not fenced
        elif not fenced and line.startswith("#"):
            levels.append(len(line) - len(line.lstrip("#")))
    return levels, blocks


@pytest.mark.parametrize("page", sorted((ROOT / "docs").glob("*.md")), ids=lambda p: p.name)
def test_every_page_has_its_chinese_page_in_step(page):
    """Each English page has a Chinese one: each links to the other, and they have the same
    sections (the levels of their headings, in order) and as many code blocks. A section or
    a command added to one language only fails here."""
    chinese = ROOT / "docs" / "zh" / page.name
    assert chinese.is_file(), f"{page.name} has no Chinese page (docs/zh/{page.name})"
    assert f"(zh/{page.name})" in page.read_text(encoding="utf-8"), "no link to the Chinese page"
    assert f"(../{page.name})" in chinese.read_text(encoding="utf-8"), "no link back to the English page"
    assert _outline(chinese) == _outline(page)


@pytest.mark.parametrize("page", CHINESE_PAGES, ids=lambda p: p.name)
def test_every_chinese_page_translates_an_english_one(page):
    assert (ROOT / "docs" / page.name).is_file()
