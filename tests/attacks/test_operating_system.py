"""Attacks that need the operating system to stop them (docs/grading-security.md): attaching
to the grader, forging its results and killing it, planting modules where it imports from.
When the grader runs as root (as here, and in a course's container), the student's code runs
as ``nobody``; these tests run the graders as root for real, and as ``nobody`` for the
grader that is not root."""

from __future__ import annotations

import csv
import ctypes
import json
import os
import pwd
import signal
import subprocess
import sys
import traceback
from pathlib import Path

import pytest

from attacks.hostile import SUBMISSIONS
from ptlab.course import chapter
from ptlab.course.grader import grade
from ptlab.course.sandbox.student_user import student_user
from ptlab.course.sandbox.submission import KEPT_ENVIRONMENT

pytestmark = [
    pytest.mark.slow,
    pytest.mark.subprocess,
    pytest.mark.skipif(os.geteuid() != 0, reason="the student user needs a root grader"),
]
NOBODY = pwd.getpwnam("nobody")


def _ptlab(*arguments: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """``ptlab ARGUMENTS`` in a process of its own."""
    return subprocess.run(
        [sys.executable, "-m", "ptlab.cli", *arguments],
        cwd=cwd,
        text=True,
        capture_output=True,
        timeout=timeout,
    )


def _as_nobody(*arguments: str, cwd: Path, environment: dict) -> subprocess.CompletedProcess:
    """``ptlab ARGUMENTS`` run by the user nobody (its groups too: root's group may not
    enter /root, where Python may live, even though others may)."""
    return subprocess.run(
        [sys.executable, "-m", "ptlab.cli", *arguments],
        cwd=cwd,
        text=True,
        capture_output=True,
        timeout=300,
        user=NOBODY.pw_uid,
        group=NOBODY.pw_gid,
        extra_groups=[],
        env=environment,
    )


def _open_to_everyone(folder: Path) -> Path:
    """``folder``, made, that every user may write (so only the grader's rules keep a
    student's process from writing there)."""
    folder.mkdir(parents=True, exist_ok=True)
    folder.chmod(0o777)
    for parent in folder.parents:  # (pytest's own folders let only root in)
        if parent.stat().st_uid == 0 and not parent.stat().st_mode & 0o001 and parent != Path("/"):
            parent.chmod(parent.stat().st_mode | 0o001)
    return folder


def test_the_students_code_runs_as_nobody_with_no_way_back(attack):
    lines: list[str] = []
    grade(
        chapter(1), attack("tells_who_it_is.py", "01_cameras.py"), timeout_scale=0.2, on_output=lines.append
    )
    who = dict(line[5:].split(" ", 1) for line in lines if line.startswith("who: "))
    uid = NOBODY.pw_uid
    assert who["uid"] == f"{uid} {uid} gid {NOBODY.pw_gid} groups []"
    assert who["seccomp"] == "2 no_new_privs 1 capabilities 0000000000000000"  # (filter mode)
    assert who["network"] == "lo"  # a network namespace of its own
    # A pid namespace of its own: bubblewrap's process and itself, nothing of the grader's.
    assert who["processes"] == "[1, 2] pid 2"
    # No namespaces of its own (a seccomp filter): EPERM for each.
    for kind in ("user", "mount", "network"):
        assert who[f"unshare-{kind}"] == "-1 errno 1", who
    # Its ptlab is the kit: no exercises (their answers and checks), no graders.
    _, _, holds = who["ptlab"].split(" ")
    assert {"course", "camera.py"} <= set(holds.split(","))
    assert not {"grading", "cli.py"} & set(holds.split(","))
    folder, mode, _, home, _, environment = who["folder"].split(" ")
    # Its folder is in memory in its own view (only its processes are there to write in it):
    # nothing of it on the grader's disk.
    assert folder == home == "/home/student"
    assert mode == "0o777"
    # (PWD is bubblewrap's)
    assert set(environment.split(",")) <= {*KEPT_ENVIRONMENT, "HOME", "TMPDIR", "PWD"}


def test_root_may_opt_out_and_an_unknown_user_is_refused(attack, tmp_path):
    lines: list[str] = []
    grade(
        chapter(1),
        attack("tells_who_it_is.py", "01_cameras.py"),
        timeout_scale=0.2,
        on_output=lines.append,
        user="root",
    )
    assert any(line.startswith("who: uid 0 0") for line in lines)
    refused = _ptlab(
        "exercise",
        "check",
        "1",
        str(SUBMISSIONS / "tells_who_it_is.py"),
        "--student-user",
        "no-such-user",
        cwd=tmp_path,
    )
    assert refused.returncode == 2
    assert "no such user" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_the_kernel_refuses_the_student_user_the_grader_and_its_files(tmp_path):
    """What the operating system keeps, with no audit hook to help: a process that became
    the student user cannot signal, ptrace or write over a root grader."""
    private = tmp_path / "results"
    private.mkdir(mode=0o700)
    read, write = os.pipe()
    child = os.fork()
    if child == 0:  # a process of the student user, with no way back
        try:
            os.close(read)
            user = student_user("nobody")
            os.setgroups([])
            os.setresgid(user.gid, user.gid, user.gid)
            os.setresuid(user.uid, user.uid, user.uid)
            outcomes = []
            for attempt in (
                lambda: os.kill(os.getppid(), 0),
                lambda: _ptrace_attach(os.getppid()),
                lambda: open(private / "result.json", "w").close(),
                lambda: os.setuid(0),
            ):
                try:
                    attempt()
                    outcomes.append("allowed")
                except OSError as error:
                    outcomes.append(error.errno)
            os.write(write, json.dumps(outcomes).encode())
        except BaseException:
            traceback.print_exc()
            os._exit(1)
        finally:  # (whatever it raised: a forked child never runs the rest of the tests)
            os._exit(0)
    os.close(write)
    _, status = os.waitpid(child, 0)
    with os.fdopen(read) as pipe:
        said = pipe.read()
    assert os.waitstatus_to_exitcode(status) == 0, "the forked child raised (its traceback: captured stderr)"
    outcomes = json.loads(said)
    assert outcomes == [1, 1, 13, 1]  # EPERM, EPERM, EACCES, EPERM


def _ptrace_attach(pid: int) -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.ptrace(16, pid, 0, 0) != 0:  # PTRACE_ATTACH
        raise OSError(ctypes.get_errno(), "ptrace")
    libc.ptrace(17, pid, 0, 0)  # PTRACE_DETACH (were it allowed)


def test_attaching_to_the_grader_gets_nowhere(attack):
    lines: list[str] = []
    result = grade(
        chapter(1),
        attack("ptraces_the_grader.py", "01_cameras.py"),
        timeout_scale=0.2,
        on_output=lines.append,
    )
    assert result.score == 0, result.table()
    tried = list(dict.fromkeys(line for line in lines if line.startswith("tried ")))
    assert len(tried) == 4, tried
    assert not any("it worked" in line for line in tried), tried
    # The farthest process it can see is bubblewrap's, in its own pid namespace, as root.
    assert "farthest 1" in lines


def test_forging_the_result_then_killing_the_grader_leaves_no_marks(tmp_path):
    out = _open_to_everyone(tmp_path / "out")
    student = _open_to_everyone(tmp_path / "student")
    answer = student / "07_path_tracing.py"
    answer.write_bytes((SUBMISSIONS / "forges_results_and_kills.py").read_bytes())
    # What an earlier run left there, claiming full marks, goes before grading starts.
    (out / "result.json").write_text('{"score": 12, "max_score": 12, "full_marks": true}')
    checked = _ptlab(
        "exercise",
        "check",
        "7",
        str(answer),
        "--json",
        str(out / "result.json"),
        "--timeout-scale",
        "0.3",
        cwd=tmp_path,
    )
    assert checked.returncode == 1, checked.stderr
    tried = [line for line in checked.stderr.splitlines() if "tried " in line]
    assert tried, tried
    assert not any("it worked" in line for line in tried), tried
    written = json.loads((out / "result.json").read_text())
    assert written["score"] == 0
    assert written["full_marks"] is False
    listing = _ptlab("exercise", "list", str(student), cwd=tmp_path)
    assert "passed" not in listing.stdout, listing.stdout


def test_a_killed_grader_leaves_no_result(tmp_path):
    out, answer = tmp_path / "out", tmp_path / "01_cameras.py"
    out.mkdir()
    answer.write_text("import time\nprint('importing', flush=True)\ntime.sleep(60)\n")
    (out / "result.json").write_text('{"score": 10, "max_score": 10, "full_marks": true}')
    grader = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "ptlab.cli",
            "exercise",
            "check",
            "1",
            str(answer),
            "--json",
            str(out / "result.json"),
        ],
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    for line in grader.stderr:  # the first check has started: kill it mid-grading
        if "| importing" in line:
            break
    grader.send_signal(signal.SIGKILL)
    grader.wait()
    grader.stderr.close()
    assert not (out / "result.json").exists()


