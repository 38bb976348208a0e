"""Student code cannot fool the graders (``ptlab.untrusted``).

Every attack in ``tests/attacks/`` ends without marks it did not earn, with an honest JSON,
in bounded time, with no process left behind and no traceback. Then the pieces: the reply
schema, the pipes, the subreaper, and what counts as ptlab's own answer.
"""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ptlab.cli import main
from ptlab.exercises import chapter
from ptlab.exercises.grader import grade, run_check
from ptlab.untrusted import ProcessGuard, StudentError, Submission, SubmissionFailed
from ptlab.untrusted.channel import Channel, ChannelError, ChannelTimeoutError
from ptlab.untrusted.ownership import library_answer
from ptlab.untrusted.plain_data import Decoder, Encoder, MalformedError, UnsendableError
from ptlab.untrusted.processes import descendants, process_table

ATTACKS = Path(__file__).parent / "attacks"
RIGHT_CAMERA = Path(__file__).parent / "exercises" / "01_right_own_code.py"


def _is_multiprocessing_helper(pid: int) -> bool:
    """The fork server and resource tracker that the graders share for the whole session."""
    try:
        command = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return True        # gone meanwhile
    return b"multiprocessing.forkserver" in command or b"multiprocessing.resource_tracker" in command


@pytest.fixture(autouse=True)
def nothing_left_behind():
    """After every test: no process below this one but multiprocessing's own helpers."""
    yield
    below = descendants({os.getpid()}, process_table(alive_only=True)) - {os.getpid()}
    left = [pid for pid in below if not _is_multiprocessing_helper(pid)]
    assert left == [], [Path(f"/proc/{pid}/cmdline").read_bytes()[:200] for pid in left]


@pytest.fixture
def attack(tmp_path):
    """Copy an attack into a fresh folder (where it writes its markers) and return its path."""
    def copy(name: str) -> Path:
        shutil.copyfile(ATTACKS / name, tmp_path / name)
        return tmp_path / name
    return copy


def alive(pids) -> list[int]:
    """Those of ``pids`` that are still running (not ended, not zombies)."""
    running = process_table(alive_only=True)
    return [pid for pid in pids if pid in running]


def assert_honest_failure(result, reason: str = "") -> None:
    assert result.score == 0, result.table()
    for check in result.results:
        assert not check.passed and reason in check.message, result.table()
        assert "Traceback" not in check.message


# -- attacks on the exercise grader ---------------------------------------------------------

def test_forged_replies_and_verdicts_earn_nothing(attack):
    result = grade(chapter(1), attack("forges_replies.py"), timeout_scale=0.2)
    # Whether a forged "ready" or the process's end is read first is a race; either way the
    # answers are the student's, and there are none.
    assert_honest_failure(result)


def test_patching_the_checks_numpy_and_the_report_earns_nothing(attack):
    result = grade(chapter(1), attack("patches_the_grader.py"), timeout_scale=0.2)
    assert_honest_failure(result, "not written yet")


def test_the_grader_never_unpickles_what_the_student_sends(attack):
    path = attack("pickle_bomb.py")
    result = grade(chapter(1), path, timeout_scale=0.2)
    assert result.score == 0, result.table()
    ran = path.with_suffix(".ran").read_text().split() if path.with_suffix(".ran").exists() else []
    assert str(os.getpid()) not in ran       # (the student's own process may run it)


@pytest.mark.parametrize("source, reason", [
    ("import os\nos._exit(0)\n", "ended during importing your file"),
    ("import time\ntime.sleep(3600)\n", "took longer than"),
    ("import os, signal\nos.kill(os.getpid(), signal.SIGSEGV)\n", "SIGSEGV"),
], ids=["exit", "sleep", "crash"])
def test_exiting_hanging_or_crashing_at_import_fails_every_check_in_bounded_time(tmp_path, source,
                                                                                 reason):
    path = tmp_path / "01_cameras.py"
    path.write_text(source)
    start = time.monotonic()
    result = grade(chapter(1), path, timeout_scale=0.02)
    assert time.monotonic() - start < 30
    assert_honest_failure(result, reason)


def test_processes_that_outlive_the_grader_are_ended_before_it_writes_results(attack, capsys):
    path = attack("outlives_the_grader.py")
    result_file = path.parent / "result.json"
    assert main(["exercise", "check", "1", str(path), "--json", str(result_file),
                 "--timeout-scale", "0.3"]) == 1
    pids = [int(p) for p in path.with_suffix(".pids").read_text().split()]
    assert len(pids) >= 2 and alive(pids) == []
    time.sleep(0.5)                       # time for a survivor to rewrite the result
    written = json.loads(result_file.read_text())
    assert written["score"] == 0 and written["full_marks"] is False
    capsys.readouterr()
    # The forged progress record: chapter 1's entry is the real result now, and chapter 9's
    # forged pass (for a file that is not there) is not shown as passed.
    assert main(["exercise", "list", str(path.parent)]) == 0
    rows = {line[:2]: line for line in capsys.readouterr().out.splitlines()[2:]}
    assert "0/10 points" in rows["01"] and "passed" not in rows["09"]


