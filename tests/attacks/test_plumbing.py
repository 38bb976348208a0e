"""Attacks on what the graders print and read around the checks (docs/grading-security.md):
file names and printed output that forge or rewrite the table's lines, CSV cells that a
spreadsheet runs, grade-all's rows lost to names that collide or hung on a FIFO, a fork
bomb that costs a student graded at the same time, a closed pipe that turns a failure into
exit code 0, and the machine a student's process may look at."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from ast import literal_eval
from pathlib import Path

import pytest

from attacks.hostile import NOT_FOR_CREDIT_LINES, SUBMISSIONS, verdict_lines
from ptlab.course import chapter
from ptlab.course.batch import find_work, safe_cell
from ptlab.course.grader import grade
from ptlab.course.sandbox.channel import Channel
from ptlab.course.sandbox.sandbox import SCRATCH_BYTES, python_prefixes
from ptlab.course.sandbox.shown import shown

RIGHT_01 = Path(__file__).parent.parent / "exercises" / "01_right_own_code.py"
FORGED = "  total  10/10  full marks"
ROOT = pytest.mark.skipif(os.geteuid() != 0, reason="the student user needs a root grader")


def _ptlab(*arguments: str, cwd: Path, timeout: float = 300, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "ptlab.cli", *arguments],
        cwd=cwd,
        text=True,
        timeout=timeout,
        **({"stdout": subprocess.PIPE, "stderr": subprocess.PIPE} | kwargs),
    )


def _hidden(text: str) -> list[str]:
    """The characters of ``text`` a terminal could act on, but the newlines between lines."""
    return [c for c in text.replace("\n", "") if c != shown(c)]


# -- 6, 7: what the grader prints ---------------------------------------------------------


def test_shown_escapes_every_character_a_terminal_acts_on_and_nothing_else():
    assert shown("a\nb\r\x1b[2K\x07\u202e\u2028\x85") == "a\\nb\\r\\x1b[2K\\x07\\u202e\\u2028\\x85"
    assert shown("06_漫反射 é.py  tab") == "06_漫反射 é.py  tab"  # printable text is left alone
    assert shown(shown("x\x1by")) == shown("x\x1by")


def test_relayed_output_is_shown_one_line_at_a_time(tmp_path):
    read, write = os.pipe()
    lines: list[str] = []
    channel = Channel(os.open(os.devnull, os.O_WRONLY), os.open(os.devnull, os.O_RDONLY), read, lines.append)
    os.write(write, b"\x1b[1A\x1b[2K\r" + FORGED.encode() + b"\r\nsecond\rline\n")
    os.close(write)
    channel.close()
    assert lines == ["\\x1b[1A\\x1b[2K\\r" + FORGED, "second\\rline"]


def test_an_output_relay_that_raises_stops_relaying_not_grading(tmp_path):
    read, write = os.pipe()
    calls: list[str] = []

    def gone(line: str) -> None:
        calls.append(line)
        raise BrokenPipeError

    channel = Channel(os.open(os.devnull, os.O_WRONLY), os.open(os.devnull, os.O_RDONLY), read, gone)
    os.write(write, b"one\ntwo\nthree")
    os.close(write)
    channel.close()  # (raised before: the pipes stayed open and the folder was kept)
    assert calls == ["one"]
    assert channel.output_fd is None


@pytest.mark.subprocess
def test_a_file_name_cannot_forge_lines_of_the_table(tmp_path):
    forged = FORGED.replace("/", "\u2215")  # (a file name holds no "/", but one that looks like it)
    path = tmp_path / f"x\n{forged}\n\x1b[2K.py"
    path.write_text("raise SystemExit('no')\n")
    result = grade(chapter(1), path, timeout_scale=0.2)
    table = result.table()
    lines = verdict_lines(table)
    assert result.score == 0
    assert len(table.splitlines()) == len(result.results) + 4 + NOT_FOR_CREDIT_LINES, table
    assert len(lines) == len(result.results) + 4, table  # title, blank, header, total
    assert [line for line in lines if line.lstrip().startswith("total")] == [lines[-1]]
    assert "full marks" not in lines[-1]
    assert _hidden(table) == []
    assert f"x\\n{forged}\\n\\x1b[2K.py" in table.splitlines()[0]


@pytest.mark.slow
@pytest.mark.subprocess
def test_printed_escapes_reach_the_terminal_only_as_text(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_bytes((SUBMISSIONS / "plumbing_rewrites_the_terminal.py").read_bytes())
    checked = _ptlab("exercise", "check", "1", str(path), "--timeout-scale", "0.2", cwd=tmp_path)
    assert checked.returncode == 1
    assert _hidden(checked.stdout) == []
    assert _hidden(checked.stderr) == []
    forged = [line for line in checked.stderr.splitlines() if "full marks" in line]
    assert forged, checked.stderr
    assert all(line.startswith("    | ") for line in forged), checked.stderr
    # The verdict: the table's last line, every check failed, the import's message one line.
    verdict = verdict_lines(checked.stdout)[-1]
    assert verdict.split()[:2] == ["total", "0/10"]
    assert "full marks" not in verdict


# -- 7: CSV cells -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "value",
    ["=1+1", ' =HYPERLINK("x")', "\t=1", "\r=1", "-2+3", "@SUM(A1)", "\uff1d1+1", "  +1", "\n=1"],
)
def test_no_cell_a_spreadsheet_reads_as_a_formula(value):
    cell = safe_cell(value)
    assert not cell.lstrip().startswith(("=", "+", "-", "@", "\uff1d", "\uff0b", "\uff0d", "\uff20"))
    assert _hidden(cell) == []
    assert "\n" not in cell
    assert cell.lstrip("'").lstrip() == shown(value).lstrip()
    assert safe_cell(cell) == cell


def test_a_cell_keeps_one_line_and_plain_text():
    assert safe_cell('a\nb,"c"\x1b[2K') == 'a\\nb,"c"\\x1b[2K'
    assert safe_cell("alice") == "alice"
    assert safe_cell(12) == "12"
    out = io.StringIO()
    csv.writer(out).writerow([safe_cell("first\nsecond"), safe_cell("x\r\ny")])
    assert len(out.getvalue().splitlines()) == 1


# -- 8, 9: grade-all's rows -----------------------------------------------------------------


def _class(tmp_path: Path) -> Path:
    folder = tmp_path / "class"
    folder.mkdir()
    right = RIGHT_01.read_bytes()
    (folder / "alice.py").write_bytes(right)
    (folder / "alice").mkdir()
    (folder / "alice" / "01_cameras.py").write_bytes(right)
    (folder / "Bob.py").write_bytes(right)
    (folder / "bob.py").write_bytes(right)
    (folder / "carol.").mkdir()
    (folder / "carol." / "01_cameras.py").write_bytes(right)
    (folder / "carol.py").write_bytes(right)
    (folder / "e\u0301mile.py").write_bytes(right)  # (e + a combining accent)
    (folder / "\u00e9mile.py").write_bytes(right)  # (é in one code point)
    (folder / "=x.py").write_bytes(right)
    (folder / "'=x.py").write_bytes(right)
    (folder / "dave.py").write_bytes(right)
    os.mkfifo(folder / "erin.py")
    (folder / "frank").mkdir()
    os.mkfifo(folder / "frank" / "01_cameras.py")
    (folder / "gina").mkdir()
    (folder / "gina" / "01_cameras.py").write_text("raise SystemExit('not done')\n")
    os.mkfifo(folder / "gina" / "helper.py")
    return folder


def test_names_that_collide_each_get_a_row_that_says_so(tmp_path):
    work = find_work(_class(tmp_path), chapter(1))
    students = [w.student for w in work]
    assert len(students) == len(set(students)) == 17 - 2 - 1  # entries, but gina's and frank's files
    by_entry = {w.entry: w for w in work}
    for entry in ("alice.py", "alice/", "Bob.py", "bob.py", "carol./", "carol.py", "=x.py", "'=x.py"):
        assert by_entry[entry].file is None, entry
        assert "ambiguous" in by_entry[entry].problem, entry
    accented = [w for w in work if w.entry.endswith("mile.py")]
    assert len(accented) == 2
    assert all("ambiguous" in w.problem for w in accented)
    assert by_entry["dave.py"].file is not None
    assert by_entry["dave.py"].student == "dave"
    assert "not a regular file (a FIFO)" in by_entry["erin.py"].problem
    assert "not a regular file (a FIFO)" in by_entry["frank/"].problem
    assert by_entry["gina/"].file is not None


@pytest.mark.slow
@pytest.mark.subprocess
def test_grade_all_grades_what_it_can_and_a_fifo_hangs_nothing(tmp_path):
    folder = _class(tmp_path)
    for name in (
        "alice.py",
        "Bob.py",
        "bob.py",
        "carol.py",
        "e\u0301mile.py",
        "\u00e9mile.py",
        "=x.py",
        "'=x.py",
    ):
        (folder / name).write_text("raise SystemExit('not graded: ambiguous')\n")
    (folder / "dave.py").write_text("raise SystemExit('not done')\n")
    grades = tmp_path / "grades.csv"
    start = time.monotonic()
    graded = _ptlab(
        "exercise",
        "grade-all",
        "1",
        str(folder),
        "--csv",
        str(grades),
        "--timeout-scale",
        "0.2",
        cwd=tmp_path,
        timeout=240,
    )
    assert graded.returncode == 0, graded.stderr
    assert time.monotonic() - start < 200
    rows = list(csv.DictReader(grades.open(encoding="utf-8")))
    assert len(rows) == 14
    assert len({row["student"] for row in rows}) == 14
    assert sum("ambiguous" in row["first_failure"] for row in rows) == 10
    assert {row["student"]: row["score"] for row in rows}["dave"] == "0"
    assert all(not cell.lstrip().startswith(("=", "+", "-", "@")) for row in rows for cell in row.values())


# -- 10: students graded at the same time ------------------------------------------------------


@ROOT
@pytest.mark.slow
@pytest.mark.subprocess
def test_a_fork_bomb_costs_a_student_graded_at_the_same_time_nothing(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "a_bomb.py").write_bytes((SUBMISSIONS / "plumbing_fork_bomb.py").read_bytes())
    # An honest student whose process starts a thread a few seconds after it started (a
    # stand-in for any slow file whose code uses threads or processes).
    (folder / "b_honest.py").write_bytes(
        RIGHT_01.read_bytes() + b"\nimport threading, time\ntime.sleep(6)\n"
        b"_worker = threading.Thread(target=sum, args=([1, 2],))\n_worker.start()\n_worker.join()\n"
    )
    grades = tmp_path / "grades.csv"
    graded = _ptlab(
        "exercise", "grade-all", "1", str(folder), "--csv", str(grades), "--workers", "2", cwd=tmp_path
    )
    assert graded.returncode == 0, graded.stderr
    rows = {row["student"]: row for row in csv.DictReader(grades.open())}
    assert rows["a_bomb"]["score"] == "0"
    assert rows["b_honest"]["score"] == "10", rows["b_honest"]


# -- 11: a closed pipe --------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_closed_pipe_never_turns_a_failure_into_success(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text("for _ in range(20000):\n    print('x' * 100)\nraise SystemExit('no')\n")
    read, write = os.pipe()
    os.close(read)  # `| true`: the reader is gone before anything is written
    try:
        checked = _ptlab(
            "exercise",
            "check",
            "1",
            str(path),
            "--timeout-scale",
            "0.2",
            "--json",
            str(tmp_path / "r.json"),
            cwd=tmp_path,
            timeout=120,
            stdout=write,
            stderr=write,
        )
    finally:
        os.close(write)
    assert checked.returncode == 1
    assert json.loads((tmp_path / "r.json").read_text())["score"] == 0


WRONG_MATERIAL = """
import numpy as np

