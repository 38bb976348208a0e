"""The exercises: every chapter's grader against the library's answer, the untouched
exercise file and typical wrong answers; the grader's time limits; the command line."""

from __future__ import annotations

import hashlib
import json
import shutil
import time
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


@pytest.mark.parametrize("path", sorted(WRONG.glob("[0-9][0-9]_right_*.py")), ids=lambda p: p.stem)
def test_right_answers_of_the_students_own_get_full_marks(path):
    # Their functions are theirs (not the library's), and run in the student's process.
    result = grade(chapter(path.name[:2]), path)
    assert result.full_marks, result.table()


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


# -- a whole class: ptlab exercise grade-all -------------------------------------------------

def _class_folder(tmp_path) -> Path:
    """Four students: a right file, a wrong one in a folder, one that hangs on the single-ray
    checks and raises on the others, and a folder without an exercise file."""
    folder = tmp_path / "submissions"
    (folder / "bob").mkdir(parents=True)
    (folder / "dave").mkdir()
    shutil.copyfile(WRONG / "01_right_own_code.py", folder / "alice.py")
    shutil.copyfile(WRONG / "01_wrong_rows_up.py", folder / "bob" / "01_cameras.py")
    shutil.copyfile(WRONG / "01_hangs_or_raises.py", folder / "carol.py")
    (folder / "dave" / "notes.txt").write_text("I ran out of time")
    return folder


def test_grade_all_grades_each_student_alone_and_resumes(tmp_path, capsys):
    import csv

    folder, grades = _class_folder(tmp_path), tmp_path / "grades.csv"
    assert main(["exercise", "grade-all", "1", str(folder), "--csv", str(grades),
                 "--workers", "2", "--timeout-scale", "0.1"]) == 0
    assert "4 students" in capsys.readouterr().out
    rows = {row["student"]: row for row in csv.DictReader(grades.open())}
    assert set(rows) == {"alice", "bob", "carol", "dave"}
    assert rows["alice"]["score"] == "10" and rows["alice"]["first_failure"] == ""
    assert rows["alice"]["render"] == "2" and rows["alice"]["file"] == "alice.py"
    assert 0 < int(rows["bob"]["score"]) < 10 and rows["bob"]["file"] == "01_cameras.py"
    assert rows["bob"]["first_failure"].startswith("field of view: the top edge")
    assert rows["carol"]["score"] == "0" and "took longer than" in rows["carol"]["first_failure"]
    assert rows["dave"]["score"] == "0" and "no 01_cameras.py in the folder" in rows["dave"]["first_failure"]
    # Resuming: only the new student is graded (alice's broken file is not looked at again).
    (folder / "alice.py").write_text("def generate_rays(:\n")
    shutil.copyfile(WRONG / "01_right_own_code.py", folder / "erin.py")
    assert main(["exercise", "grade-all", "1", str(folder), "--csv", str(grades)]) == 0
    again = {row["student"]: row for row in csv.DictReader(grades.open())}
    assert again["alice"] == rows["alice"] and again["erin"]["score"] == "10"
    assert main(["exercise", "grade-all", "2", str(folder), "--csv", str(grades)]) == 2
    assert "columns are not chapter 2's" in capsys.readouterr().err


def test_a_grader_that_does_not_finish_costs_only_its_student(tmp_path):
    from ptlab.exercises.batch import Work, _Runner
    from ptlab.untrusted import ProcessGuard

    sleeper = tmp_path / "sleeper.py"
    sleeper.write_text("import time\ntime.sleep(3600)\n")
    runner = _Runner(chapter(1), timeout_scale=1.0, limit=2.0)
    with ProcessGuard() as guard:
        runner.guard = guard
        start = time.monotonic()
        row = runner.grade(Work("sleeper", sleeper))
    assert time.monotonic() - start < 15
    assert row["score"] == 0 and "did not finish in 2 s" in row["first_failure"]


# -- progress: where list looks --------------------------------------------------------------

def _graded(path: Path, score: int):
    from ptlab.exercises.grader import CheckResult, Grade
    results = [CheckResult("a", score, 10, score == 10, "", 0.0)]
    return Grade(1, "Cameras", str(path), results, hashlib.sha256(path.read_bytes()).hexdigest())


def test_list_finds_the_work_where_the_student_looks_and_says_where(tmp_path, monkeypatch, capsys):
    from ptlab.exercises.progress import remember

    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    homework, elsewhere = tmp_path / "course" / "hw", tmp_path / "elsewhere"
    elsewhere.mkdir()
    assert main(["exercise", "start", "1", str(homework)]) == 0
    remember(_graded(homework / "01_cameras.py", 10))
    capsys.readouterr()

    def listing() -> tuple[str, dict]:
        assert main(["exercise", "list"]) == 0
        lines = capsys.readouterr().out.splitlines()
        return lines[0], {line[:2]: line for line in lines[2:]}

    monkeypatch.chdir(elsewhere)                 # found in the folder start made
    where, rows = listing()
    assert str(homework.resolve()) in where and "1 record found" in where
    assert "passed (10/10)" in rows["01"] and "01_cameras.py" in rows["01"]
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "other-state"))
    monkeypatch.chdir(tmp_path / "course")       # found below the current folder
    where, rows = listing()
    assert "this folder and its subfolders" in where and "passed (10/10)" in rows["01"]
    (homework / "01_cameras.py").write_text("# changed\n")
    assert "10/10, file changed since" in listing()[1]["01"]
    monkeypatch.chdir(elsewhere)                 # nothing here, nothing remembered
    where, rows = listing()
    assert "no results recorded" in where and "passed" not in rows["01"]


def test_a_later_failure_replaces_a_pass_in_the_record(tmp_path):
    from ptlab.exercises.progress import read_record, remember

    answer = tmp_path / "01_cameras.py"
    answer.write_text("# a first version\n")
    remember(_graded(answer, 10))
    answer.write_text("# a second version\n")
    remember(_graded(answer, 4))
    entry = read_record(tmp_path)["01"]
    assert entry["score"] == 4 and entry["full_marks"] is False
    assert entry["sha256"] == hashlib.sha256(answer.read_bytes()).hexdigest()
