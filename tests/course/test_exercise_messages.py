"""The graders' texts (``ptlab.course.messages``): one catalogue per language, the same
messages in each, and every message of the graders taken from them, so that a student on
the Chinese track gets a Chinese table (``ptlab exercise check --lang zh``)."""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import string
import subprocess
import sys
from pathlib import Path

import pytest

import ptlab.course
from ptlab.course import all_chapters, chapter
from ptlab.course.grader import grade
from ptlab.course.messages import (
    CATALOGUES,
    LANGUAGES,
    active_language,
    check_name,
    language,
    language_from_locale,
    text,
)

HERE = Path(ptlab.course.__file__).parent
WRONG = Path(__file__).parents[1] / "exercises"
#: The modules whose messages come from the catalogues: the grader's own, and the chapters'.
MODULES = [
    HERE / "chapter.py",
    HERE / "grader.py",
    HERE / "finite.py",
    HERE / "renders.py",
    HERE / "side_by_side.py",
    *sorted((HERE / "chapters").glob("ch*.py")),
]
#: The messages that are names, the same in Chinese: functions and formulas' names.
NAMES = {
    "ch06.check.eval",
    "ch06.check.sample",
    "ch09.check.Smith G",
    "ch09.check.Fresnel-Schlick",
    "ch09.check.eval",
    "ch07.check.Cornell box",
}
#: Three words in a row: a sentence (an id, a dotted name or a check's name is less).
SENTENCE = re.compile(r"[A-Za-z']+ [A-Za-z']+ [A-Za-z']+")
#: The errors whose messages are the grader's own bugs or the command line's, not verdicts.
OWN_ERRORS = ("ValueError", "RuntimeError", "TypeError", "PtlabError")
#: Words of an English sentence that no Chinese message holds (in a student's values
#: neither, for the wrong answers graded below).
ENGLISH = re.compile(r"\b(the|your|yours|should|must|is|are|not|of|from|with|and|differ)\b")


def _fields(message: str) -> list[tuple[str, str]]:
    return sorted((name, spec) for _, name, spec, _ in string.Formatter().parse(message) if name is not None)


def test_every_message_is_in_every_language_with_the_same_fields():
    ids = set(CATALOGUES["en"])
    for lang in LANGUAGES:
        assert set(CATALOGUES[lang]) == ids, (lang, set(CATALOGUES[lang]) ^ ids)
    for message_id in ids:
        fields = {lang: _fields(CATALOGUES[lang][message_id]) for lang in LANGUAGES}
        assert fields["zh"] == fields["en"], (message_id, fields)
    # A Chinese message is Chinese: each holds at least one CJK character, or is only fields
    # and symbols (a bracket, a quotation mark), or is a name said alike in both.
    for message_id, message in CATALOGUES["zh"].items():
        words = re.sub(r"\{[^}]*\}", "", message)
        if message_id in NAMES:
            assert message == CATALOGUES["en"][message_id], message_id
        else:
            assert re.search(r"[\u4e00-\u9fff]", words) or not re.search(r"[A-Za-z]{3}", words), message_id


@pytest.mark.parametrize("found", all_chapters(), ids=lambda c: c.stem)
def test_each_chapter_has_its_title_and_check_names_in_every_language(found):
    number = found.number
    for lang in LANGUAGES:
        with language(lang):
            assert text(f"ch{number:02d}.title")
            for check in found.checks:
                assert check_name(number, check.name)
    with language("en"):
        assert text(f"ch{number:02d}.title") == found.title
        assert [check_name(number, c.name) for c in found.checks] == [c.name for c in found.checks]


