"""The exercise commands' outputs: a path that cannot be written is one line and exit 2,
before the work (a grading takes minutes, a class hours), with nothing written; ``list``
shows each chapter's best file; a failed render check's suggested command names the file.

The bad paths fail for root too (root ignores permissions): a folder that does not exist, a
regular file where a folder should be, a folder where the file should be, and /proc (where
nobody may create a file); a folder without write permission is tried as another user.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from test_exercises import _graded, _wrong_answer_text

from ptlab.cli import main
from ptlab.course import progress
from ptlab.course.inspect_command import graded_file, suggestion
from ptlab.course.messages import language
from ptlab.course.progress import RECORD, read_record, remember

#: A submission whose grading would take half a minute: a command that grades it before
#: checking its output path shows in the time it takes (and in what it prints).
SLOW = "import time\ntime.sleep(30)\n"
#: Seconds a refusal may take: imports and the parser, far from a grading.
REFUSED_WITHIN = 10.0
CASES = ["no such folder", "under a file", "a folder", "in /proc"]


def bad_output(tmp_path: Path, case: str, suffix: str) -> tuple[Path, str]:
    """A file path that cannot be written, and what the one line says about it."""
    (tmp_path / "a-file").write_text("not a folder\n")
    (tmp_path / f"a-folder{suffix}").mkdir(exist_ok=True)
    return {
        "no such folder": (tmp_path / "nowhere" / f"out{suffix}", "does not exist"),
        "under a file": (tmp_path / "a-file" / f"out{suffix}", "is not a folder"),
        "a folder": (tmp_path / f"a-folder{suffix}", "is a folder"),
        "in /proc": (Path(f"/proc/ptlab-out{suffix}"), "cannot write in /proc"),
    }[case]


def everything_in(tmp_path: Path) -> set[str]:
    """Every path below ``tmp_path`` (an output, a record, a temporary file left behind)."""
    return {str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*")}


def refused(capsys, argv: list[str], said: str, tmp_path: Path) -> None:
    """``ptlab *argv`` exits 2 at once with one line saying ``said``, printing and writing
    nothing else."""
    before = everything_in(tmp_path)
    start = time.monotonic()
    code = main(argv)
    seconds = time.monotonic() - start
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("ptlab: error: "), lines
    assert said in lines[0], lines
    assert seconds < REFUSED_WITHIN
    assert everything_in(tmp_path) == before


@pytest.fixture
def slow_answer(tmp_path) -> Path:
    path = tmp_path / "01_cameras.py"
    path.write_text(SLOW)
    return path


@pytest.mark.parametrize("case", CASES)
def test_check_refuses_a_json_it_cannot_write_before_grading(tmp_path, capsys, slow_answer, case):
    out, said = bad_output(tmp_path, case, ".json")
    refused(capsys, ["exercise", "check", "1", str(slow_answer), "--json", str(out)], said, tmp_path)
    assert not (tmp_path / RECORD).exists()  # (nothing graded, nothing recorded)


@pytest.mark.parametrize("case", CASES)
def test_inspect_refuses_a_json_it_cannot_write_before_tracing(tmp_path, capsys, case):
    answer = tmp_path / "07_path_tracing.py"
    answer.write_text(SLOW)
    out, said = bad_output(tmp_path, case, ".json")
    argv = ["exercise", "inspect", "7", str(answer), "--pixel", "1,1", "--json", str(out)]
    refused(capsys, argv, said, tmp_path)


@pytest.mark.parametrize("option", ["--csv", "--alike"])
@pytest.mark.parametrize("case", CASES)
def test_grade_all_refuses_an_output_it_cannot_write_before_grading(tmp_path, capsys, case, option):
    submissions = tmp_path / "class"
    submissions.mkdir()
    (submissions / "alice.py").write_text(SLOW)
    out, said = bad_output(tmp_path, case, ".csv")
    outputs = {"--csv": tmp_path / "grades.csv", "--alike": tmp_path / "alike.csv", option: out}
    argv = ["exercise", "grade-all", "1", str(submissions)]
    refused(capsys, [*argv, *(word for pair in outputs.items() for word in map(str, pair))], said, tmp_path)


def test_grade_all_refuses_a_private_state_it_cannot_write_before_grading(tmp_path, capsys, monkeypatch):
    # The grader's own record of what it wrote (ptlab.course.batch.Record) lives there.
    submissions = tmp_path / "class"
    submissions.mkdir()
    (submissions / "alice.py").write_text(SLOW)
    (tmp_path / "a-file").write_text("not a folder\n")
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "a-file" / "state"))
    argv = ["exercise", "grade-all", "1", str(submissions), "--csv", str(tmp_path / "grades.csv")]
    refused(capsys, argv, "XDG_STATE_HOME", tmp_path)


@pytest.mark.parametrize("case", ["under a file", "a file", "in /proc", "a folder for the file"])
def test_start_refuses_a_folder_it_cannot_write_in(tmp_path, capsys, case):
    (tmp_path / "a-file").write_text("not a folder\n")
    (tmp_path / "taken" / "01_cameras.py").mkdir(parents=True)
    folder, said = {
        "under a file": (tmp_path / "a-file" / "work", "is not a folder"),
        "a file": (tmp_path / "a-file", "is not a folder"),
        "in /proc": (Path("/proc/ptlab-work"), "cannot write in /proc"),
        "a folder for the file": (tmp_path / "taken", "is a folder"),
    }[case]
    refused(capsys, ["exercise", "start", "1", str(folder), "--force"], said, tmp_path)
    assert not (Path(os.environ["XDG_STATE_HOME"]) / "ptlab" / "exercise-folders.json").exists()


@pytest.mark.parametrize("case", ["under a file", "a file", "in /proc"])
def test_render_refuses_an_out_folder_it_cannot_write_in_before_rendering(tmp_path, capsys, case):
    answer = tmp_path / "03_whitted.py"
    answer.write_text(SLOW)
    (tmp_path / "a-file").write_text("not a folder\n")
    out, said = {
        "under a file": (tmp_path / "a-file" / "pictures", "is not a folder"),
        "a file": (tmp_path / "a-file", "is not a folder"),
        "in /proc": (Path("/proc/ptlab-pictures"), "cannot write in /proc"),
    }[case]
    refused(capsys, ["exercise", "render", "3", str(answer), "--out", str(out), "--quiet"], said, tmp_path)


@pytest.mark.subprocess
def test_check_refuses_a_json_in_a_folder_it_may_not_write(slow_answer):
    # Root may write anywhere: the command runs as nobody then (setpriv, util-linux).
    as_other = []
    if os.geteuid() == 0:
        if shutil.which("setpriv") is None:
            pytest.skip("root without setpriv cannot run the command as another user")
        as_other = ["setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups"]
    top = Path(tempfile.mkdtemp(prefix="ptlab-outputs-"))  # (a folder nobody can enter)
    try:
        top.chmod(0o755)
        answer, read_only = top / "01_cameras.py", top / "read-only"
        answer.write_text(SLOW)
        answer.chmod(0o644)
        read_only.mkdir(mode=0o555)
        read_only.chmod(0o555)
        command = [sys.executable, "-m", "ptlab.cli", "exercise", "check", "1", str(answer)]
        start = time.monotonic()
        ran = subprocess.run(
            [*as_other, *command, "--json", str(read_only / "result.json")],
            capture_output=True,
            text=True,
            cwd=top,
            timeout=60,
        )
        assert time.monotonic() - start < REFUSED_WITHIN + 5  # (+ a fresh interpreter's start)
        assert ran.returncode == 2, ran.stderr
        assert ran.stdout == ""
        said = f"--json {read_only / 'result.json'}: cannot write in {read_only}: Permission denied"
        assert ran.stderr.splitlines() == [f"ptlab: error: {said}"]
        assert list(read_only.iterdir()) == []
    finally:
        shutil.rmtree(top)


# -- list: each chapter's best file ---------------------------------------------------------


@pytest.fixture
def ticking_clock(monkeypatch) -> None:
    """Each record's time a minute after the one before (``remember`` stamps to the
    second: records made within one would tie)."""
    minutes = iter(range(60))
    monkeypatch.setattr(progress.time, "strftime", lambda _format: f"2025-09-01 10:{next(minutes):02d}:00")


def listed(capsys, folder: Path) -> str:
    """Chapter 1's row of ``ptlab exercise list folder``."""
    assert main(["exercise", "list", str(folder)]) == 0
    rows = {line[:2]: line for line in capsys.readouterr().out.splitlines()[2:]}
    return rows["01"]