class M:
    def eval(self, wo, wi, n):
        return np.full(wo.shape, 5.0)

    def pdf(self, wo, wi, n):
        return np.full(len(wo), 1 / (2 * np.pi))

    def sample(self, wo, n, u):
        return n.copy()
"""


@pytest.mark.subprocess
def test_a_closed_pipe_after_ptlab_grade_keeps_the_failure(tmp_path):
    path = tmp_path / "material.py"
    path.write_text(WRONG_MATERIAL)
    read, write = os.pipe()
    os.close(read)
    try:
        graded = _ptlab(
            "grade", f"{path}:M", "--samples", "1000", cwd=tmp_path, timeout=120, stdout=write, stderr=write
        )
    finally:
        os.close(write)
    assert graded.returncode == 1


# -- 13: what a student's process may look at ----------------------------------------------------


@pytest.mark.subprocess
def test_the_students_process_sees_only_its_folder_and_the_installed_files(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_bytes((SUBMISSIONS / "plumbing_looks_around.py").read_bytes())
    lines: list[str] = []
    grade(chapter(1), path, timeout_scale=0.2, on_output=lines.append)
    told = {line.split(": ")[1]: line.split(": ", 2)[2] for line in lines if line.startswith("tell: ")}
    assert told["processes"] == "[1, 2]", told  # bubblewrap's and its own: no grader
    assert str(tmp_path) not in "\n".join(lines)  # no path of the grader's, in any command line
    assert "pytest" not in told["command lines"]
    # Its own /tmp, empty but for the folders above a Python that lies in /tmp (a virtual
    # environment made there): its own folder is /home/student.
    python_in_tmp = {prefix.split("/")[2] for prefix in python_prefixes() if prefix.startswith("/tmp/")}
    assert set(literal_eval(told["/tmp"])) <= python_in_tmp
    assert set(literal_eval(told["/etc"])) <= {"ld.so.cache", "localtime", "nsswitch.conf"}
    assert told["/etc/passwd"] == "refused: FileNotFoundError"
    python = {prefix.split("/")[1] for prefix in python_prefixes()}
    assert set(literal_eval(told["/"])) <= {"bin", "dev", "etc", "home", "lib", "lib64", "proc", "sbin"} | {
        "tmp",
        "usr",
        "var",
        *python,
    }
    assert "01_cameras.py" in literal_eval(told["own folder"])
    assert int(told["own status"]) > 0
    assert int(told["numpy's folder"]) > 0


@pytest.mark.subprocess
def test_filling_every_writable_place_stops_at_its_size_and_leaves_nothing(tmp_path):
    before = set(Path(tempfile.gettempdir()).glob("ptlab-student-*"))
    path = tmp_path / "01_cameras.py"
    path.write_bytes((SUBMISSIONS / "plumbing_fills_the_disk.py").read_bytes())
    lines: list[str] = []
    result = grade(chapter(1), path, timeout_scale=0.2, on_output=lines.append)
    assert result.score == 0
    filled = [line for line in lines if line.startswith("filled ")]
    assert filled, lines
    for line in filled:  # each place is a file system in memory of SCRATCH_BYTES: then ENOSPC
        megabytes, errno = int(line.split(": ")[1].split(" ")[0]), int(line.rsplit(" ", 1)[1])
        assert megabytes <= SCRATCH_BYTES >> 20
        assert errno == 28, line
    # Nothing of it on the grader's disk (a folder of another grading may come and go).
    new = set(Path(tempfile.gettempdir()).glob("ptlab-student-*")) - before
    assert not [folder for folder in new if (folder / "fill0").exists()]