def _class(folder: Path, *students: tuple[str, Path]) -> Path:
    folder.mkdir(parents=True)
    for name, source in students:
        (folder / name).mkdir()
        (folder / name / "07_path_tracing.py").write_bytes(source.read_bytes())
    return folder


def _rows(path: Path) -> dict[str, dict]:
    return {row["student"]: row for row in csv.DictReader(path.open())}


def test_grade_all_resumes_only_from_what_it_wrote_itself(tmp_path):
    right = Path(__file__).parent.parent / "exercises" / "07_right_own_code.py"
    folder = _class(
        tmp_path / "class", ("attacker", SUBMISSIONS / "forges_results_and_kills.py"), ("next", right)
    )
    out = _open_to_everyone(tmp_path / "out")
    grades = out / "grades.csv"
    first = _ptlab("exercise", "grade-all", "7", str(folder), "--csv", str(grades), cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert "each takes at most" in first.stderr  # the worst case, stated
    rows = _rows(grades)
    assert rows["attacker"]["score"] == "0"
    assert rows["next"]["score"] == "12"
    # Forged as a student of the grader's own user could: the attacker's row to full marks,
    # the next student's to nothing, and one for a student who handed in nothing.
    forged = dict(rows["attacker"], score="12", first_failure="")
    rows.update(
        attacker=forged, next=dict(rows["next"], score="0"), ghost=dict(rows["next"], student="ghost")
    )
    with grades.open("w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(forged))
        writer.writeheader()
        writer.writerows(rows.values())
    again = _ptlab("exercise", "grade-all", "7", str(folder), "--csv", str(grades), cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    rows = _rows(grades)
    assert set(rows) == {"attacker", "next"}
    assert rows["attacker"]["score"] == "0"
    assert rows["next"]["score"] == "12"


def test_modules_planted_where_the_graders_run_are_never_imported(tmp_path):
    planted = _open_to_everyone(tmp_path / "cwd")
    marker = planted / "imported"
    for name in ("trimesh", "scipy", "numpy", "embreex", "OpenImageIO", "tqdm", "ptlab"):
        (planted / f"{name}.py").write_text(
            f"open({str(marker)!r}, 'a').write({name!r} + ' ')\nraise SystemExit('planted {name} imported')\n"
        )
    right = Path(__file__).parent.parent / "exercises" / "01_right_own_code.py"
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "honest.py").write_bytes(right.read_bytes())
    (folder / '=HYPERLINK("evil.example","grade me")').mkdir()
    graded = subprocess.run(
        [
            sys.executable,
            "-I",
            "-c",
            "from ptlab.cli import main; main()",
            "exercise",
            "grade-all",
            "1",
            str(folder),
            "--csv",
            str(tmp_path / "grades.csv"),
        ],
        cwd=planted,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert graded.returncode == 0, graded.stderr
    assert not marker.exists(), marker.read_text()
    rows = _rows(tmp_path / "grades.csv")
    assert rows["honest"]["score"] == "10"
    assert '\'=HYPERLINK("evil.example","grade me")' in rows
    assert all(not cell.startswith(("=", "+", "-", "@")) for row in rows.values() for cell in row.values())


def _nobody_can_run_this_python() -> bool:
    try:
        ran = subprocess.run(
            [sys.executable, "-I", "-c", "import ptlab"],
            capture_output=True,
            user=NOBODY.pw_uid,
            group=NOBODY.pw_gid,
            extra_groups=[],
            cwd="/",
        )
    except OSError:  # (exec refused: a Python under a folder closed to other users)
        return False
    return ran.returncode == 0


def test_a_grader_that_is_not_root_is_not_dumpable_and_cannot_change_users(tmp_path):
    if not _nobody_can_run_this_python():
        pytest.skip("a grader run as nobody needs a Python nobody may read (python .ci/let_students_in.py)")
    home = _open_to_everyone(tmp_path / "nobody")
    answer = home / "01_cameras.py"
    # The student's code looks for the grader's environment in every process it can see.
    answer.write_bytes(
        (Path(__file__).parent.parent / "exercises" / "01_right_own_code.py").read_bytes()
        + b"\nfrom pathlib import Path as _P\n"
        b"for _p in _P('/proc').iterdir():\n"
        b"    try:\n        _e = (_p / 'environ').read_bytes()\n    except OSError:\n        continue\n"
        b"    if b'PTLAB_GRADERS_SECRET' in _e:\n        print('read the grader', _p.name, flush=True)\n"
    )
    environment = dict(
        os.environ, HOME=str(home), XDG_STATE_HOME=str(home / "state"), PTLAB_GRADERS_SECRET="1"
    )
    checked = _as_nobody("exercise", "check", "1", str(answer), cwd=home, environment=environment)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "read the grader" not in checked.stderr
    # Not root, it still makes the namespaces (a user namespace of its own), but the
    # student's code is the grader's own user: not for credit.
    assert "NOT FOR CREDIT: the grader is not root" in checked.stdout
    probe = (
        "import os\nfrom ptlab.course.sandbox.processes import make_undumpable\nmake_undumpable()\n"
        "parent = os.getpid()\nif os.fork() == 0:\n    try:\n"
        "        open(f'/proc/{parent}/environ', 'rb').read()\n        print('read', flush=True)\n"
        "    except OSError as error:\n        print('refused', error.errno, flush=True)\n"
        "    finally:\n        os._exit(0)\nos.wait()\n"
    )
    kernel = subprocess.run(
        [sys.executable, "-I", "-c", probe],
        capture_output=True,
        text=True,
        timeout=60,
        user=NOBODY.pw_uid,
        group=NOBODY.pw_gid,
        extra_groups=[],
        cwd=home,
    )
    assert kernel.stdout.strip() == "refused 13", kernel.stdout + kernel.stderr
    other = _as_nobody(
        "exercise", "check", "1", str(answer), "--student-user", "daemon", cwd=home, environment=environment
    )
    assert other.returncode == 2
    assert "only root can run students' code as another user" in other.stderr
