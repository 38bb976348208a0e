"""The pieces of ``ptlab.course.sandbox``: the reply schema, the pipes, the student's process,
the subreaper, and what counts as ptlab's own answer. (The attacks on the graders, whole,
are in ``tests/attacks/``.)"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ptlab.course import chapter
from ptlab.course.grader import grade
from ptlab.course.sandbox import Arguments, ProcessGuard, Rules, StudentError, Submission, SubmissionFailed
from ptlab.course.sandbox.channel import Channel, ChannelError, ChannelTimeoutError
from ptlab.course.sandbox.ownership import library_answer
from ptlab.course.sandbox.plain_data import Decoder, Encoder, MalformedError, UnsendableError
from ptlab.course.sandbox.processes import descendants, process_table

pytestmark = pytest.mark.usefixtures("nothing_left_behind")
RIGHT_CAMERA = Path(__file__).parents[1] / "exercises" / "01_right_own_code.py"


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


POOLS_STUDENT = """
import multiprocessing, os, time
from concurrent.futures import ProcessPoolExecutor

_left_open = []

def _pid_after(seconds):
    time.sleep(seconds)
    return os.getpid()

def pool_left_open():
    pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("forkserver"))
    _left_open.append(pool)
    worker = pool.submit(_pid_after, 0).result()
    pool.submit(_pid_after, 60)
    return worker

def pool_closed():
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("forkserver")) as pool:
        return pool.submit(_pid_after, 0).result()