def test_list_shows_the_best_file_not_the_last_checked(tmp_path, capsys, ticking_clock):
    full, half = tmp_path / "01_cameras.py", tmp_path / "01_second_try.py"
    full.write_text("# the answer that passed\n")
    half.write_text("# another try, checked later\n")
    remember(_graded(full, 10))
    remember(_graded(half, 5))
    assert set(read_record(tmp_path)["01"]) == {full.name, half.name}  # (both kept)
    row = listed(capsys, tmp_path)
    assert "passed (10/10)" in row
    assert f"{full.resolve()} (best of 2)" in row
    # A pass that no longer stands (its file changed) is not the best: the 5/10 that does is.
    full.write_text("# changed since\n")
    row = listed(capsys, tmp_path)
    assert "5/10 points" in row
    assert f"{half.resolve()} (best of 2)" in row
    # Checked again, each file's entry is replaced, not added to.
    remember(_graded(full, 10))
    assert set(read_record(tmp_path)["01"]) == {full.name, half.name}
    assert "passed (10/10)" in listed(capsys, tmp_path)


def test_list_shows_the_best_of_several_folders(tmp_path, capsys, ticking_clock):
    first, second = tmp_path / "monday", tmp_path / "tuesday"
    for folder, score in ((first, 10), (second, 4)):  # (the worse one checked last)
        folder.mkdir()
        (folder / "01_cameras.py").write_text(f"# {folder.name}\n")
        remember(_graded(folder / "01_cameras.py", score))
    row = listed(capsys, tmp_path)
    assert "passed (10/10)" in row
    assert "monday" in row
    assert "tuesday" not in row


