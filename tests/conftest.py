"""Shared fixtures: the built-in Cornell box, a private state folder, a record of NaN
contributions, a check that a test left no process behind; the Hypothesis profiles; the
check that a test which starts a process says so (the ``subprocess`` marker); and the
``--untouched-modules`` option, which lists the modules a run never called a function of.
(Scene builders and other helpers that test files import are in ``helpers.py``.)"""

from __future__ import annotations

import ast
import inspect
import multiprocessing.process
import os
import sys
import tempfile
import threading
from pathlib import Path

import pytest
from helpers import library_modules
from hypothesis import HealthCheck, settings

import ptlab
from ptlab.scene import Scene

# Property-based tests (tests/renderer/test_fuzz.py) run a fixed, derandomized set of examples by
# default, so that the suite's time and verdict are the same on every run, and keep no
# example database; Hypothesis's other files (caches) go to the temporary folder, not the
# checkout. HYPOTHESIS_PROFILE=long searches afresh, far longer.
os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY", str(Path(tempfile.gettempdir()) / "ptlab-hypothesis"))
_FUZZ = dict(
    database=None,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
settings.register_profile("fixed", max_examples=100, derandomize=True, **_FUZZ)
settings.register_profile("long", max_examples=2000, **_FUZZ)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fixed"))


# -- the layers: pyproject.toml's markers ----------------------------------------------------
# ``pytest -m "not slow"`` is the quick layer; ``subprocess`` marks every test that starts a
# process (a grader's child, the command as a program, a tutorial, a pool of workers). This
# process sees each start: os.fork, exec, spawn and subprocess.Popen through their audit
# events (PEP 578), and multiprocessing's starts (a fork server or ``spawn`` starts a process
# without an event here) through ``BaseProcess.start``.
PROCESS_EVENTS = {
    "os.fork",
    "os.forkpty",
    "os.exec",
    "os.posix_spawn",
    "os.spawn",
    "os.system",
    "subprocess.Popen",
}
_started: list[str] = []


def _audit(event: str, args) -> None:
    if event in PROCESS_EVENTS and not _looking_up_a_library():
        _started.append(event)


def _looking_up_a_library() -> bool:
    """True inside ``ctypes.util.find_library``, which runs ``ldconfig -p`` (the first render
    of a session does, in ``ptlab.rendering.memory``): not a process the test is about."""
    frame = sys._getframe(2)
    while frame is not None and frame.f_globals.get("__name__") != "ctypes.util":
        frame = frame.f_back
    return frame is not None


sys.addaudithook(_audit)
_start_process = multiprocessing.process.BaseProcess.start


def _recorded_start(self) -> None:
    _started.append("multiprocessing")
    _start_process(self)


multiprocessing.process.BaseProcess.start = _recorded_start


def pytest_runtest_setup(item) -> None:
    _started.clear()  # (before the test's fixtures of any scope are set up)
    if item.config.getoption("untouched_modules") and sys.gettrace() is not _record_call:
        sys.settrace(_record_call)  # (Hypothesis's explain phase leaves no tracer behind)


@pytest.fixture(autouse=True)
def _graders_speak_english():
    """The tests read the graders' English messages, whatever this machine's locale
    (``ptlab.course.messages``); a test of another language sets it itself."""
    from ptlab.course.messages import language

    with language("en"):
        yield


@pytest.fixture(autouse=True)
def marked_if_it_starts_processes(request):
    """Fail a test that started a process (its fixtures included) without the ``subprocess``
    marker, so that ``-m "not subprocess"`` and the marker's promise stay true."""
    yield
    if _started and request.node.get_closest_marker("subprocess") is None:
        pytest.fail(
            f"started processes ({', '.join(sorted(set(_started)))}) but is not "
            f"marked subprocess: add @pytest.mark.subprocess",
            pytrace=False,
        )


# -- does a run reach every module? ---------------------------------------------------------
# ``pytest -m "not slow" --untouched-modules`` records which functions of ptlab run in this
# process (sys.settrace, calls only: the run takes about twice as long) and fails the run if
# a module that defines functions had none of them called: the quick layer must touch every
# module, not just import it.

#: Modules whose functions run only in a student's process (``ptlab.course.sandbox.child`` sets
#: them up there), where this one cannot trace them; the quick layer grades in such
#: processes (course/test_sandbox.py, course/test_exercises.py).
ONLY_IN_STUDENTS_PROCESSES = {"ptlab.course.sandbox.confinement"}
_called: set = set()
_untouched: list[str] = []


def _record_call(frame, event: str, arg) -> None:
    _called.add(frame.f_code)  # (returning None: no line-by-line tracing)


def pytest_addoption(parser) -> None:
    parser.addoption(
        "--untouched-modules",
        action="store_true",
        help="fail the run if some module of ptlab had none of its functions called "
        "in this process (about twice as slow)",
    )


def pytest_configure(config) -> None:
    if config.getoption("untouched_modules"):
        threading.settrace(_record_call)
        sys.settrace(_record_call)


def untouched_modules(called: set) -> list[str]:
    """The library's modules that define a function and had none of them ``called`` (code
    objects): module and class bodies and comprehensions run on import, so they do not count."""
    ran = {
        code.co_filename
        for code in called
        if code.co_flags & inspect.CO_OPTIMIZED
        and (code.co_name == "<lambda>" or not code.co_name.startswith("<"))
    }
    return sorted(
        name
        for name, path in library_modules().items()
        if name not in ONLY_IN_STUDENTS_PROCESSES
        and str(path) not in ran
        and any(
            isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        )
    )


@pytest.hookimpl(tryfirst=True)
def pytest_sessionfinish(session) -> None:
    if session.config.getoption("untouched_modules"):
        sys.settrace(None)
        threading.settrace(None)
        _untouched[:] = untouched_modules(_called)
        if _untouched:
            session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_terminal_summary(terminalreporter, config) -> None:
    if config.getoption("untouched_modules"):
        terminalreporter.write_line(
            f"untouched modules: {', '.join(_untouched)}"
            if _untouched
            else "untouched modules: none (every module of ptlab had a function called)",
            red=bool(_untouched),
            green=not _untouched,
        )


@pytest.fixture(autouse=True)
def private_state_folder(tmp_path_factory, monkeypatch) -> None:
    """Keep 'ptlab exercise start' from recording the tests' folders in the user's own
    ~/.local/state/ptlab (where 'ptlab exercise list' would then look for them)."""
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path_factory.mktemp("state")))


@pytest.fixture(autouse=True)
def same_import_path():
    """Give ``sys.path`` back as the test found it. A grader run in this process (``grade``,
    ``ptlab grade``, ``ptlab exercise check``) takes the current folder off it; run from the
    checkout with an editable install, that is where ptlab is, and every process started
    later (Dask's workers, a pool) could not import it."""
    path = sys.path[:]
    yield
    sys.path[:] = path


@pytest.fixture(scope="session")
def cornell() -> Scene:
    return ptlab.load_scene("cornell-box")


def _is_multiprocessing_helper(pid: int) -> bool:
    """The fork server and resource tracker that the graders share for the whole session."""
    try:
        command = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return True  # gone meanwhile
    return b"multiprocessing.forkserver" in command or b"multiprocessing.resource_tracker" in command


@pytest.fixture
def nothing_left_behind():
    """After the test: no process below this one but multiprocessing's own helpers."""
    from ptlab.course.sandbox.processes import descendants, process_table

    yield
    below = descendants({os.getpid()}, process_table(alive_only=True)) - {os.getpid()}
    left = [pid for pid in below if not _is_multiprocessing_helper(pid)]
    assert left == [], [Path(f"/proc/{pid}/cmdline").read_bytes()[:200] for pid in left]