def _sentences(path: Path) -> list[tuple[int, str]]:
    """(line, text) of each string of ``path`` that reads as an English sentence and is not
    a docstring, a check's name (``check_name``'s key), or the message of an error of the grader's own
    (``ValueError``, ``RuntimeError``: a bug, not a verdict)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped: set[int] = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            skipped.add(id(body[0].value))
        if isinstance(node, ast.Raise) and getattr(getattr(node.exc, "func", None), "id", "") in OWN_ERRORS:
            skipped.update(id(n) for n in ast.walk(node.exc))
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") in (
            "ChapterCheck",
            "Chapter",
            "check_name",
        ):
            skipped.update(id(n) for n in ast.walk(node))
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and id(node) not in skipped
        and SENTENCE.search(node.value)
    ]


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_the_graders_say_nothing_outside_the_catalogues(path):
    assert _sentences(path) == []


def test_the_language_comes_from_lang_else_the_locale():
    assert language_from_locale({"LANG": "zh_CN.UTF-8"}) == "zh"
    assert language_from_locale({"LANG": "en_GB.UTF-8"}) == "en"
    assert language_from_locale({}) == "en"
    # POSIX's order: LC_ALL over LC_MESSAGES over LANG; an empty one does not count.
    assert language_from_locale({"LC_ALL": "C", "LANG": "zh_CN.UTF-8"}) == "en"
    assert language_from_locale({"LC_ALL": "", "LC_MESSAGES": "zh_TW", "LANG": "en_US"}) == "zh"
    with language("zh"):
        assert active_language() == "zh"
        assert text("table.pass") == "通过"
        with language("en"):
            assert text("table.pass") == "pass"
        assert text("aside", hint="x") == "（x）"
    with pytest.raises(ValueError, match="language 'fr'"), language("fr"):
        pass


@pytest.mark.subprocess
def test_a_wrong_answer_graded_in_chinese_gets_a_chinese_table_and_hints(tmp_path):
    """Chapter 1's right answer with u ignored: every heading, verdict and hint in Chinese,
    the numbers as they are."""
    wrong = (WRONG / "01_right_own_code.py").read_text(encoding="utf-8")
    mistakes = {
        "(2 * (pixel_x + u[:, 0]) / width - 1)": "(2 * (pixel_x + 0.5) / width - 1)",
        "(1 - 2 * (pixel_y + u[:, 1]) / height)": "(1 - 2 * (pixel_y + 0.5) / height)",
    }
    for old, new in mistakes.items():
        assert wrong.count(old) == 1, old
        wrong = wrong.replace(old, new)
    path = tmp_path / "01_cameras.py"
    path.write_text(wrong, encoding="utf-8")
    result = grade(chapter("1"), path, seed=25, lang="zh")
    table = result.table()
    assert result.lang == result.as_dict()["lang"] == "zh"
    for heading in ("第 1 章：相机与主光线", "检查", "得分", "说明", "总分", "评分种子 25"):
        assert heading in table, table
    failed = [r for r in result.results if not r.passed]
    assert {r.name for r in failed} >= {"jittered rays", "render"}, table
    assert "未通过  " in table, table
    for r in result.results:
        assert re.search(r"[\u4e00-\u9fff]", r.message), r.message
        assert not ENGLISH.search(r.message), r.message
    messages = {r.name: r.message for r in result.results}
    assert "忽略了 u" in messages["jittered rays"], messages


@pytest.mark.slow
@pytest.mark.subprocess
def test_check_speaks_the_locales_language(tmp_path):
    """``ptlab exercise check`` as a program, on the untouched exercise file of chapter 4
    (every check fails at once) with LANG=zh_CN.UTF-8 and no --lang: the Chinese table,
    the language kept in the JSON."""
    path = tmp_path / chapter("4").template.name
    shutil.copyfile(chapter("4").template, path)
    environment = {k: v for k, v in os.environ.items() if k not in ("LC_ALL", "LC_MESSAGES")}
    environment["LANG"] = "zh_CN.UTF-8"
    command = [sys.executable, "-m", "ptlab", "exercise", "check", "4", str(path), "--json", "out.json"]
    done = subprocess.run(command, env=environment, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 1, done.stderr
    table = done.stdout
    assert "第 4 章：包围盒：slab 测试" in table, table
    assert "slab_test 还没有写：它仍然抛出 NotImplementedError" in table, table
    assert "“进入包围盒”通过之前不计分" in table, table
    assert not ENGLISH.search(table.split("\n", 1)[1]), table  # (the first line holds the path)
    result = json.loads((tmp_path / "out.json").read_text(encoding="utf-8"))
    assert result["lang"] == "zh"
    assert result["checks"][0]["name"] == "entering a box"  # (a key: the same in every language)


def test_lang_is_an_option_of_check_and_grade_all_only_with_the_catalogues_languages():
    from ptlab.cli import build_parser

    parser = build_parser()
    for action in ("check", "grade-all"):
        args = parser.parse_args(["exercise", action, "4", "x", "--lang", "zh"])
        assert args.lang == "zh"
        assert parser.parse_args(["exercise", action, "4", "x"]).lang is None  # (the locale's)
    with pytest.raises(SystemExit):
        parser.parse_args(["exercise", "check", "4", "x.py", "--lang", "fr"])