def test_a_record_of_one_entry_per_chapter_still_reads(tmp_path):
    # Records written before a chapter held an entry per file.
    entry = dict(score=7, max_score=10, full_marks=False, file="01_cameras.py", sha256="0", when="2025")
    (tmp_path / RECORD).write_text(json.dumps({"01": entry}))
    assert read_record(tmp_path) == {"01": {"01_cameras.py": entry}}


# -- the command a failed render check suggests ----------------------------------------------


def test_the_suggested_command_names_the_graded_file_quoted_for_a_shell():
    library = np.zeros((6, 8, 3))
    student = library.copy()
    student[4, 5] = 1.0  # x 5, y 4
    assert "inspect 7 YOUR_FILE --pixel 5,4" in suggestion(7, student, library, 3)  # (no file known)
    with graded_file("my work/07_path_tracing.py"):
        line = suggestion(7, student, library, 3)
        with language("zh"):
            chinese = suggestion(7, student, library, 3)
    assert "ptlab exercise inspect 7 'my work/07_path_tracing.py' --pixel 5,4 --seed 3" in line
    assert "ptlab exercise inspect 7 'my work/07_path_tracing.py' --pixel 5,4 --seed 3" in chinese
    assert "YOUR_FILE" in suggestion(7, student, library, 3)  # (only inside the block)


@pytest.mark.subprocess
def test_a_failed_render_check_suggests_inspecting_the_file_that_was_checked(tmp_path, capsys):
    answer = tmp_path / "my whitted.py"
    answer.write_text(_wrong_answer_text("03_wrong_no_total_internal_reflection"), encoding="utf-8")
    out = tmp_path / "result.json"
    assert main(["exercise", "check", "3", str(answer), "--json", str(out), "--grading-seed", "1"]) == 1
    capsys.readouterr()
    render = next(c for c in json.loads(out.read_text())["checks"] if c["name"] == "render")
    assert f"ptlab exercise inspect 3 {shlex.quote(str(answer))} --pixel " in render["message"]
