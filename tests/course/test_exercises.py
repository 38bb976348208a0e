"""The exercises: every chapter's grader against the library's answer, the untouched
exercise file, right answers of students' own and typical wrong answers; the grader's time
limits; the command line.

The right answers (``tests/exercises/NN_right_*.py``) are whole files; most wrong answers
are one of them with the mistake patched in (``tests/exercises/wrong_answers.toml``), which
``_wrong_answer_text`` applies, and the few written otherwise throughout are whole files
(``NN_wrong_*.py``)."""

from __future__ import annotations

import ast
import hashlib
import json
import re
import shlex
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from ptlab.cli import main
from ptlab.course import all_chapters, chapter
from ptlab.course.grader import grade

WRONG = Path(__file__).parents[1] / "exercises"
#: The wrong answers that are right answers with the mistake patched in, by name.
PATCHED = tomllib.loads((WRONG / "wrong_answers.toml").read_text(encoding="utf-8"))
CHAPTERS = all_chapters()
#: The grading seed of the tests whose verdicts rest on statistics (each grading otherwise
#: draws a fresh one): deterministic, and a false alarm at the checks' stated rates would
#: show on every run, not now and then.
GRADING_SEED = 25


def _ids(chapters):
    return [c.stem for c in chapters]


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("found", CHAPTERS, ids=_ids(CHAPTERS))
def test_the_library_answer_gets_full_marks(found, tmp_path):
    result = grade(found, found.solution, library_answer=True, seed=GRADING_SEED)
    assert result.full_marks, result.table()


@pytest.mark.subprocess
@pytest.mark.parametrize("found", CHAPTERS, ids=_ids(CHAPTERS))
def test_the_untouched_exercise_file_fails_every_check_clearly(found, tmp_path):
    copied = tmp_path / found.template.name  # as 'ptlab exercise start' copies it
    shutil.copyfile(found.template, copied)
    result = grade(found, copied)
    assert result.score == 0, result.table()
    requiring = {c.name for c in found.checks if c.requires}
    for check in result.results:
        assert "Traceback" not in check.message
        if check.message.startswith("not graded until "):  # (it builds on a check that failed)
            assert check.name in requiring, result.table()
        assert "not written yet" in check.message or "NotImplementedError" in check.message, result.table()


def _wrong_answers() -> list[str]:
    """The names of the typical wrong answers (``NN_wrong_what``), patched and whole."""
    return sorted([*PATCHED, *(path.stem for path in WRONG.glob("[0-9][0-9]_wrong_*.py"))])


def _right_answers():
    return sorted(WRONG.glob("[0-9][0-9]_right_*.py"))


def _wrong_answer_text(name: str) -> str:
    """The wrong answer ``name`` as a student's file: a whole file as it is, a patched one
    as its right answer with each ``old`` replaced by its ``new`` and the docstring its
    ``about``. A patch whose ``old`` is not in the right answer exactly once (the right
    answer changed since) fails the test that asked for it."""
    if name not in PATCHED:
        return (WRONG / f"{name}.py").read_text(encoding="utf-8")
    wrong = PATCHED[name]
    text = (WRONG / wrong["base"]).read_text(encoding="utf-8")
    for replacement in wrong["replace"]:
        found = text.count(replacement["old"])
        if found != 1:
            pytest.fail(
                f"{name}: the patch of {wrong['base']} no longer applies: these lines "
                f"are there {found} times, not once (update wrong_answers.toml):\n"
                f"{replacement['old']}"
            )
        text = text.replace(replacement["old"], replacement["new"])
    docstring = ast.parse(text).body[0]
    lines = text.splitlines(keepends=True)
    return f'"""{wrong["about"]}"""\n' + "".join(lines[docstring.end_lineno :])


def _expected(name: str) -> dict:
    """What the graders must say of the wrong answer ``name``: ``failures``, the checks it
    fails; ``hints``, phrases their messages hold; ``misleading``, phrases they must not.
    A whole file says them in EXPECTED_FAILURES, EXPECTED_HINTS and MISLEADING_HINTS."""
    if name in PATCHED:
        return PATCHED[name]
    namespace: dict = {}
    exec(compile(_wrong_answer_text(name), f"{name}.py", "exec"), namespace)
    return dict(
        failures=namespace["EXPECTED_FAILURES"],
        hints=namespace.get("EXPECTED_HINTS", {}),
        misleading=namespace.get("MISLEADING_HINTS", {}),
    )


