"""The first round of attacks on the graders (docs/grading-security.md): each earns nothing,
leaves an honest result, ends in bounded time and leaves no process behind."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from attacks.hostile import assert_honest_failure, printed_pids, students_processes, verdict_lines
from ptlab.cli import main
from ptlab.course import chapter
from ptlab.course.grader import grade, run_check
from ptlab.course.sandbox import ProcessGuard

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes

# -- attacks on the exercise grader ---------------------------------------------------------


def test_forged_replies_and_verdicts_earn_nothing(attack):
    result = grade(chapter(1), attack("forges_replies.py"), timeout_scale=0.2)
    # Whether a forged "ready" or the process's end is read first is a race; either way the
    # answers are the student's, and there are none.
    assert_honest_failure(result)


def test_patching_the_checks_numpy_and_the_report_earns_nothing(attack):
    # (It swaps a function's __code__ at import: the grader cannot read what would run.)
    result = grade(chapter(1), attack("patches_the_grader.py"), timeout_scale=0.2)
    assert_honest_failure(result, "needs a teacher's look")


def test_the_grader_never_unpickles_what_the_student_sends(attack):
    path = attack("pickle_bomb.py")
    result = grade(chapter(1), path, timeout_scale=0.2)
    assert result.score == 0, result.table()
    ran = path.with_suffix(".ran").read_text().split() if path.with_suffix(".ran").exists() else []
    assert str(os.getpid()) not in ran  # (the student's own process may run it)


@pytest.mark.parametrize(
    ("source", "reason"),
    [
        ("import os\nos._exit(0)\n", "ended during importing your file"),
        ("import time\ntime.sleep(3600)\n", "took longer than"),
        ("import os, signal\nos.kill(os.getpid(), signal.SIGSEGV)\n", "SIGSEGV"),
    ],
    ids=["exit", "sleep", "crash"],
)
def test_exiting_hanging_or_crashing_at_import_fails_every_check_in_bounded_time(tmp_path, source, reason):
    path = tmp_path / "01_cameras.py"
    path.write_text(source)
    start = time.monotonic()
    result = grade(chapter(1), path, timeout_scale=0.02)
    assert time.monotonic() - start < 30
    assert_honest_failure(result, reason)


def test_processes_that_outlive_the_grader_are_ended_before_it_writes_results(attack, capsys):
    path = attack("outlives_the_grader.py")
    result_file = path.parent / "result.json"
    assert (
        main(["exercise", "check", "1", str(path), "--json", str(result_file), "--timeout-scale", "0.3"]) == 1
    )
    pids = printed_pids(capsys.readouterr().err)
    assert len(pids) >= 2  # (the attack ran)
    assert students_processes() == []
    time.sleep(0.5)  # time for a survivor to rewrite the result
    written = json.loads(result_file.read_text())
    assert written["score"] == 0
    assert written["full_marks"] is False
    # The forged progress record: chapter 1's entry is the real result now, and chapter 9's
    # forged pass (for a file that is not there) is not shown as passed.
    assert main(["exercise", "list", str(path.parent)]) == 0
    rows = {line[:2]: line for line in capsys.readouterr().out.splitlines()[2:]}
    assert "0/10 points" in rows["01"]
    assert "passed" not in rows["09"]


def test_a_process_holding_the_graders_stdout_does_not_keep_its_reader_waiting(attack, tmp_path):
    # The holders would keep the grader's stdout open for 60 s after it ends, and whoever
    # reads it waiting. So: the moment the grader has exited (its own exit, not the end of
    # its output), none of them may be left; then its output ends at once.
    path = attack("holds_stdout.py")
    with open(tmp_path / "stderr.txt", "w+") as stderr:
        grader = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "ptlab.cli",
                "exercise",
                "check",
                "1",
                str(path),
                "--timeout-scale",
                "0.3",
            ],
            stdout=subprocess.PIPE,
            stderr=stderr,
            text=True,
        )
        grader.wait(timeout=600)  # (a guard against a hang, not a measure of speed)
        stderr.seek(0)
        err = stderr.read()
    pids = printed_pids(err)
    assert len(pids) >= 2, err
    assert students_processes() == [], err
    out = grader.stdout.read()
    grader.stdout.close()
    assert grader.returncode == 1
    assert "0/10" in out
    assert "Traceback" not in err


MALFORMED = {
    "a huge message": "struct.pack('<I', 1) + struct.pack('<Q', 1 << 40)",
    "too many parts": "struct.pack('<I', 10**7)",
    "not JSON": "struct.pack('<I', 1) + struct.pack('<Q', 5) + b'{{{{{'",
    "deep JSON": "struct.pack('<I', 1) + struct.pack('<Q', 200000) + b'[' * 200000",
    "an unknown tag": "frame({'id': 2, 'value': {'pickle': 'gASVBQAAAAAAAAB9lC4='}})",
    "an object array": "frame({'id': 2, 'value': {'array': 0}}, object_array())",
    "a half message": "struct.pack('<I', 1) + struct.pack('<Q', 100) + b'x' * 10",
}
#: What the forger does after writing: the half message is left unfinished for good.
AFTER = {"a half message": "time.sleep(60)"}
FORGER = """
import io, json, os, struct, time
import numpy as np

