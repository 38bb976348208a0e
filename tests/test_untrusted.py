"""The pieces of ``ptlab.untrusted``: the reply schema, the pipes, the student's process,
the subreaper, and what counts as ptlab's own answer. (The attacks on the graders, whole,
are in ``tests/attacks/``.)"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ptlab.exercises import chapter
from ptlab.exercises.grader import grade
from ptlab.untrusted import Arguments, ProcessGuard, Rules, StudentError, Submission, SubmissionFailed
from ptlab.untrusted.channel import Channel, ChannelError, ChannelTimeoutError
from ptlab.untrusted.ownership import library_answer
from ptlab.untrusted.plain_data import Decoder, Encoder, MalformedError, UnsendableError
from ptlab.untrusted.processes import process_table

pytestmark = pytest.mark.usefixtures("nothing_left_behind")
RIGHT_CAMERA = Path(__file__).parent / "exercises" / "01_right_own_code.py"


def alive(pids) -> list[int]:
    running = process_table(alive_only=True)
    return [pid for pid in pids if pid in running]


# -- the reply schema ---------------------------------------------------------------------


def _roundtrip(value):
    """``value`` encoded as the student's process does and decoded as the grader does."""
    kept = []
    encoder = Encoder(
        lambda obj: kept.append(obj) or len(kept) - 1,
        lambda obj: dict(name="f", kind="function", origin=None, parameters=None),
    )
    tree = json.loads(json.dumps(encoder.encode(value)))
    return Decoder([bytearray(b"".join(part)) for part in encoder.parts], lambda tag: tag).decode(tree)


def test_plain_data_crosses_as_itself():
    from ptlab.rendering.jobs import Tile

    value = {
        "a": [1, 2.5, None, True, "text"],
        (1, 2): {3, 4},
        "arrays": (
            np.arange(6, dtype=np.int32).reshape(2, 3),
            np.asfortranarray(np.ones((4, 3), np.float32)),
            np.zeros(0),
        ),
        "scalar": np.float32(1.5),
        "tile": Tile(1, 0, 0, 4, 4),
    }
    back = _roundtrip(value)
    assert back["a"] == value["a"]
    assert back[(1, 2)] == {3, 4}
    assert back["tile"] == Tile(1, 0, 0, 4, 4)
    for got, sent in zip(back["arrays"], value["arrays"], strict=True):
        assert got.dtype == sent.dtype
        assert got.shape == sent.shape
        assert np.array_equal(got, sent)
    assert type(back["scalar"]) is np.float32
    assert back["scalar"] == 1.5
    assert _roundtrip(iter(range(3))) == [0, 1, 2]
    assert _roundtrip(object())["type"] == "object"  # a handle, not the object


@pytest.mark.parametrize(
    ("tree", "parts"),
    [
        ({"pickle": "x"}, []),
        ({"array": 3}, []),
        ({"list": {"not": "a list"}}, []),
        ({"scalar": ["O", 1]}, []),
        ({"scalar": ["<f8", "1.0"]}, []),
        ({"record": "Scene", "fields": {}}, []),
        ({"record": "Tile", "fields": {"index": 1}}, []),
        ({"set": [{"list": []}]}, []),
        ({"dict": [[{"list": []}, 1]]}, []),
        (
            {"array": 0},
            [
                b"\x93NUMPY\x01\x00v\x00{'descr': '|O', 'fortran_order': False, 'shape': (1,), }"
                + b" " * 52
                + b"\n"
                + b"\0" * 8
            ],
        ),
        (
            {"array": 0},
            [
                b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (9,), }"
                + b" " * 50
                + b"\n"
                + b"\0" * 8
            ],
        ),
        ({"array": 0}, [b"not an npy file at all"]),
    ],
    ids=[
        "tag",
        "no such part",
        "list",
        "object scalar",
        "string scalar",
        "other record",
        "record fields",
        "unhashable set",
        "unhashable key",
        "object array",
        "short array",
        "not npy",
    ],
)
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