def test_each_patched_wrong_answer_is_a_right_answer_of_its_chapter_with_lines_changed():
    # Fast, without grading: a right answer that changed shows here first.
    assert not set(PATCHED) & {path.stem for path in WRONG.glob("[0-9][0-9]_wrong_*.py")}
    for name, wrong in PATCHED.items():
        assert re.fullmatch(r"\d\d_wrong_\w+", name), name
        assert re.fullmatch(rf"{name[:2]}_right_\w+\.py", wrong["base"]), (name, wrong["base"])
        assert wrong["replace"], name
        assert all(r["old"] != r["new"] for r in wrong["replace"]), name
        assert set(wrong) <= {"base", "about", "failures", "hints", "misleading", "replace"}, name
        text = _wrong_answer_text(name)
        compile(text, f"{name}.py", "exec")
        assert ast.get_docstring(ast.parse(text)) == wrong["about"].strip()


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("name", _wrong_answers())
def test_typical_wrong_answers_fail_exactly_the_checks_meant_to_catch_them(name, tmp_path):
    """Each wrong answer fails the checks it names, and no other (a mistake is reported by
    the check that owns it); where it names hints, the messages say them (the essential
    words), and not the misleading ones."""
    expected = _expected(name)
    path = tmp_path / f"{name}.py"
    path.write_text(_wrong_answer_text(name), encoding="utf-8")
    result = grade(chapter(name[:2]), path, seed=GRADING_SEED)
    failed = {r.name for r in result.results if not r.passed}
    assert failed == set(expected["failures"]), result.table()
    messages = {r.name: r.message for r in result.results}
    for check, phrases in expected.get("hints", {}).items():
        for phrase in phrases:
            assert phrase in messages[check], (check, phrase, messages[check])
    for check, phrases in expected.get("misleading", {}).items():
        for phrase in phrases:
            assert phrase not in messages[check], (check, phrase, messages[check])


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("path", _right_answers(), ids=lambda p: p.stem)
def test_right_answers_of_the_students_own_get_full_marks_and_no_warning(path):
    """Right answers written into the exercise file as a student would (another sampling
    than the library's) get full marks: their functions are theirs (not the library's), and
    run in the student's process. The material harness warns of nothing: the exercise
    file's own ``__init__`` keeps float32 float32."""
    from ptlab.course.sandbox.child import import_file
    from ptlab.grading import check_material

    result = grade(chapter(path.name[:2]), path, seed=GRADING_SEED)
    assert result.full_marks, result.table()
    module = import_file(path)
    materials = [getattr(module, name)() for name in ("Lambertian", "GGXMetal") if hasattr(module, name)]
    if not materials:
        return  # (a right answer of a chapter without a material)
    material = materials[0]
    report = check_material(material, seed=0, samples=100_000)
    assert [c.verdict for c in report.checks] == ["pass"] * len(report.checks), str(report)


@pytest.mark.slow
@pytest.mark.subprocess
def test_an_answer_that_imports_a_moved_name_from_its_old_place_keeps_full_marks(tmp_path):
    # ``reflect`` lived in ptlab.vectors before ptlab.scattering gathered the formulas.
    source = (Path(__file__).parents[1] / "exercises" / "09_right_walter.py").read_text()
    assert "from ptlab.scattering import reflect" in source
    path = tmp_path / "09_microfacet.py"
    old, new = "from ptlab.scattering import reflect", "from ptlab.vectors import reflect"
    path.write_text(source.replace(old, new))
    result = grade(chapter(9), path, seed=GRADING_SEED)
    assert result.full_marks, result.table()


@pytest.mark.parametrize(("number", "name"), [(6, "Lambertian"), (9, "GGXMetal")])
def test_the_exercise_files_keep_material_parameters_in_float32(number, name):
    from ptlab.course.sandbox.child import import_file

    material = getattr(import_file(chapter(number).template), name)()
    parameter = material.albedo if number == 6 else material.f0
    assert parameter.dtype == np.float32