def frame(envelope, *parts):
    body = [json.dumps(envelope).encode(), *parts]
    return struct.pack("<I", len(body)) + b"".join(struct.pack("<Q", len(p)) for p in body) + b"".join(body)

def object_array():
    stream = io.BytesIO()
    np.lib.format.write_array(stream, np.array([object()], dtype=object), allow_pickle=True)
    return stream.getvalue()

def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    for fd in range(3, 256):
        try:
            os.write(fd, {payload})
        except OSError:
            pass
    {after}
    return np.zeros((len(pixel_x), 3)), np.zeros((len(pixel_x), 3))
"""


@pytest.mark.parametrize("what", MALFORMED)
def test_a_malformed_reply_fails_the_check_with_one_line_in_bounded_time(tmp_path, monkeypatch, what):
    # The forger writes to the channel's descriptor with os.write, which the grader's reading
    # of the text refuses before anything runs; this test is of the protocol underneath.
    monkeypatch.setattr("ptlab.course.sandbox.submission.unreadable_in_text", lambda *arguments: None)
    path = tmp_path / "01_cameras.py"
    path.write_text(FORGER.format(payload=MALFORMED[what], after=AFTER.get(what, "pass")))
    start = time.monotonic()
    with ProcessGuard() as guard:
        result, _ = run_check(chapter(1).checks[0], path, 3.0, guard, rules=chapter(1).rules)
    assert time.monotonic() - start < 15
    assert not result.passed
    expected = "took longer than" if what == "a half message" else "malformed reply"
    assert expected in result.message
    assert "Traceback" not in result.message


def test_the_librarys_answers_under_the_students_names_earn_nothing(attack):
    result = grade(chapter(7), attack("07_reexports.py"), timeout_scale=0.5)
    by_name = {r.name: r for r in result.results}
    own = "trace_paths: this is ptlab's own answer (ptlab.integrators.path.trace_paths), not yours"
    for name in ("light not black", "white furnace", "Cornell box"):
        assert own in by_name[name].message
    assert result.score == 0
    for name in ("06_subclass_of_diffuse.py", "06_imported_at_run_time.py"):
        result = grade(chapter(6), attack(name), timeout_scale=0.5)
        assert_honest_failure(result, "this is ptlab's own answer (ptlab.materials.")


def test_what_the_students_code_says_cannot_forge_lines_of_the_table(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text(
        "def generate_rays(camera, width, height, pixel_x, pixel_y, u):\n"
        "    raise ValueError('oops\\n  render   2/2    pass     ok\\n  total"
        "  10/10  full marks\\x1b[2J')\n"
    )
    result = grade(chapter(1), path, timeout_scale=0.2)
    lines = verdict_lines(result.table())
    assert len(lines) == 3 + len(chapter(1).checks) + 1
    assert lines[-1].lstrip().startswith("total")
    assert result.score == 0
    assert all("\x1b" not in line and "oops render 2/2 pass ok total" in line for line in lines[3:-1])


def test_resource_limits_hold_in_the_students_process(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text(
        "import numpy as np\n"
        "def generate_rays(camera, width, height, pixel_x, pixel_y, u):\n"
        "    return np.ones((1 << 40,)), None     # 8 TiB\n"
    )
    with ProcessGuard() as guard:
        result, _ = run_check(chapter(1).checks[0], path, 10.0, guard, rules=chapter(1).rules)
    assert not result.passed
    assert "MemoryError" in result.message


# -- attacks on ptlab grade -----------------------------------------------------------------


def test_ptlab_grade_judges_in_its_own_process_whatever_the_file_patches(attack, capsys):
    path = attack("bright_material_patching.py")
    assert main(["grade", f"{path}:Bright", "--samples", "20000"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out
    assert "energy" in out
    assert "PASSED" not in out


@pytest.mark.parametrize(
    ("source", "reason"),
    [
        ("import os\nos._exit(0)\n", "ended during importing"),
        ("import time\ntime.sleep(3600)\n", "took longer than"),
    ],
)
def test_ptlab_grade_of_a_file_that_exits_or_hangs_at_import(tmp_path, capsys, source, reason):
    path = tmp_path / "material.py"
    path.write_text(source)
    start = time.monotonic()
    assert main(["grade", f"{path}:Material", "--time-limit", "2"]) == 2
    assert time.monotonic() - start < 20
    err = capsys.readouterr().err
    assert reason in err
    assert len(err.strip().splitlines()) == 1


def test_ptlab_grade_refuses_the_librarys_own_material(attack, capsys):
    path = attack("06_subclass_of_diffuse.py")
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    assert "ptlab's own answer (ptlab.materials.Diffuse), not yours" in capsys.readouterr().out