@pytest.mark.subprocess
def test_calls_change_the_graders_arguments_as_they_would_in_its_own_process(tmp_path):
    path = tmp_path / "student.py"
    path.write_text(
        "import numpy as np\n"
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
        "        return self.k\n"
    )
    from ptlab.integrators.path import Paths

    film, rng = np.zeros((3, 3)), np.random.default_rng(1)
    paths = Paths(
        origins=np.zeros((2, 3)),
        dirs=np.zeros((2, 3)),
        throughput=np.ones((2, 3)),
        pixel=np.arange(2),
        sees_emission=np.ones(2, dtype=bool),
        sample=np.arange(2, dtype=np.uint64),
    )
    expected = np.random.default_rng(1).random()
    rules = Rules(
        arguments={"add_into": Arguments(("film", "paths", "rng"), writes=("film", "paths", "rng"))}
    )
    with ProcessGuard() as guard, Submission(path, guard, time_limit=30, rules=rules) as submission:
        module = submission.module
        assert module.add_into(film, paths, rng) == expected
        assert (film == 1).all()
        assert (paths.throughput == 2).all()
        assert paths.pixel[0] == 7
        assert rng.random() == np.random.default_rng(1).random(2)[1]  # its state moved on
        with pytest.raises(StudentError) as raised:
            module.fail()
        assert type(raised.value).__name__ == "ZeroDivisionError"
        assert raised.value.describe() == "ZeroDivisionError: oops (student.py:8)"
        material, x = module.Material(3), np.ones(2)
        assert material.k == 3
        assert material.eval(x) == 3
        assert (x == 1).all()
        assert getattr(module, "missing", None) is None


@pytest.mark.subprocess
def test_a_call_has_its_own_time_limit_and_ends_the_process(tmp_path):
    path = tmp_path / "student.py"
    path.write_text("import time\ndef slow():\n    time.sleep(60)\ndef fast():\n    return 1\n")
    with ProcessGuard() as guard, Submission(path, guard, time_limit=30, call_time_limit=0.5) as submission:
        start = time.monotonic()
        with pytest.raises(SubmissionFailed, match=r"took longer than 0.5 s .*\(in slow\)"):
            submission.module.slow()
        assert time.monotonic() - start < 5
        with pytest.raises(SubmissionFailed):  # the process is gone: so is every later call
            submission.module.fast()
        assert alive([submission.pid]) == []


@pytest.mark.subprocess
def test_the_guard_ends_processes_that_left_their_session_and_their_parent():
    script = (
        "import os, subprocess, sys, time\n"
        "p = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)'],"
        " start_new_session=True)\n"
        "print(p.pid, flush=True)\n"
        "if os.fork() == 0:\n"
        "    os.setsid()\n"
        "    if os.fork() == 0:\n"
        "        print(os.getpid(), flush=True); time.sleep(60)\n"
        "    os._exit(0)\n"
        "time.sleep(0.5)\n"
    )
    with ProcessGuard() as guard:
        process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
        pids = [int(process.stdout.readline()) for _ in range(2)]
        process.wait()  # its children are orphans now, re-parented to this process
        assert len(alive(pids)) == 2
        guard.end(process.pid)
    process.stdout.close()
    assert alive(pids) == []


# -- what counts as ptlab's own answer -------------------------------------------------------


@pytest.mark.parametrize(
    ("source", "origin"),
    [
        ("from ptlab.integrators.path import trace_paths", "ptlab.integrators.path.trace_paths"),
        (
            "from ptlab.integrators.path import trace_paths as t\ntrace_paths = t",
            "ptlab.integrators.path.trace_paths",
        ),
        (
            "import ptlab.integrators.path as p\ntrace_paths = p.trace_paths",
            "ptlab.integrators.path.trace_paths",
        ),
        (
            "import ptlab.integrators.path\n"
            "def trace_paths(*args):\n    return ptlab.integrators.path.trace_paths(*args)",
            "ptlab.integrators.path.trace_paths",
        ),
        ("def trace_paths(film):\n    return film", None),
        ("from ptlab.integrators.path import trace_paths\ndef trace_paths(film):\n    return film", None),
        ("from ptlab.integrators.path import scatter\ndef trace_paths(*a):\n    return scatter(*a)", None),
    ],
    ids=[
        "import",
        "alias",
        "module attribute",
        "thin wrapper",
        "own",
        "own after import",
        "own using a helper",
    ],
)
def test_functions_that_are_ptlabs_own(source, origin):
    assert library_answer(ast.parse(source), "trace_paths") == origin