def test_every_chapter_has_a_wrong_answer_that_fails():
    covered = {int(name[:2]) for name in _wrong_answers()}
    assert covered == {c.number for c in CHAPTERS}


@pytest.mark.slow
@pytest.mark.subprocess
def test_code_that_hangs_or_raises_fails_its_check_and_grading_goes_on():
    result = grade(chapter(1), WRONG / "01_hangs_or_raises.py", timeout_scale=0.05)
    by_name = {r.name: r for r in result.results}
    assert "took longer than" in by_name["centre ray"].message  # the single-ray check hung
    # ... and the next checks still ran, each failing with the error and the student's line.
    assert "01_hangs_or_raises.py:" in by_name["unit directions"].message
    assert "ValueError: my bug with 500 rays" in by_name["unit directions"].message
    assert result.score == 0
    assert len(result.results) == len(chapter(1).checks)


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


@pytest.mark.subprocess
def test_check_prints_a_score_table_writes_json_and_list_shows_progress(tmp_path, capsys):
    answer = tmp_path / "01_cameras.py"
    shutil.copyfile(WRONG / "01_right_own_code.py", answer)
    assert main(["exercise", "check", "1", str(answer), "--json", str(tmp_path / "r.json")]) == 0
    table = capsys.readouterr().out
    assert "10/10" in table
    assert "full marks" in table
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["full_marks"]
    assert result["score"] == result["max_score"] == 10
    assert {c["name"] for c in result["checks"]} >= {"centre ray", "render"}
    assert main(["exercise", "list", str(tmp_path)]) == 0
    listing = capsys.readouterr().out
    assert "1 record found" in listing.splitlines()[0]
    assert "passed (10/10)" in listing.splitlines()[2]