"""


def _below(pid: int) -> list[str]:
    """The command lines of the processes below ``pid``."""
    below = descendants({pid}, process_table(alive_only=True))
    return sorted(
        Path(f"/proc/{child}/cmdline").read_bytes().replace(b"\0", b" ").decode() for child in below
    )


@pytest.mark.subprocess
def test_ending_a_checks_pools_ends_their_workers_and_spares_multiprocessings_helpers(tmp_path):
    """A pool left running ends with its check (its busy worker too), while multiprocessing's
    resource tracker and fork server, started once for every later pool, stay: ending them
    made the next pool print "resource_tracker: process died unexpectedly" to students."""
    path = tmp_path / "student.py"
    path.write_text(POOLS_STUDENT)
    said: list[str] = []
    with ProcessGuard() as guard, Submission(path, guard, time_limit=60, on_output=said.append) as submission:
        module = submission.import_by_file_name()
        module.pool_left_open()  # (its worker's pid is the sandbox's, not ours: count them)
        before = _below(submission.pid)
        submission.end_started_processes()
        deadline = time.monotonic() + 5
        while len(_below(submission.pid)) >= len(before) and time.monotonic() < deadline:
            time.sleep(0.05)
        after = _below(submission.pid)
        assert len(after) == len(before) - 1, (before, after)  # the worker, not the two helpers
        module.pool_closed()
        submission.end_started_processes()
        module.pool_closed()
    assert not any("resource_tracker" in line or "died unexpectedly" in line for line in said), said


@pytest.mark.subprocess
def test_the_guard_ends_processes_that_left_their_session_and_their_parent():
    script = (
        "import os, subprocess, sys, time\n"
        "p = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)'],"
        " start_new_session=True)\n"
        "print(p.pid, flush=True)\n"
        "if os.fork() == 0:\n"
        "    try:\n"
        "        os.setsid()\n"
        "        if os.fork() == 0:\n"
        "            try:\n"
        "                print(os.getpid(), flush=True); time.sleep(60)\n"
        "            finally:\n"
        "                os._exit(0)\n"
        "    finally:\n"
        "        os._exit(0)\n"
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


# -- code the grader can read (ptlab.course.sandbox.readable) ------------------------------------

ENCODED = "import base64, zlib\nexec(zlib.decompress(base64.b64decode(b'eJwDAAAAAAE=')))\n"
GRADED = "07_path_tracing.py"


def _taken(files: dict[str, str] | str, graded: str = GRADED):
    """A submission as ``take_in`` reads it, from texts (one text: the graded file alone)."""
    from ptlab.course.sandbox import Taken

    files = {graded: files} if isinstance(files, str) else files
    data = {name: text.encode() for name, text in files.items()}
    return Taken(Path(graded), data, "", ast.parse(data[graded]))


def _unreadable(files: dict[str, str] | str, name: str = "trace_paths"):
    from ptlab.course.sandbox.readable import unreadable_in_text

    return unreadable_in_text(_taken(files), name)


#: Texts whose graded function reaches what a readable file does not use: (text, reason,
#: what the message names). Each spelling of code made from data, or of an object reached
#: by a name built at run time, that the allowlist leaves out (ptlab.course.sandbox.uses).
UNREADABLE_TEXTS = {
    "encoded": (ENCODED, "unreadable.at_import", "exec"),
    "encoded beside a def": (
        ENCODED + "def trace_paths(film):\n    return film",
        "unreadable.at_import",
        "exec",
    ),
    "marshal": (
        "import marshal, types\ntrace_paths = types.FunctionType(marshal.loads(b''), {})",
        "unreadable.at_import",
        "types.FunctionType",
    ),
    "marshal imported by name": (
        "from marshal import loads\ndef trace_paths(b):\n    return loads(b)",
        "unreadable.runs_made_code",
        "marshal",
    ),
    "__import__ of a constant": (
        "_m = __import__('marshal')\ndef trace_paths(film):\n    return film",
        "unreadable.at_import",
        "__import__",
    ),
    "function type of a lambda": (
        "_f = type(lambda: 0)\ndef trace_paths(film):\n    return film",
        "unreadable.at_import",
        "type(...)",
    ),
    "function type called": (
        "def trace_paths(f, g):\n    return type(f)(g, {})",
        "unreadable.runs_made_code",
        "type(...)",
    ),
    "class of a function called": (
        "def trace_paths(f, g):\n    return f.__class__(g, {})",
        "unreadable.runs_made_code",
        ".__class__",
    ),
    "type with three arguments": (
        "def trace_paths(d):\n    return type('T', (), d)",
        "unreadable.runs_made_code",
        "type(name, bases, namespace)",
    ),
    "function type through typing": (
        "import typing\ndef trace_paths(c):\n    return typing.types.FunctionType(c, {})",
        "unreadable.runs_made_code",
        "types.FunctionType",
    ),
    "globals looked up": (
        "def trace_paths(film):\n    return globals()['_h'](film)",
        "unreadable.runs_made_code",
        "globals()",
    ),
    "globals updated": (
        "globals().update({'_h': print})\ndef trace_paths(film):\n    return film",
        "unreadable.at_import",
        "globals()",
    ),
    "vars looked up": (
        "def trace_paths(o, k):\n    return vars(o)[k]",
        "unreadable.runs_made_code",
        "vars()",
    ),
    "sys.modules": (
        "import sys\ndef trace_paths(film):\n    return sys.modules['builtins']",
        "unreadable.runs_made_code",
        "sys.modules",
    ),
    "sys through another module": (
        "import dataclasses\ndef trace_paths(film):\n    return dataclasses.sys.modules",
        "unreadable.runs_made_code",
        "sys.modules",
    ),
    "settrace": (
        "import sys\nsys.settrace(None)\ndef trace_paths(film):\n    return film",
        "unreadable.at_import",
        ".settrace",
    ),
    "gc's objects": (
        "import gc\ndef trace_paths(film):\n    return gc.get_objects()",
        "unreadable.runs_made_code",
        "gc.get_objects",
    ),
    "getattr of a built name": (
        "def trace_paths(o):\n    return getattr(o, 'ex' + 'ec')",
        "unreadable.runs_made_code",
        "getattr() with a name built at run time",
    ),
    "getattr of a dunder": (
        "def trace_paths(f):\n    return getattr(f, '__globals__')",
        "unreadable.runs_made_code",
        "getattr(..., '__globals__')",
    ),
    "getattr handed on": (
        "import functools\ndef trace_paths(o):\n    return functools.reduce(getattr, ['a'], o)",
        "unreadable.runs_made_code",
        "getattr",
    ),
    "getattr of a module's attribute": (
        "import sys\ndef trace_paths(film):\n    return getattr(sys, 'modules')",
        "unreadable.runs_made_code",
        "sys.modules",
    ),
    "builtins": (
        "def trace_paths(f):\n    return __builtins__",
        "unreadable.runs_made_code",
        "__builtins__",
    ),
    "a function's globals": (
        "def trace_paths(f):\n    return f.__globals__['x']",
        "unreadable.runs_made_code",
        ".__globals__",
    ),
    "a frame": (
        "def trace_paths(e):\n    return e.tb_frame.f_back",
        "unreadable.runs_made_code",
        ".f_back",
    ),
    "exec as a local of the module": (
        "run = exec\ndef trace_paths(s):\n    return run(s)",
        "unreadable.at_import",
        "exec",
    ),
    "exec bound in a class body": (
        "class _K:\n    exec = exec\ndef trace_paths(s):\n    return _K.exec(s)",
        "unreadable.at_import",
        "exec",
    ),
    "helper with eval": (
        "def _run(s):\n    return eval(s)\ndef trace_paths(s):\n    return _run(s)",
        "unreadable.runs_made_code",
        "eval",
    ),
    "pickle in npy": (
        "import numpy as np\ndef trace_paths(f):\n    return np.load(f, allow_pickle=True)",
        "unreadable.runs_made_code",
        "allow_pickle",
    ),
    "numpy's ctypes": (
        "import numpy as np\ndef trace_paths(a):\n    return np.ctypeslib.as_array(a)",
        "unreadable.runs_made_code",
        ".ctypeslib",
    ),
    "numpy handed on": (
        "import numpy as np\ndef trace_paths(f, xp=np):\n    return xp.ctypeslib",
        "unreadable.at_import",
        "numpy as a value",
    ),
    "the grader's end in the kit": (
        "from ptlab.course.sandbox import child\ndef trace_paths(f):\n    return child.code_digest(f)",
        "unreadable.runs_made_code",
        "ptlab.course.sandbox",
    ),
    "find_spec kept": (
        "import importlib.util\n_spec = importlib.util.find_spec('numba')\ndef trace_paths(f):\n    return f",
        "unreadable.at_import",
        "importlib.util.find_spec",
    ),
    "importlib": (
        "import importlib\ndef trace_paths(f):\n    return importlib.import_module(f)",
        "unreadable.runs_made_code",
        "importlib.import_module",
    ),
    "own code swapped in": (
        "def _a(f):\n    return f\ndef trace_paths(f):\n    pass\ntrace_paths.__code__ = _a.__code__",
        "unreadable.at_import",
        ".__code__",
    ),
    "imported": ("from fastpath import trace_paths", "unreadable.imported", None),
    "module attribute": ("import fastpath\ntrace_paths = fastpath.trace", "unreadable.imported", None),
    "bound in globals()": ("globals()['trace_paths'] = print", "unreadable.at_import", "globals()"),
    "the file's encoding": (
        "# coding: utf-7\ndef trace_paths(film):\n    return film",
        "unreadable.encoding",
        None,
    ),
    "reordered on screen": (
        "def trace_paths(film):\n    return film  # \u202e ok\n",
        "unreadable.reordered",
        None,
    ),
}

#: Texts whose graded function a readable file may hold: what honest answers do.
READABLE_TEXTS = {
    "own": "def trace_paths(film):\n    return film",
    # exec and eval where no graded function reaches them and nothing runs them at import
    "eval unreached": "def _debug(expression):\n    print(eval(expression))\n"
    "def trace_paths(film):\n    return film\nif __name__ == '__main__':\n    exec('print(1)')",
    "local named eval": "def trace_paths(m, x):\n    eval = m.eval\n    return eval(x)",
    "parameter named compile": "def trace_paths(compile, x):\n    return compile(x)",
    "type test": "import types\ndef trace_paths(eta):\n"
    "    return eta() if isinstance(eta, types.FunctionType) else eta",
    "type compared and named": "def trace_paths(a, b):\n    return type(a) is type(b) and type(a).__name__",
    "find_spec as a test": "import importlib.util\nHAVE = importlib.util.find_spec('numba') is not None\n"
    "def trace_paths(film):\n    return film if HAVE else -film",
    "optional import": "try:\n    import numba\nexcept ImportError:\n    numba = None\n"
    "def trace_paths(film):\n    return film if numba is None else numba.njit(film)",
    "globals iterated": "def trace_paths(film):\n    return [k for k in globals() if k.startswith('t')]",
    "constant getattr": "def trace_paths(m):\n    return getattr(m, 'albedo', 0) + hasattr(m, '__dict__')",
    "object.__setattr__": "class S:\n    def __init__(self, x):\n        object.__setattr__(self, 'x', x)\n"
    "        super().__init__()\ndef trace_paths(film):\n    return S(film).x",
    "sys and os, harmlessly": "import os, sys\ndef trace_paths(film):\n"
    "    print(os.cpu_count(), file=sys.stderr)\n    return film * sys.float_info.epsilon",
    "star import": "from ptlab.vectors import *\ndef trace_paths(a):\n    return dot(a, a) + np.sum(a)",
    "garbage collected": "import gc\ndef trace_paths(film):\n    gc.collect()\n    return film",
    "math handed on": "import math\ndef trace_paths(a, m=math):\n    return m.sqrt(a)",
    "a dataclass": "from dataclasses import dataclass, field\n@dataclass\nclass S:\n"
    "    x: list = field(default_factory=list)\ndef trace_paths(film):\n    return S().x",
    "numpy and scipy": "import numpy as np\nfrom scipy import ndimage\ndef trace_paths(a):\n"
    "    return ndimage.uniform_filter(np.linalg.norm(a, axis=1), 3)",
    "a closure and a partial": "import functools\ndef _make(k):\n    def inner(x):\n        return x * k\n"
    "    return inner\ntrace_paths = functools.partial(_make(2))",
}


@pytest.mark.parametrize(("text", "reason", "what"), UNREADABLE_TEXTS.values(), ids=UNREADABLE_TEXTS)
def test_what_a_readable_file_does_not_use(text, reason, what):
    found = _unreadable(text)
    assert found is not None, text
    assert found.reason == reason, found
    if what is not None:
        assert found.fields["what"] == what, found


@pytest.mark.parametrize("text", READABLE_TEXTS.values(), ids=READABLE_TEXTS)
def test_what_honest_answers_do_is_readable(text):
    assert _unreadable(text) is None


@pytest.mark.parametrize(
    ("files", "reason", "what"),
    [
        (
            {GRADED: "from helpers import trace_paths", "helpers.py": "def trace_paths(f):\n    return f"},
            None,
            None,
        ),
        ({GRADED: "from helpers import trace_paths", "helpers.py": ENCODED}, "unreadable.at_import", "exec"),
        (
            {
                GRADED: "import helpers\ndef trace_paths(f):\n    return helpers.run(f)",
                "helpers.py": "def run(f):\n    return eval(f)",
            },
            "unreadable.runs_made_code",
            "eval",
        ),
        # a library reached through the submission's own module is judged as the library's
        (
            {
                GRADED: "import helpers\ndef trace_paths(f):\n    return helpers.pickle.loads(f)",
                "helpers.py": "import pickle\n",
            },
            "unreadable.runs_made_code",
            "pickle",
        ),
        (
            {
                GRADED: "from helpers import *\ndef trace_paths(f):\n    return marshal.loads(f)",
                "helpers.py": "import marshal\n",
            },
            "unreadable.runs_made_code",
            "marshal",
        ),
        # a file named like a module Python has loaded already is not what import finds
        (
            {
                GRADED: "import types\ndef trace_paths(f):\n    return types.new_class(f)",
                "types.py": "new_class = 1",
            },
            "unreadable.runs_made_code",
            "types.new_class",
        ),
    ],
    ids=[
        "other file",
        "other file encoded",
        "other file's eval",
        "library through another file",
        "library through another file's import *",
        "shadowed",
    ],
)
def test_the_submissions_other_files_are_read_as_the_graded_one(files, reason, what):
    found = _unreadable(files)
    assert (found and found.reason) == reason, found
    if what is not None:
        assert found.fields["what"] == what, found


def test_unreadable_messages_name_the_reason_and_ask_for_a_teacher():
    from ptlab.course.messages import language
    from ptlab.course.sandbox.readable import unreadable_in_text

    material = "class L:\n    def eval(self, wo, wi, n):\n        return wo\n"
    assert unreadable_in_text(_taken(material, "06_diffuse.py"), "L") is None
    found = unreadable_in_text(_taken(ENCODED + material, "06_diffuse.py"), "L")
    with language("en"):
        message = found.message("L")
    assert message.startswith("L: your file uses exec when it is imported (06_diffuse.py:2)")
    assert "needs a teacher's look" in message
    with language("zh"):
        assert "老师" in found.message("L")
    # importlib, but for a test of whether a package is installed, is told the way that is
    found = _unreadable(
        "import importlib.util\n_s = importlib.util.find_spec('numba')\ndef trace_paths(f): pass"
    )
    with language("en"):
        assert "write 'try: import numba' and 'except ImportError:'" in found.message("trace_paths")
    with language("zh"):
        assert "except ImportError" in found.message("trace_paths")


def _grading_process(tmp_path: Path, text: str, name: str = GRADED):
    """A process of the student's file ``text``, as the graders start one (not ptlab's own)."""
    path = tmp_path / name
    path.write_text(text)
    guard = ProcessGuard()
    guard.__enter__()
    submission = Submission(path, guard, time_limit=60, rules=Rules())
    return guard, submission


@contextlib.contextmanager
def _student_process(tmp_path: Path, text: str, name: str = GRADED):
    guard, submission = _grading_process(tmp_path, text, name)
    try:
        yield submission
    finally:
        submission.close()
        guard.__exit__(None, None, None)


#: Code made at run time, reached in ways no name in the graded function's code shows: a
#: dict in the globals, a slot, a library's wrapper, an attribute of NumPy. The reading of
#: the text refuses each (exec); what runs is checked for itself (the text reading aside).
MADE = "_namespace = {}\nexec('def _h(film):\\n    return film + 1', _namespace)\n"
MADE_AND_REACHED = {
    "globals": MADE
    + "globals()['_H'] = _namespace\ndef trace_paths(film):\n    return globals()['_H']['_h'](film)\n",
    "slots": MADE + "class _Call:\n    __slots__ = ('f',)\n    def __init__(self, f):\n        self.f = f\n"
    "    def __call__(self, *a):\n        return self.f(*a)\ntrace_paths = _Call(_namespace['_h'])\n",
    "library wrapper": MADE + "import contextlib\nclass _Quiet(contextlib.ContextDecorator):\n"
    "    def __enter__(self):\n        return self\n    def __exit__(self, *e):\n        return False\n"
    "trace_paths = _Quiet()(_namespace['_h'])\n",
    "numpy's attribute": MADE
    + "import functools, numpy as np\nnp.my_h = functools.partial(_namespace['_h'])\n"
    "def trace_paths(film):\n    return np.my_h(film)\n",
    # compiled under the name of the file, at the def's line and under its name
    "said to be the file's": "def trace_paths(film):\n    return film\n"
    "_code = compile('def trace_paths(film):\\n    return film + 1', __file__, 'exec')\n"
    "trace_paths = type(trace_paths)(_code.co_consts[0], globals())\n",
    # compiled under the name of a library file: not what that file holds
    "said to be NumPy's": "import numpy\n_namespace = {}\n"
    "exec(compile('def _h(film):\\n    return film + 1', numpy.__file__, 'exec'), _namespace)\n"
    "def trace_paths(film):\n    return _namespace['_h'](film)\n",
    # a module written into the student's folder while it runs, and imported
    # written and imported at import, where nothing is recorded: its module is found
    "module written at import": "import os, sys\n_folder = os.path.dirname(__file__)\n"
    "with open(os.path.join(_folder, 'extra.py'), 'w') as _f:\n    _f.write('VALUE = 41\\n')\n"
    "sys.path.insert(0, _folder)\nimport extra\ndef trace_paths(film):\n    return extra.VALUE + film\n",
    "module written at run time": "import os, sys\ndef trace_paths(film):\n"
    "    folder = os.path.dirname(__file__)\n"
    "    with open(os.path.join(folder, 'extra.py'), 'w') as f:\n"
    "        f.write('def h(x):\\n    return x + 1\\n')\n"
    "    sys.path.insert(0, folder)\n    import extra\n    return extra.h(film)\n",
}


@pytest.mark.subprocess
@pytest.mark.parametrize("text", MADE_AND_REACHED.values(), ids=MADE_AND_REACHED)
def test_code_that_runs_and_is_not_the_files_is_found_when_it_runs(tmp_path, text):
    from ptlab.course.sandbox.submission import UnreadableCode

    with _student_process(tmp_path, text) as submission:
        with pytest.raises(UnreadableCode) as raised:
            submission.module.trace_paths(1)
        assert raised.value.why.reason == "unreadable.not_the_text"
        assert "this needs a teacher's look" in str(raised.value)
        # It ends the check: whatever the check catches, the next request fails the same way.
        with pytest.raises(UnreadableCode):
            submission.module.trace_paths(1)


@pytest.mark.subprocess
def test_code_of_the_file_and_of_the_library_is_read_however_it_is_built(tmp_path):
    """Closures, lambdas, generators, dataclasses and named tuples (whose methods the standard
    library compiles from strings), a thread of the student's, functions of ptlab's kit and of
    NumPy, a module-level table far larger than any walk would follow: all run and all are
    readable."""
    text = (
        "import collections, dataclasses, threading\n"
        "import numpy as np\n"
        "from ptlab.vectors import dot\n"
        "@dataclasses.dataclass(frozen=True)\n"
        "class Settings:\n"
        "    scale: float = 2.0\n"
        "    tags: list = dataclasses.field(default_factory=lambda: [1])\n"
        "TABLE = [(i, i * i) for i in range(60001)]\n"
        "_square = lambda x: x * x\n"
        "def _make(k):\n"
        "    def inner(film):\n"
        "        Pair = collections.namedtuple('Pair', 'a b')\n"
        "        box = []\n"
        "        thread = threading.Thread(target=lambda: box.append(sum(i for i in range(3))))\n"
        "        thread.start()\n"
        "        thread.join()\n"
        "        ones = np.ones((1, 3))\n"
        "        return (_square(film) * k * Settings().scale + Pair(1, 2).a + box[0] + len(TABLE)\n"
        "                + np.linspace(0, 1, 2)[0] + dot(ones, ones)[0])\n"
        "    return inner\n"
        "trace_paths = _make(3)\n"
    )
    with _student_process(tmp_path, text) as submission:
        assert submission.module.trace_paths(1.0) == 3 * 2.0 + 1 + 3 + 60001 + 3
        assert submission.code_ran.records > 50  # (the library's code is checked too)


def test_a_dataclass_is_a_class_the_grader_calls_and_its_objects_stay_objects():
    from dataclasses import dataclass

    @dataclass
    class Lambertian:
        albedo: float = 0.8

        def __call__(self):
            return self.albedo

    kept = []
    encoder = Encoder(lambda obj: kept.append(obj) or len(kept) - 1, lambda obj: {"name": "x"})
    assert "function" in encoder.encode(Lambertian)  # (a class: the grader makes objects of it)
    assert "object" in encoder.encode(Lambertian())  # (its fields are read as attributes)


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
    from ptlab.course.sandbox import sandbox

    if sandbox.missing() is not None:
        pytest.skip(str(sandbox.missing()))
    if os.geteuid() != 0:  # (tests/attacks/test_operating_system.py holds what it does then)
        pytest.skip("a grader that is not root grades not for credit: its students' code runs as itself")
    result = grade(chapter(1), RIGHT_CAMERA, timeout_scale=0.5)
    assert result.full_marks, result.table()
    assert result.for_credit
    assert result.as_dict()["for_credit"] is True
    assert "NOT FOR CREDIT" not in result.table()