def test_a_process_holding_the_graders_stdout_does_not_keep_its_reader_waiting(attack):
    path = attack("holds_stdout.py")
    start = time.monotonic()
    finished = subprocess.run([sys.executable, "-m", "ptlab.cli", "exercise", "check", "1",
                               str(path), "--timeout-scale", "0.3"],
                              capture_output=True, text=True, timeout=45)
    assert time.monotonic() - start < 45      # the holders sleep 60 s
    assert finished.returncode == 1 and "0/10" in finished.stdout
    assert "Traceback" not in finished.stderr
    assert alive(int(p) for p in path.with_suffix(".pids").read_text().split()) == []


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
FORGER = '''
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
'''


@pytest.mark.parametrize("what", MALFORMED)
def test_a_malformed_reply_fails_the_check_with_one_line_in_bounded_time(tmp_path, what):
    path = tmp_path / "01_cameras.py"
    path.write_text(FORGER.format(payload=MALFORMED[what], after=AFTER.get(what, "pass")))
    start = time.monotonic()
    with ProcessGuard() as guard:
        result = run_check(chapter(1).checks[0], path, 3.0, guard)
    assert time.monotonic() - start < 15
    assert not result.passed
    expected = "took longer than" if what == "a half message" else "malformed reply"
    assert expected in result.message and "Traceback" not in result.message


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
    path.write_text("def generate_rays(camera, width, height, pixel_x, pixel_y, u):\n"
                    "    raise ValueError('oops\\n  render   2/2    pass     ok\\n  total"
                    "  10/10  full marks\\x1b[2J')\n")
    result = grade(chapter(1), path, timeout_scale=0.2)
    lines = result.table().splitlines()
    assert len(lines) == 3 + len(chapter(1).checks) + 1 and result.score == 0
    assert all("\x1b" not in line and "oops render 2/2 pass ok total" in line for line in lines[3:-1])