@pytest.mark.parametrize(
    ("source", "origin"),
    [
        ("import ptlab.materials\nclass L(ptlab.materials.Diffuse):\n    pass", "ptlab.materials.Diffuse"),
        (
            "from ptlab.materials import Diffuse\nclass B(Diffuse):\n    def __init__(self): pass\n"
            "class L(B):\n    pass",
            "ptlab.materials.Diffuse",
        ),
        (
            "from ptlab.materials import Material\nclass L(Material):\n    def eval(self, wo, wi, n): pass",
            None,
        ),
        (
            "from ptlab.materials import Diffuse\nclass L(Diffuse):\n    def sample(self, wo, n, u): pass",
            None,
        ),
        (
            "from ptlab.materials import Diffuse\nclass Mine:\n    def eval(self, wo, wi, n): pass\n"
            "class L(Mine, Diffuse):\n    pass",
            None,
        ),
        ("class L:\n    def eval(self, wo, wi, n): pass", None),
    ],
    ids=["subclass", "subclass of a subclass", "interface", "overrides one", "own base first", "plain"],
)
def test_materials_that_are_ptlabs_own(source, origin):
    assert library_answer(ast.parse(source), "L") == origin


@pytest.mark.subprocess
def test_the_library_solutions_are_graded_as_themselves():
    result = grade(chapter(10), chapter(10).solution, library_answer=True)
    assert result.full_marks, result.table()


@pytest.mark.subprocess
def test_output_of_the_students_code_is_passed_on_not_mixed_into_results(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text("print('hello from import')\n" + RIGHT_CAMERA.read_text())
    lines = []
    result = grade(chapter(1), path, on_output=lines.append)
    assert result.full_marks
    assert lines.count("hello from import") == len(chapter(1).checks)


def test_the_schema_encoder_refuses_arrays_of_objects():
    encoder = Encoder(lambda obj: 0, lambda obj: {})
    with pytest.raises(UnsendableError):
        encoder.encode(np.array([object()], dtype=object))


# -- where the sandbox cannot be made -----------------------------------------------------------


@pytest.mark.slow
@pytest.mark.subprocess
def test_without_bubblewrap_the_grader_grades_and_says_not_for_credit(tmp_path):
    # A PATH with no bwrap on it is a machine without bubblewrap.
    result = tmp_path / "result.json"
    command = ["exercise", "check", "1", str(RIGHT_CAMERA), "--json", str(result)]
    ran = subprocess.run(
        [sys.executable, "-m", "ptlab.cli", *command],
        env=dict(os.environ, PATH=str(tmp_path)),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert ran.returncode == 0, ran.stdout + ran.stderr  # (the student's own check: full marks)
    assert "NOT FOR CREDIT: bubblewrap is not installed (apt-get install bubblewrap)" in ran.stdout
    written = json.loads(result.read_text())
    assert written["for_credit"] is False
    assert "bubblewrap is not installed" in written["not_for_credit"]


@pytest.mark.slow
@pytest.mark.subprocess
def test_with_bubblewrap_a_grade_is_for_credit(tmp_path):
    from ptlab.untrusted import sandbox

    if sandbox.missing() is not None:
        pytest.skip(str(sandbox.missing()))
    result = grade(chapter(1), RIGHT_CAMERA, timeout_scale=0.5)
    assert result.full_marks, result.table()
    assert result.for_credit
    assert result.as_dict()["for_credit"] is True
    assert "NOT FOR CREDIT" not in result.table()
