"""The exercises: every chapter's grader against the library's answer, the untouched
exercise file and typical wrong answers; the grader's time limits; the command line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from ptlab.cli import main
from ptlab.exercises import all_chapters, chapter
from ptlab.exercises.grader import grade

WRONG = Path(__file__).parent / "exercises"
CHAPTERS = all_chapters()


def _ids(chapters):
    return [c.stem for c in chapters]


@pytest.mark.parametrize("found", CHAPTERS, ids=_ids(CHAPTERS))
def test_the_library_answer_gets_full_marks(found, tmp_path):
    result = grade(found, found.solution)
    assert result.full_marks, result.table()


@pytest.mark.parametrize("found", CHAPTERS, ids=_ids(CHAPTERS))
def test_the_untouched_exercise_file_fails_every_check_clearly(found):
    result = grade(found, found.template)
    assert result.score == 0, result.table()
    for check in result.results:
        assert "not written yet" in check.message or "NotImplementedError" in check.message, \
            result.table()
        assert "Traceback" not in check.message


def _wrong_answers():
    return sorted(WRONG.glob("[0-9][0-9]_wrong_*.py"))


@pytest.mark.parametrize("path", _wrong_answers(), ids=lambda p: p.stem)
def test_typical_wrong_answers_fail_the_checks_meant_to_catch_them(path):
    namespace: dict = {}
    exec(compile(path.read_text(), str(path), "exec"), namespace)   # for EXPECTED_FAILURES
    result = grade(chapter(path.name[:2]), path)
    assert not result.full_marks
    failed = {r.name for r in result.results if not r.passed}
    assert set(namespace["EXPECTED_FAILURES"]) <= failed, result.table()


def test_every_chapter_has_a_wrong_answer_that_fails():
    covered = {int(p.name[:2]) for p in _wrong_answers()}
    assert covered == {c.number for c in CHAPTERS}


def test_code_that_hangs_or_raises_fails_its_check_and_grading_goes_on():
    result = grade(chapter(1), WRONG / "01_hangs_or_raises.py", timeout_scale=0.05)
    by_name = {r.name: r for r in result.results}
    assert "took longer than" in by_name["centre ray"].message       # the single-ray check hung
    # ... and the next checks still ran, each failing with the error and the student's line.
    assert "01_hangs_or_raises.py:" in by_name["unit directions"].message
    assert "ValueError: my bug with 500 rays" in by_name["unit directions"].message
    assert result.score == 0 and len(result.results) == len(chapter(1).checks)


def test_a_file_with_a_syntax_error_fails_with_the_line(tmp_path):
    broken = tmp_path / "01_cameras.py"
    broken.write_text("def generate_rays(:\n    pass\n")
    result = grade(chapter(1), broken, timeout_scale=0.2)
    assert result.score == 0
    assert all("01_cameras.py:1: syntax error" in r.message for r in result.results)


def test_start_copies_the_exercise_file_and_refuses_to_overwrite(tmp_path, capsys):
    assert main(["exercise", "start", "01", str(tmp_path)]) == 0
    copied = tmp_path / "01_cameras.py"
    assert copied.read_text() == chapter(1).template.read_text()
    assert main(["exercise", "start", "1", str(tmp_path)]) == 2
    assert "already exists" in capsys.readouterr().err


def test_check_prints_a_score_table_writes_json_and_list_shows_progress(tmp_path, capsys):
    answer = tmp_path / "01_cameras.py"
    shutil.copyfile(WRONG / "01_right_own_code.py", answer)
    assert main(["exercise", "check", "1", str(answer), "--json", str(tmp_path / "r.json")]) == 0
    table = capsys.readouterr().out
    assert "10/10" in table and "full marks" in table
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["full_marks"] and result["score"] == result["max_score"] == 10
    assert {c["name"] for c in result["checks"]} >= {"centre ray", "render"}
    assert main(["exercise", "list", str(tmp_path)]) == 0
    listing = capsys.readouterr().out
    assert "1 record found" in listing.splitlines()[0]
    assert "passed (10/10)" in listing.splitlines()[2]


def test_check_exits_1_below_full_marks_and_2_for_user_errors(tmp_path, capsys):
    answer = tmp_path / "01_cameras.py"
    shutil.copyfile(chapter(1).template, answer)
    assert main(["exercise", "check", "1", str(answer)]) == 1
    capsys.readouterr()
    for arguments, message in [(["check", "99", str(answer)], "no such chapter"),
                               (["check", "1", str(tmp_path / "missing.py")], "no such file"),
                               (["start", "x"], "no such chapter")]:
        assert main(["exercise", *arguments]) == 2
        error = capsys.readouterr().err
        assert message in error and error.count("\n") == 1
