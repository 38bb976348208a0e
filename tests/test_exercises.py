"""The exercises: every chapter's grader against the library's answer, the untouched
exercise file and typical wrong answers; the grader's time limits; the command line."""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
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


def _right_answers():
    return sorted(WRONG.glob("[0-9][0-9]_right_*.py"))


def _constants(path: Path) -> dict:
    """EXPECTED_FAILURES, EXPECTED_HINTS, MISLEADING_HINTS of an answer in tests/exercises."""
    namespace: dict = {}
    exec(compile(path.read_text(), str(path), "exec"), namespace)
    return namespace


@pytest.mark.parametrize("path", _wrong_answers(), ids=lambda p: p.stem)
def test_typical_wrong_answers_fail_exactly_the_checks_meant_to_catch_them(path):
    """Each wrong answer fails the checks it names, and no other (a mistake is reported by
    the check that owns it); where it names hints, the messages say them (the essential
    words), and not the misleading ones."""
    constants = _constants(path)
    result = grade(chapter(path.name[:2]), path)
    failed = {r.name for r in result.results if not r.passed}
    assert failed == set(constants["EXPECTED_FAILURES"]), result.table()
    messages = {r.name: r.message for r in result.results}
    for check, phrases in constants.get("EXPECTED_HINTS", {}).items():
        for phrase in phrases:
            assert phrase in messages[check], (check, phrase, messages[check])
    for check, phrases in constants.get("MISLEADING_HINTS", {}).items():
        for phrase in phrases:
            assert phrase not in messages[check], (check, phrase, messages[check])


@pytest.mark.parametrize("path", _right_answers(), ids=lambda p: p.stem)
def test_other_right_answers_get_full_marks_and_no_warning(path):
    """Right answers written into the exercise file as a student would (another sampling
    than the library's) get full marks, and the material harness warns of nothing: the
    exercise file's own ``__init__`` keeps float32 float32."""
    from ptlab.grading import check_material
    from ptlab.grading.untrusted import import_file

    result = grade(chapter(path.name[:2]), path)
    assert result.full_marks, result.table()
    module = import_file(path)
    material = module.Lambertian() if hasattr(module, "Lambertian") else module.GGXMetal()
    report = check_material(material, seed=0, samples=100_000)
    assert [c.verdict for c in report.checks] == ["pass"] * len(report.checks), str(report)


@pytest.mark.parametrize("number, name", [(6, "Lambertian"), (9, "GGXMetal")])
def test_the_exercise_files_keep_material_parameters_in_float32(number, name):
    from ptlab.grading.untrusted import import_file

    material = getattr(import_file(chapter(number).template), name)()
    parameter = material.albedo if number == 6 else material.f0
    assert parameter.dtype == np.float32


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
    shutil.copyfile(chapter(1).solution, answer)
    assert main(["exercise", "check", "1", str(answer), "--json", str(tmp_path / "r.json")]) == 0
    table = capsys.readouterr().out
    assert "10/10" in table and "full marks" in table
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["full_marks"] and result["score"] == result["max_score"] == 10
    assert {c["name"] for c in result["checks"]} >= {"centre ray", "render"}
    assert main(["exercise", "list", str(tmp_path)]) == 0
    listing = capsys.readouterr().out
    assert "passed (10/10)" in listing.splitlines()[1]


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


def test_the_harness_names_the_checked_file_in_a_command_that_runs_where_the_check_ran(tmp_path):
    """A student in their home folder checks "my work/attempt.py": the harness's message
    gives the ``ptlab grade`` command for that file, and the command works from there."""
    work = tmp_path / "my work"
    work.mkdir()
    shutil.copyfile(WRONG / "06_wrong_pdf_off_by_2.py", work / "attempt.py")
    ptlab = [sys.executable, "-m", "ptlab.cli"]
    run = subprocess.run([*ptlab, "exercise", "check", "6", "my work/attempt.py", "--json", "r.json"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stderr
    checks = {c["name"]: c["message"] for c in json.loads((tmp_path / "r.json").read_text())["checks"]}
    command = re.search(r"see the whole table with: ptlab (grade .*)\)$", checks["material harness"])
    assert command and command.group(1) == "grade 'my work/attempt.py':Lambertian", checks
    table = subprocess.run([*ptlab, *shlex.split(command.group(1))], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300)
    assert table.returncode == 1 and "chi-square" in table.stdout, table.stderr


@pytest.mark.parametrize("chinese", [False, True], ids=["en", "zh"])
def test_docs_shows_a_chapters_page_and_where_its_tutorial_is(chinese, capsys):
    from ptlab.exercises.pages import page, tutorial

    found = chapter(7)
    assert main(["exercise", "docs", "7", *(["--zh"] if chinese else [])]) == 0
    shown = capsys.readouterr().out
    assert shown.startswith(page(found, chinese).read_text(encoding="utf-8").rstrip("\n"))
    assert ("路径追踪" in shown) == chinese and "ptlab exercise check 7" in shown
    assert f"python {tutorial(found)} --out DIR" in shown and tutorial(found).is_file()
    assert main(["exercise", "docs", "7", "--path"]) == 0
    assert capsys.readouterr().out.strip() == str(page(found))


def test_docs_without_a_chapter_shows_the_list_and_start_points_to_docs(tmp_path, capsys):
    assert main(["exercise", "docs"]) == 0
    assert "| 10 |" in capsys.readouterr().out
    assert main(["exercise", "start", "6", str(tmp_path)]) == 0
    assert "ptlab exercise docs 6" in capsys.readouterr().out
    assert "ptlab exercise docs 6" in chapter(6).template.read_text()
    assert main(["exercise", "docs", "12"]) == 2
    assert "no such chapter" in capsys.readouterr().err


def test_docs_piped_into_a_reader_that_stops_early_is_no_error():
    """``ptlab exercise docs 7 | head -0``: the reader has closed the pipe before the page
    is written (the interpreter takes far longer to start than this takes to close it)."""
    process = subprocess.Popen([sys.executable, "-m", "ptlab.cli", "exercise", "docs", "7"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()
    error = process.stderr.read().decode()
    assert process.wait(timeout=60) == 0 and "Traceback" not in error, error