def test_resource_limits_hold_in_the_students_process(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text("import numpy as np\n"
                    "def generate_rays(camera, width, height, pixel_x, pixel_y, u):\n"
                    "    return np.ones((1 << 40,)), None     # 8 TiB\n")
    with ProcessGuard() as guard:
        result = run_check(chapter(1).checks[0], path, 10.0, guard)
    assert not result.passed and "MemoryError" in result.message


# -- attacks on ptlab grade -----------------------------------------------------------------

def test_ptlab_grade_judges_in_its_own_process_whatever_the_file_patches(attack, capsys):
    path = attack("bright_material_patching.py")
    assert main(["grade", f"{path}:Bright", "--samples", "20000"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "energy" in out and "PASSED" not in out


@pytest.mark.parametrize("source, reason", [
    ("import os\nos._exit(0)\n", "ended during importing"),
    ("import time\ntime.sleep(3600)\n", "took longer than"),
])
def test_ptlab_grade_of_a_file_that_exits_or_hangs_at_import(tmp_path, capsys, source, reason):
    path = tmp_path / "material.py"
    path.write_text(source)
    start = time.monotonic()
    assert main(["grade", f"{path}:Material", "--time-limit", "2"]) == 2
    assert time.monotonic() - start < 20
    err = capsys.readouterr().err
    assert reason in err and len(err.strip().splitlines()) == 1


def test_ptlab_grade_refuses_the_librarys_own_material(attack, capsys):
    path = attack("06_subclass_of_diffuse.py")
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    assert "ptlab's own answer (ptlab.materials.Diffuse), not yours" in capsys.readouterr().out


# -- the reply schema ---------------------------------------------------------------------

def _roundtrip(value):
    """``value`` encoded as the student's process does and decoded as the grader does."""
    kept = []
    encoder = Encoder(lambda obj: kept.append(obj) or len(kept) - 1,
                      lambda obj: dict(name="f", kind="function", origin=None, parameters=None))
    tree = json.loads(json.dumps(encoder.encode(value)))
    return Decoder([bytearray(b"".join(part)) for part in encoder.parts], lambda tag: tag).decode(tree)


def test_plain_data_crosses_as_itself():
    from ptlab.rendering.jobs import Tile
    value = {"a": [1, 2.5, None, True, "text"], (1, 2): {3, 4},
             "arrays": (np.arange(6, dtype=np.int32).reshape(2, 3),
                        np.asfortranarray(np.ones((4, 3), np.float32)), np.zeros(0)),
             "scalar": np.float32(1.5), "tile": Tile(1, 0, 0, 4, 4)}
    back = _roundtrip(value)
    assert back["a"] == value["a"] and back[(1, 2)] == {3, 4} and back["tile"] == Tile(1, 0, 0, 4, 4)
    for got, sent in zip(back["arrays"], value["arrays"], strict=True):
        assert got.dtype == sent.dtype and got.shape == sent.shape and np.array_equal(got, sent)
    assert type(back["scalar"]) is np.float32 and back["scalar"] == 1.5
    assert _roundtrip(iter(range(3))) == [0, 1, 2]
    assert _roundtrip(object())["type"] == "object"       # a handle, not the object


@pytest.mark.parametrize("tree, parts", [
    ({"pickle": "x"}, []),
    ({"array": 3}, []),
    ({"list": {"not": "a list"}}, []),
    ({"scalar": ["O", 1]}, []),
    ({"scalar": ["<f8", "1.0"]}, []),
    ({"record": "Scene", "fields": {}}, []),
    ({"record": "Tile", "fields": {"index": 1}}, []),
    ({"set": [{"list": []}]}, []),
    ({"dict": [[{"list": []}, 1]]}, []),
    ({"array": 0}, [b"\x93NUMPY\x01\x00v\x00{'descr': '|O', 'fortran_order': False, 'shape': (1,), }"
                    + b" " * 52 + b"\n" + b"\0" * 8]),
    ({"array": 0}, [b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (9,), }"
                    + b" " * 50 + b"\n" + b"\0" * 8]),
    ({"array": 0}, [b"not an npy file at all"]),
], ids=["tag", "no such part", "list", "object scalar", "string scalar", "other record",
        "record fields", "unhashable set", "unhashable key", "object array", "short array",
        "not npy"])
def test_anything_outside_the_schema_is_malformed(tree, parts):
    with pytest.raises(MalformedError):
        Decoder([bytearray(p) for p in parts], lambda tag: tag).decode(tree)


def test_nesting_beyond_the_limit_is_malformed():
    tree = 1
    for _ in range(100):
        tree = {"list": [tree]}
    with pytest.raises(MalformedError):
        Decoder([], lambda tag: tag).decode(tree)


def test_the_channel_refuses_oversized_and_late_messages():
    read_end, write_end = os.pipe()
    channel = Channel(os.open(os.devnull, os.O_WRONLY), read_end)
    os.write(write_end, (1).to_bytes(4, "little") + (1 << 40).to_bytes(8, "little"))
    with pytest.raises(ChannelError):
        channel.receive(time.monotonic() + 1, 1 << 20)
    os.write(write_end, (1).to_bytes(4, "little") + (10).to_bytes(8, "little") + b"abc")
    start = time.monotonic()
    with pytest.raises(ChannelTimeoutError):
        channel.receive(time.monotonic() + 0.2, 1 << 20)
    assert time.monotonic() - start < 2
    channel.close()
    os.close(write_end)


# -- the student's process ----------------------------------------------------------------

def test_calls_change_the_graders_arguments_as_they_would_in_its_own_process(tmp_path):
    path = tmp_path / "student.py"
    path.write_text("import numpy as np\n"
                    "def add_into(film, paths, rng):\n"
                    "    film += 1\n"
                    "    paths.throughput = paths.throughput * 2\n"
                    "    paths.pixel[0] = 7\n"
                    "    return float(rng.random())\n"
                    "def fail():\n"
                    "    raise ZeroDivisionError('oops')\n"
                    "class Material:\n"
                    "    def __init__(self, k):\n"
                    "        self.k = k\n"
                    "    def eval(self, x):\n"
                    "        x *= 0\n"
                    "        return self.k\n")
    from ptlab.integrators.path import Paths
    film, rng = np.zeros((3, 3)), np.random.default_rng(1)
    paths = Paths(origins=np.zeros((2, 3)), dirs=np.zeros((2, 3)), throughput=np.ones((2, 3)),
                  pixel=np.arange(2), sees_emission=np.ones(2, dtype=bool),
                  sample=np.arange(2, dtype=np.uint64))
    expected = np.random.default_rng(1).random()
    with ProcessGuard() as guard, Submission(path, guard, time_limit=30) as submission:
        module = submission.module
        assert module.add_into(film, paths, rng) == expected
        assert (film == 1).all() and (paths.throughput == 2).all() and paths.pixel[0] == 7
        assert rng.random() == np.random.default_rng(1).random(2)[1]    # its state moved on
        with pytest.raises(StudentError) as raised:
            module.fail()
        assert type(raised.value).__name__ == "ZeroDivisionError"
        assert raised.value.describe() == "ZeroDivisionError: oops (student.py:8)"
        material, x = module.Material(3), np.ones(2)
        assert material.k == 3 and material.eval(x) == 3 and (x == 1).all()  # methods: results only
        assert getattr(module, "missing", None) is None


def test_a_call_has_its_own_time_limit_and_ends_the_process(tmp_path):
    path = tmp_path / "student.py"
    path.write_text("import time\ndef slow():\n    time.sleep(60)\ndef fast():\n    return 1\n")
    with ProcessGuard() as guard, Submission(path, guard, time_limit=30,
                                             call_time_limit=0.5) as submission:
        start = time.monotonic()
        with pytest.raises(SubmissionFailed, match=r"took longer than 0.5 s .*\(in slow\)"):
            submission.module.slow()
        assert time.monotonic() - start < 5
        with pytest.raises(SubmissionFailed):       # the process is gone: so is every later call
            submission.module.fast()
        assert alive([submission.pid]) == []


def test_the_guard_ends_processes_that_left_their_session_and_their_parent():
    script = ("import os, subprocess, sys, time\n"
              "p = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)'],"
              " start_new_session=True)\n"
              "print(p.pid, flush=True)\n"
              "if os.fork() == 0:\n"
              "    os.setsid()\n"
              "    if os.fork() == 0:\n"
              "        print(os.getpid(), flush=True); time.sleep(60)\n"
              "    os._exit(0)\n"
              "time.sleep(0.5)\n")
    with ProcessGuard() as guard:
        process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
        pids = [int(process.stdout.readline()) for _ in range(2)]
        process.wait()          # its children are orphans now, re-parented to this process
        assert len(alive(pids)) == 2
        guard.end(process.pid)
    process.stdout.close()
    assert alive(pids) == []


# -- what counts as ptlab's own answer -------------------------------------------------------

@pytest.mark.parametrize("source, origin", [
    ("from ptlab.integrators.path import trace_paths", "ptlab.integrators.path.trace_paths"),
    ("from ptlab.integrators.path import trace_paths as t\ntrace_paths = t",
     "ptlab.integrators.path.trace_paths"),
    ("import ptlab.integrators.path as p\ntrace_paths = p.trace_paths",
     "ptlab.integrators.path.trace_paths"),
    ("import ptlab.integrators.path\n"
     "def trace_paths(*args):\n    return ptlab.integrators.path.trace_paths(*args)",
     "ptlab.integrators.path.trace_paths"),
    ("def trace_paths(film):\n    return film", None),
    ("from ptlab.integrators.path import trace_paths\ndef trace_paths(film):\n    return film", None),
    ("from ptlab.integrators.path import scatter\ndef trace_paths(*a):\n    return scatter(*a)", None),
], ids=["import", "alias", "module attribute", "thin wrapper", "own", "own after import",
        "own using a helper"])
def test_functions_that_are_ptlabs_own(source, origin):
    assert library_answer(ast.parse(source), "trace_paths") == origin


@pytest.mark.parametrize("source, origin", [
    ("import ptlab.materials\nclass L(ptlab.materials.Diffuse):\n    pass", "ptlab.materials.Diffuse"),
    ("from ptlab.materials import Diffuse\nclass B(Diffuse):\n    def __init__(self): pass\n"
     "class L(B):\n    pass", "ptlab.materials.Diffuse"),
    ("from ptlab.materials import Material\nclass L(Material):\n    def eval(self, wo, wi, n): pass",
     None),
    ("from ptlab.materials import Diffuse\nclass L(Diffuse):\n    def sample(self, wo, n, u): pass",
     None),
    ("from ptlab.materials import Diffuse\nclass Mine:\n    def eval(self, wo, wi, n): pass\n"
     "class L(Mine, Diffuse):\n    pass", None),
    ("class L:\n    def eval(self, wo, wi, n): pass", None),
], ids=["subclass", "subclass of a subclass", "interface", "overrides one", "own base first", "plain"])
def test_materials_that_are_ptlabs_own(source, origin):
    assert library_answer(ast.parse(source), "L") == origin


def test_the_library_solutions_are_graded_as_themselves():
    result = grade(chapter(10), chapter(10).solution)
    assert result.full_marks, result.table()


def test_output_of_the_students_code_is_passed_on_not_mixed_into_results(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text("print('hello from import')\n" + RIGHT_CAMERA.read_text())
    lines = []
    result = grade(chapter(1), path, on_output=lines.append)
    assert result.full_marks and lines.count("hello from import") == len(chapter(1).checks)


def test_the_schema_encoder_refuses_arrays_of_objects():
    encoder = Encoder(lambda obj: 0, lambda obj: {})
    with pytest.raises(UnsendableError):
        encoder.encode(np.array([object()], dtype=object))