@pytest.mark.subprocess
def test_check_exits_1_below_full_marks_and_2_for_user_errors(tmp_path, capsys):
    answer = tmp_path / "01_cameras.py"
    shutil.copyfile(chapter(1).template, answer)
    assert main(["exercise", "check", "1", str(answer)]) == 1
    capsys.readouterr()
    for arguments, message in [
        (["check", "99", str(answer)], "no such chapter"),
        (["check", "1", str(tmp_path / "missing.py")], "no such file"),
        (["start", "x"], "no such chapter"),
    ]:
        assert main(["exercise", *arguments]) == 2
        error = capsys.readouterr().err
        assert message in error
        assert error.count("\n") == 1


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_harness_names_the_checked_file_in_a_command_that_runs_where_the_check_ran(tmp_path):
    """A student in their home folder checks "my work/attempt.py": the harness's message
    gives the ``ptlab grade`` command for that file, and the command works from there."""
    work = tmp_path / "my work"
    work.mkdir()
    (work / "attempt.py").write_text(_wrong_answer_text("06_wrong_pdf_off_by_2"), encoding="utf-8")
    ptlab = [sys.executable, "-m", "ptlab.cli"]
    run = subprocess.run(
        [*ptlab, "exercise", "check", "6", "my work/attempt.py", "--json", "r.json"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 1, run.stderr
    checks = {c["name"]: c["message"] for c in json.loads((tmp_path / "r.json").read_text())["checks"]}
    command = re.search(r"see the whole table with: ptlab (grade .*)\)$", checks["material harness"])
    assert command, checks
    assert command.group(1) == "grade 'my work/attempt.py':Lambertian", checks
    table = subprocess.run(
        [*ptlab, *shlex.split(command.group(1))], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert table.returncode == 1, table.stderr
    assert "chi-square" in table.stdout, table.stderr


@pytest.mark.parametrize("chinese", [False, True], ids=["en", "zh"])
def test_docs_shows_a_chapters_page_and_where_its_tutorial_is(chinese, capsys):
    from ptlab.course.pages import page, tutorial

    found = chapter(7)
    assert main(["exercise", "docs", "7", *(["--zh"] if chinese else [])]) == 0
    shown = capsys.readouterr().out
    assert shown.startswith(page(found, chinese).read_text(encoding="utf-8").rstrip("\n"))
    assert ("路径追踪" in shown) == chinese
    assert "ptlab exercise check 7" in shown
    assert f"python {tutorial(found)} --out DIR" in shown
    assert tutorial(found).is_file()
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


@pytest.mark.subprocess
def test_docs_piped_into_a_reader_that_stops_early_is_no_error():
    """``ptlab exercise docs 7 | head -0``: the reader has closed the pipe before the page
    is written (the interpreter takes far longer to start than this takes to close it)."""
    process = subprocess.Popen(
        [sys.executable, "-m", "ptlab.cli", "exercise", "docs", "7"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    process.stdout.close()
    error = process.stderr.read().decode()
    assert process.wait(timeout=60) == 0, error
    assert "Traceback" not in error, error


# -- a whole class: ptlab exercise grade-all -------------------------------------------------


def _class_folder(tmp_path) -> Path:
    """Four students: a right file, a wrong one in a folder, one that hangs on the single-ray
    checks and raises on the others, and a folder without an exercise file."""
    folder = tmp_path / "submissions"
    (folder / "bob").mkdir(parents=True)
    (folder / "dave").mkdir()
    shutil.copyfile(WRONG / "01_right_own_code.py", folder / "alice.py")
    (folder / "bob" / "01_cameras.py").write_text(_wrong_answer_text("01_wrong_rows_up"), encoding="utf-8")
    shutil.copyfile(WRONG / "01_hangs_or_raises.py", folder / "carol.py")
    (folder / "dave" / "notes.txt").write_text("I ran out of time")
    return folder


@pytest.mark.slow
@pytest.mark.subprocess
def test_grade_all_grades_each_student_alone_and_resumes(tmp_path, capsys):
    import csv

    folder, grades = _class_folder(tmp_path), tmp_path / "grades.csv"
    assert (
        main(
            [
                "exercise",
                "grade-all",
                "1",
                str(folder),
                "--csv",
                str(grades),
                "--workers",
                "2",
                "--timeout-scale",
                "0.1",
            ]
        )
        == 0
    )
    assert "4 students" in capsys.readouterr().out
    rows = {row["student"]: row for row in csv.DictReader(grades.open())}
    assert set(rows) == {"alice", "bob", "carol", "dave"}
    assert rows["alice"]["score"] == "10"
    assert rows["alice"]["first_failure"] == ""
    assert rows["alice"]["render"] == "2"
    assert rows["alice"]["file"] == "alice.py"
    assert 0 < int(rows["bob"]["score"]) < 10
    assert rows["bob"]["file"] == "01_cameras.py"
    assert rows["bob"]["first_failure"].startswith("field of view: the top edge")
    assert rows["carol"]["score"] == "0"
    assert "took longer than" in rows["carol"]["first_failure"]
    assert rows["dave"]["score"] == "0"
    assert "no 01_cameras.py in the folder" in rows["dave"]["first_failure"]
    # Resuming: the new student is graded, and bob, whose file changed since; alice, carol
    # and dave keep the rows the grader wrote (carol's hanging file is not run again).
    (folder / "bob" / "01_cameras.py").write_text("def generate_rays(:\n")
    shutil.copyfile(WRONG / "01_right_own_code.py", folder / "erin.py")
    start = time.monotonic()
    assert main(["exercise", "grade-all", "1", str(folder), "--csv", str(grades)]) == 0
    assert time.monotonic() - start < 60
    again = {row["student"]: row for row in csv.DictReader(grades.open())}
    assert all(again[name] == rows[name] for name in ("alice", "carol", "dave"))
    assert again["erin"]["score"] == "10"
    assert again["bob"]["score"] == "0"
    assert "syntax error" in again["bob"]["first_failure"]
    assert main(["exercise", "grade-all", "2", str(folder), "--csv", str(grades)]) == 2
    assert "columns are not chapter 2's" in capsys.readouterr().err


@pytest.mark.subprocess
def test_a_grader_that_does_not_finish_costs_only_its_student(tmp_path):
    from ptlab.course.batch import Work, _Runner
    from ptlab.course.sandbox import ProcessGuard

    sleeper = tmp_path / "sleeper.py"
    sleeper.write_text("import time\ntime.sleep(3600)\n")
    runner = _Runner(chapter(1), timeout_scale=1.0, limit=2.0)
    with ProcessGuard() as guard:
        runner.guard = guard
        start = time.monotonic()
        row = runner.grade(Work("sleeper", sleeper))
    assert time.monotonic() - start < 15
    assert row["score"] == 0
    assert "did not finish in 2 s" in row["first_failure"]


# -- progress: where list looks --------------------------------------------------------------


def _graded(path: Path, score: int):
    from ptlab.course.grader import CheckResult, Grade

    results = [CheckResult("a", score, 10, score == 10, "", 0.0)]
    return Grade(1, "Cameras", str(path), results, hashlib.sha256(path.read_bytes()).hexdigest())


def test_list_finds_the_work_where_the_student_looks_and_says_where(tmp_path, monkeypatch, capsys):
    from ptlab.course.progress import remember

    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    homework, elsewhere = tmp_path / "course" / "hw", tmp_path / "elsewhere"
    elsewhere.mkdir()
    assert main(["exercise", "start", "1", str(homework)]) == 0
    remember(_graded(homework / "01_cameras.py", 10))
    capsys.readouterr()

    def listing(*options: str) -> tuple[str, dict]:
        assert main(["exercise", "list", *options]) == 0
        lines = capsys.readouterr().out.splitlines()
        return lines[0], {line[:2]: line for line in lines[2:]}

    monkeypatch.chdir(elsewhere)  # not by default: on a shared account, others' work is there
    where, rows = listing()
    assert "no results recorded" in where
    assert "--all also looks in the folders 'start' made" in where
    assert rows["01"].split()[-2:] != ["passed", "(10/10)"]
    where, rows = listing("--all")  # found in the folder start made
    assert str(homework.resolve()) in where
    assert "1 record found" in where
    assert "passed (10/10)" in rows["01"]
    assert "01_cameras.py" in rows["01"]
    assert main(["exercise", "list", "--forget", str(homework)]) == 0
    assert "forgot" in capsys.readouterr().out
    where, rows = listing("--all")  # forgotten
    assert "no results recorded" in where
    assert main(["exercise", "list", "--forget", str(homework)]) == 2
    assert "not a folder 'ptlab exercise start' remembers" in capsys.readouterr().err
    from ptlab.course.progress import state_file

    state_file().unlink()  # start's folders forgotten:
    monkeypatch.chdir(tmp_path / "course")  # found below the current folder
    where, rows = listing()
    assert "this folder and its subfolders" in where
    assert "passed (10/10)" in rows["01"]
    (homework / "01_cameras.py").write_text("# changed\n")
    assert "10/10, file changed since" in listing()[1]["01"]
    monkeypatch.chdir(elsewhere)  # nothing here, nothing remembered
    where, rows = listing()
    assert "no results recorded" in where
    assert "passed" not in rows["01"]


def test_a_later_failure_replaces_a_pass_in_the_record(tmp_path):
    from ptlab.course.progress import read_record, remember

    answer = tmp_path / "01_cameras.py"
    answer.write_text("# a first version\n")
    remember(_graded(answer, 10))
    answer.write_text("# a second version\n")
    remember(_graded(answer, 4))
    entry = read_record(tmp_path)["01"]["01_cameras.py"]
    assert entry["score"] == 4
    assert entry["full_marks"] is False
    assert entry["sha256"] == hashlib.sha256(answer.read_bytes()).hexdigest()


def test_replacing_materials_keeps_the_scenes_lights_sky_uvs_and_defaults():
    # Homework 5's scene has all four: point lights, a sky, a textured floor's uvs and its
    # own resolution; a render check that swaps in a student's material must keep them.
    import ptlab
    from ptlab.course.renders import replace_materials

    scene = ptlab.load_scene("games101-hw5")
    swapped = replace_materials(scene, lambda m: None if m.emission is not None else m)
    assert swapped.point_lights is not None
    assert scene.point_lights is not None
    np.testing.assert_array_equal(swapped.point_lights.positions, scene.point_lights.positions)
    assert swapped.sky is not None
    assert np.array_equal(swapped.sky.radiance, scene.sky.radiance)
    np.testing.assert_array_equal(swapped.uvs, scene.uvs)
    assert swapped.defaults == scene.defaults
