"""The process that imports a student's file and runs its functions for the grader.

It is a fresh interpreter that ``ptlab.course.sandbox.submission`` starts in the student's
sandbox (``ptlab.course.sandbox.sandbox``), where the only ptlab is the chapter's kit
(``ptlab.course.sandbox.kit``); everything in it is the student's to change, and the grader
trusts nothing it says beyond the schema of ``ptlab.course.sandbox.plain_data``. ``main``

1. reads its setup (``ChildSetup``) from standard input, which the grader then closes;
2. asks to be killed if its parent goes, makes itself non-dumpable, lowers its resource
   limits (``Limits``) and adds the authorship hook (``ptlab.course.sandbox.confinement``);
3. imports the student's file (``import_file``) and says whether that worked;
4. serves requests until the grader closes the pipe: ``get`` and ``set`` an attribute of
   an object it holds (object 0 is the student's module), ``call`` a function or method,
   ``call_each`` a method of several objects on their rows, ``repr`` an object,
   ``import_by_stem`` the file again under its own name. While it serves them, it records
   the code that runs (``CodeRecorder``): each reply says what code ran for the first time,
   for the grader to compare with the files' text (``ptlab.course.sandbox.code_ran``).

A call's reply is its result, plus (for functions, not methods) the changes it made to its
arguments in place: arrays written into (the film that ``trace_paths`` adds to), fields of
the library's dataclasses given new values, a random generator's state. The grader copies
those into its own arguments, as if the function had run in its process.
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import importlib
import importlib.util
import inspect
import io
import json
import math
import os
import pickle
import resource
import signal
import sys
import threading
import traceback
import types
from collections.abc import Sequence
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from ptlab.course.sandbox.channel import ChannelClosedError, Reader, write_message
from ptlab.course.sandbox.confinement import Refused, confine
from ptlab.course.sandbox.copies import Answers
from ptlab.course.sandbox.ownership import MATERIAL_METHODS
from ptlab.course.sandbox.plain_data import RECORDS, Encoder, UnsendableError, frozen
from ptlab.errors import PtlabError
from ptlab.rendering.memory import keep_freed_memory

if TYPE_CHECKING:
    from ptlab.integrators.wavefront import SurfaceHit

#: The ptlab package: code under it is the library's own, not a student's.
PTLAB = Path(__file__).resolve().parents[2]
#: A graded class is ptlab's own answer if its MATERIAL_METHODS are all ptlab's (and not the
#: ``Material`` interface's, which only raise ``NotImplementedError``).
INTERFACE = PTLAB / "materials" / "base.py"
MAX_MESSAGE_TEXT = 2000
#: How ``code_record`` names the files of the student's folder and of ptlab (its kit, for
#: the grader): by their place inside them, whatever path this process sees them at.
SUBMISSION_FILE = "<submission>/"
PTLAB_FILE = "<ptlab>/"
PR_SET_PDEATHSIG = 1
PR_SET_DUMPABLE = 4


class GradeLoadError(PtlabError):
    """The student's file cannot be loaded: a syntax error, or an exception at import."""


@dataclass(frozen=True)
class Limits:
    """Resource limits of the student's process (``resource.setrlimit``), each inherited by
    every process it starts.

    Attributes:
        cpu_seconds: CPU time of each process (then SIGKILL).
        memory_bytes: address space of each process (allocations beyond fail: MemoryError).
        file_bytes: the largest file a process may write.
        processes: processes and threads the user may have beyond those of now (not
            enforced for root).
    """

    cpu_seconds: int = 600
    memory_bytes: int = 8 << 30
    file_bytes: int = 64 << 20
    processes: int = 512


@dataclass(frozen=True)
class ChildSetup:
    """What the grader tells the student's process before it starts (on its standard input).

    Attributes:
        path: the student's file, in the process's private folder.
        receive, send: the file descriptors of the grader's requests and of the replies.
        limits: its resource limits.
        answers: fingerprints of the answers it may not compile (the authorship hook).
        record_code: record the code that runs for the grader (``CodeRecorder``); not for
            ptlab's own answer files, graded as themselves.
    """

    path: str
    receive: int
    send: int
    limits: Limits
    answers: Answers
    record_code: bool = True


def import_file(path: Path):
    """Import a Python file as a module of its own; its folder is importable while it loads."""
    module_name = f"ptlab_graded_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise GradeLoadError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    folder = str(path.resolve().parent)
    sys.path.insert(0, folder)
    sys.modules[module_name] = module  # (dataclasses and pickling look modules up there)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as error:
        del sys.modules[module_name]
        raise GradeLoadError(f"{path.name}:{error.lineno}: syntax error: {error.msg}") from None
    except Refused as error:  # one of the grader's rules (ptlab.course.sandbox.confinement)
        sys.modules.pop(module_name, None)
        raise GradeLoadError(f"{path.name}: {_text(error)}") from None
    except BaseException as error:  # anything the student's module raises on import
        sys.modules.pop(module_name, None)
        raise GradeLoadError(
            f"{path.name}: importing it raised {type(error).__name__}: {_text(error)}"
        ) from None
    finally:
        sys.path.remove(folder)
    return module


def main() -> None:
    """The child's whole life: set up, import the student's file, answer until told to stop
    (``sandbox.BOOTSTRAP`` calls this once it is the student's user)."""
    setup = pickle.load(sys.stdin.buffer)  # (the grader's, written before any student code)
    if not isinstance(setup, ChildSetup):
        raise SystemExit("the grader sent no setup")
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    os.close(null)
    for stream in (sys.stdout, sys.stderr):
        if isinstance(stream, io.TextIOWrapper):  # (Python's own, unless its pipe is missing: None)
            stream.reconfigure(line_buffering=True)
    keep_freed_memory()  # every call's arrays arrive in new buffers: no page faults for them
    _set_up(setup)
    requests = Reader(setup.receive)
    path = Path(setup.path)
    recorder = CodeRecorder(path.resolve().parent) if setup.record_code else None
    server = _Server(path, setup.send, recorder)
    pid = os.getpid()  # (as this process's own code sees it: in its pid namespace)
    try:
        server.handles.append(import_file(Path(setup.path)))
    except GradeLoadError as error:
        server.send({"id": 0, "import_failed": str(error)})
        return
    server.send({"id": 0, "ready": True, "pid": pid})
    while True:
        try:
            parts = requests.read_message()
        except ChannelClosedError:
            return
        server.answer(parts)


def _set_up(setup: ChildSetup) -> None:
    """Step 2 of the module docstring: the parent-death signal and non-dumpability (a
    change of user clears both, so after it), then the limits, then the hook."""
    if sys.platform.startswith("linux"):
        libc = ctypes.CDLL(None)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        libc.prctl(PR_SET_DUMPABLE, 0, 0, 0, 0)
    limits = setup.limits
    for name, value in (
        (resource.RLIMIT_CPU, limits.cpu_seconds),
        (resource.RLIMIT_AS, limits.memory_bytes),
        (resource.RLIMIT_FSIZE, limits.file_bytes),
        (resource.RLIMIT_CORE, 0),
        (resource.RLIMIT_NPROC, _user_tasks() + limits.processes),
    ):
        _lower_limit(name, value)
    confine(setup.answers)


def _lower_limit(name: int, value: int) -> None:
    _soft, hard = resource.getrlimit(name)
    if hard != resource.RLIM_INFINITY:
        value = min(value, hard)
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(name, (value, value))


def _user_tasks() -> int:
    """Processes and threads of this user now (what RLIMIT_NPROC counts; 0 without /proc)."""
    uid, count = os.getuid(), 0
    if not Path("/proc/self").is_dir():
        return 0
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if entry.stat().st_uid == uid:
                    count += len(os.listdir(entry / "task"))
            except OSError:
                pass
    return count


class _Server:
    """Answers the grader's requests about the objects it holds (``handles``)."""

    def __init__(self, path: Path, send_fd: int, recorder: CodeRecorder | None = None):
        self.path, self.send_fd, self.recorder = path, send_fd, recorder
        self.handles: list = []
        self.shared: dict[int, object] = {}

    def send(self, envelope: dict, parts: Sequence = ()) -> None:
        write_message(self.send_fd, [json.dumps(envelope).encode(), *parts])

    def keep(self, value) -> int:
        self.handles.append(value)
        return len(self.handles) - 1

    def answer(self, parts) -> None:
        request_id = int.from_bytes(parts[0], "little")
        try:
            operation, *arguments = _Unpickler(parts[1], self, parts[2:]).load()
        except Exception as error:  # the grader sent what this process cannot rebuild
            envelope = {"id": request_id, "unreceived": f"{type(error).__name__}: {_text(error)}"}
            if self.recorder is not None:
                envelope["ran"] = self.recorder.new_records()
            self.send(envelope)
            return
        encoder = Encoder(self.keep, self.describe)
        recording = self.recorder.recording() if self.recorder is not None else contextlib.nullcontext()
        try:
            with recording:
                envelope = getattr(self, f"do_{operation}")(encoder, *arguments)
        except UnsendableError as error:
            envelope = {"unreadable": str(error)}
        except BaseException as error:  # the student's code raised: report it
            envelope = {"raised": self.describe_error(error)}
        if self.recorder is not None:
            envelope["ran"] = self.recorder.new_records()
        self.send(dict(id=request_id, **envelope), encoder.parts)

    # -- requests ----------------------------------------------------------------------

    def do_get(self, encoder: Encoder, handle: int, name: str) -> dict:
        return {"value": encoder.encode(getattr(self.handles[handle], name))}

    def do_set(self, encoder: Encoder, handle: int, name: str, value) -> dict:
        setattr(self.handles[handle], name, value)
        return {"value": None}

    def do_repr(self, encoder: Encoder, handle: int) -> dict:
        return {"value": repr(self.handles[handle])[:200]}

    def do_call(self, encoder: Encoder, handle: int, args: tuple, kwargs: dict, writeback: bool) -> dict:
        before = _Snapshot(args, kwargs) if writeback else None
        with _counting_nonfinite() as nonfinite:
            result = self.handles[handle](*args, **kwargs)
        envelope = {"value": encoder.encode(result)}
        if nonfinite is not None and nonfinite.count:
            # The samples ``add_to_film`` left out in this process, for the grader to count as
            # its own (a render's tally is the grader's): film rows and depths.
            rows, depths = np.concatenate(nonfinite.rows), np.concatenate(nonfinite.depths)
            envelope["nonfinite"] = encoder.encode([rows.astype(np.int64), depths.astype(np.int64)])
        if before is not None:
            envelope["writeback"] = [
                [path, how, encoder.encode(value)] for path, how, value in before.changes()
            ]
        return envelope

    def do_call_each(
        self, encoder: Encoder, handles: list[int], which: np.ndarray, method: str, args: tuple
    ) -> dict:
        """``method`` of several objects, each on its rows (``which[k]`` is the object of row
        k): the library's ``shade``, here, so that all the rows take one request."""
        from types import SimpleNamespace

        from ptlab.integrators.wavefront import shade

        groups = [(np.flatnonzero(which == k), self.handles[h]) for k, h in enumerate(handles)]
        hit = SimpleNamespace(prim=which, materials=[g for g in groups if len(g[0])])
        # (A SurfaceHit as far as shade reads one: its prim and its materials' groups.)
        return {"value": encoder.encode(shade(cast("SurfaceHit", hit), method, *args))}

    def do_import_by_stem(self, encoder: Encoder) -> dict:
        """The student's file imported again under its own name (``08_parallel``), with its
        folder on ``sys.path`` for good, so that processes it starts can import it too."""
        folder = str(self.path.resolve().parent)
        if folder not in sys.path:
            sys.path.insert(0, folder)
        module = importlib.import_module(self.path.stem)
        found = Path(getattr(module, "__file__", "") or "")
        if found.resolve() != self.path.resolve():
            return {"value": encoder.encode({"taken_by": str(found) or "Python itself"})}
        return {"value": encoder.encode(module)}

    # -- descriptions ------------------------------------------------------------------

    def describe(self, value) -> dict:
        """A callable's name, kind, parameters and, if it is ptlab's own, where it is from."""
        kind = "class" if inspect.isclass(value) else "method" if inspect.ismethod(value) else "function"
        try:
            parameters = [[p.name, int(p.kind)] for p in inspect.signature(value).parameters.values()]
        except (TypeError, ValueError):
            parameters = None
        name = getattr(value, "__qualname__", None)
        return {
            "name": name if isinstance(name, str) else type(value).__name__,
            "kind": kind,
            "origin": self.library_origin(value),
            "parameters": parameters,
        }

    def library_origin(self, value) -> str | None:
        """``module.name`` if ``value`` is ptlab's own function, or a class whose material
        methods are all ptlab's; None if it is (at least partly) the student's."""
        if inspect.isclass(value):
            methods = [getattr(value, name, None) for name in MATERIAL_METHODS]
            files = [_code_file(m) for m in methods]
            if all(f is not None and self._is_library(f) and f != INTERFACE for f in files):
                return f"{value.__module__}.{value.__qualname__}"
            return None
        file = _code_file(value)
        if file is not None and self._is_library(file):
            return f"{getattr(value, '__module__', '?')}.{getattr(value, '__qualname__', '?')}"
        return None

    def _is_library(self, file: Path) -> bool:
        return file.is_relative_to(PTLAB) and file != self.path.resolve()

    def describe_error(self, error: BaseException) -> dict:
        return {
            "type": type(error).__name__,
            "message": _text(error),
            "where": self.where(error),
            "not_implemented": isinstance(error, NotImplementedError),
        }

    def where(self, error: BaseException) -> str | None:
        """``file.py:line`` of the deepest frame of the student's file in the traceback
        (from the frames alone: reading the source lines of ptlab's files is refused)."""
        graded = str(self.path.resolve())
        lines = [
            line
            for frame, line in traceback.walk_tb(error.__traceback__)
            if os.path.realpath(frame.f_code.co_filename) == graded
        ]
        return f"{self.path.name}:{lines[-1]}" if lines else None


@contextlib.contextmanager
def _counting_nonfinite():
    """``counting_nonfinite`` around a call, if the student's code has the film's module (it
    is not imported for it: chapters that never touch a film pay nothing); else None."""
    wavefront = sys.modules.get("ptlab.integrators.wavefront")
    if wavefront is None:
        yield None
        return
    with wavefront.counting_nonfinite() as nonfinite:
        yield nonfinite


def _code_file(value) -> Path | None:
    """The source file of a function (or method, or partial), if it has Python code."""
    for _ in range(5):
        value = getattr(value, "__func__", None) or getattr(value, "func", None) or value
        code = getattr(value, "__code__", None)
        if code is not None:
            return Path(code.co_filename).resolve()
    return None


def code_digest(code: types.CodeType) -> str:
    """What a code object runs, as a SHA-256 (hex): its bytecode, names, layout and constants
    (nested code by their own digests), not its file's name nor its line numbers. The grader
    compiles a file's text itself and compares (``ptlab.course.sandbox.code_ran``): the same in
    every process of the same Python, whether the code was compiled from the source or
    loaded from its ``.pyc``."""
    digest = hashlib.sha256()
    layout = (
        code.co_code,  # (the bytecode as compiled: Python 3.11 keeps its specialised copy apart)
        code.co_names,
        code.co_varnames,
        code.co_freevars,
        code.co_cellvars,
        code.co_argcount,
        code.co_posonlyargcount,
        code.co_kwonlyargcount,
        code.co_flags,
        code.co_qualname,
        code.co_exceptiontable,
    )
    digest.update(repr(layout).encode())
    for constant in code.co_consts:
        digest.update(_constant_key(constant).encode())
    return digest.hexdigest()


def _constant_key(constant) -> str:
    """A constant as text, the same in every process: nested code by its digest, the items of
    a frozenset in sorted order (its order of iteration changes with the hash seed)."""
    kind = type(constant)
    if kind is types.CodeType:
        return f"code {code_digest(constant)}"
    if kind is tuple or kind is frozenset:
        items = [_constant_key(item) for item in constant]
        return f"{kind.__name__}({','.join(sorted(items) if kind is frozenset else items)})"
    return f"{kind.__name__} {constant!r}"


class CodeRecorder:
    """The code objects that run while this process serves the grader's requests, and the
    modules it loads from the student's folder, for the grader to compare with the files'
    text (``ptlab.course.sandbox.code_ran``).

    A trace function (``sys.settrace``) sees every Python function, method, lambda,
    comprehension and generator as its frame starts, whatever called it: a function kept
    in a dict, a slot, a library's wrapper. It asks for no line events (it returns None),
    so each call costs one dict store; it runs on this thread during requests only, and
    in every thread the student's code starts (``threading.settrace``), but not in
    processes it forks. The student's code runs in this process and could turn it off or
    change what it says: the grader's reading of the file's text, which refuses every way
    to reach it, comes first (``ptlab.course.sandbox.readable``).
    """

    def __init__(self, folder: Path):
        self.folder = str(folder)
        self.ptlab = str(PTLAB)
        #: {id: code object}, in the order they first ran (kept alive: no id is reused).
        self.ran: dict[int, types.CodeType] = {}
        self.sent = 0
        self.modules: set[str] = set()
        self.trace = _tracer(self.ran)
        threading.settrace(self.trace)
        os.register_at_fork(after_in_child=_stop_tracing)

    @contextlib.contextmanager
    def recording(self):
        """Record on this thread while the block runs."""
        sys.settrace(self.trace)
        try:
            yield
        finally:
            sys.settrace(None)

    def new_records(self) -> list[list]:
        """``code_record`` of the code that ran since the last call, and of the modules
        loaded from the student's folder since then."""
        ran = list(self.ran.values())  # (a copy in one step: other threads may be adding)
        found = [code_record(code, self._file(code.co_filename)) for code in ran[self.sent :]]
        self.sent = len(ran)
        for name, module in list(sys.modules.items()):
            if name not in self.modules:
                self.modules.add(name)
                file = getattr(module, "__file__", None)
                if isinstance(file, str) and not _is_libraries(file):
                    found.append([self._file(file), 0, "<module file>", "", []])
        return found

    def _file(self, file: str) -> str:
        """A file as the records name it: one of the student's folder as ``SUBMISSION_FILE``
        and its name, one of ptlab as ``PTLAB_FILE`` and its path in the package."""
        if file.startswith("<"):
            return file  # (a string compiled, <string>; a frozen module)
        real = os.path.realpath(file)
        for root, name in ((self.folder, SUBMISSION_FILE), (self.ptlab, PTLAB_FILE)):
            if real.startswith(root + os.sep):
                return name + os.path.relpath(real, root)
        return real


def _tracer(ran: dict):
    """The trace function: records the code of every frame that starts (a closure, which
    is as cheap as a call gets)."""

    def trace(frame, event, argument):
        ran[id(frame.f_code)] = frame.f_code

    return trace


def _stop_tracing() -> None:
    """In a process the student's code forks (a pool's worker): no recording, which no one
    would read (the grader reads what this process replies)."""
    sys.settrace(None)
    threading.settrace(None)


def _is_libraries(file: str) -> bool:
    """Whether a module's file is Python's own or an installed package's, as far as this
    process can tell cheaply: the grader checks every one that is not."""
    return file.startswith((sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix))


def code_record(code: types.CodeType, file: str) -> list:
    """What the grader needs to find ``code`` in the file it says it is from (named
    ``file``): [file, first line, qualified name, ``code_digest``, and for code compiled
    from a string the names of its variables and of those of the code it holds, from
    which the grader writes a named tuple's ``__new__`` again]."""
    names = []
    if file.startswith("<"):
        inner = [c for c in code.co_consts if type(c) is types.CodeType]
        names = [*code.co_varnames, *(name for c in inner for name in c.co_varnames)]
    return [file, code.co_firstlineno, code.co_qualname, code_digest(code), names]


def _text(error: BaseException) -> str:
    try:
        return str(error)[:MAX_MESSAGE_TEXT]
    except BaseException:
        return f"(a {type(error).__name__} whose message cannot be shown)"


class _Unpickler(pickle.Unpickler):
    """Unpickles the grader's requests (trusted data), resolving the grader's references to
    objects held here (``handle``), to objects sent once per check (``shared``), to arrays
    sent as raw bytes in the message's other parts (``array``), and to arrays sent as their
    one repeated row (``rows``)."""

    def __init__(self, data, server: _Server, arrays: list):
        super().__init__(io.BytesIO(data))
        self.server, self.arrays = server, arrays

    def persistent_load(self, pid):
        if isinstance(pid, str):  # "array <part> <dtype> <shape> <order>"
            _, part, dtype, shape, order = pid.split(" ")
            dtype, shape = np.dtype(dtype), tuple(int(n) for n in shape.split(",") if n)
            count = math.prod(shape)
            if count == 0:
                return np.empty(shape, dtype, order=order)
            return np.frombuffer(self.arrays[int(part)], dtype, count).reshape(shape, order=order)
        kind, key, *payload = pid
        if kind == "handle":
            return self.server.handles[key]
        if kind == "rows":  # an array whose rows are all ``key`` (one row)
            rows, order = payload
            array = np.empty((rows, key.shape[1]), key.dtype, order=order)
            array[...] = key
            return array
        if kind == "shared":
            if payload:
                self.server.shared[key] = _Unpickler(payload[0], self.server, self.arrays).load()
            return self.server.shared[key]
        raise pickle.UnpicklingError(f"unknown reference {kind!r}")


class _Snapshot:
    """What a call may change in its arguments: arrays (by content), fields of the
    library's records and items of lists and dicts (by identity), random generators (by
    state). ``changes()`` lists what differs after the call as (path, how, new value)."""

    def __init__(self, args: tuple, kwargs: dict):
        self.entries: list[tuple] = []
        # The paths start in the call's (args, kwargs); those two themselves the function
        # cannot change for its caller.
        for k, value in enumerate(args):
            self._walk(value, [("item", 0), ("item", k)], 0)
        for name, value in kwargs.items():
            self._walk(value, [("item", 1), ("key", name)], 0)

    def _walk(self, value, path: list, depth: int) -> None:
        if isinstance(value, np.ndarray):
            self.entries.append((path, "array", value, value.copy(order="K")))
        elif isinstance(value, np.random.Generator):
            self.entries.append((path, "state", value, repr(value.bit_generator.state)))
        elif depth < 4:
            for step, child in _children(value):
                if _rebindable(value):
                    self.entries.append(([*path, step], "identity", value, child))
                self._walk(child, [*path, step], depth + 1)

    def changes(self) -> list[tuple]:
        found = []
        for path, how, value, before in self.entries:
            if how == "array" and not _same_bits(value, before):
                found.append((path, "array", value))
            elif how == "state" and repr(value.bit_generator.state) != before:
                found.append((path, "state", value.bit_generator.state))
            elif how == "identity":
                now = dict(_children(value)).get(path[-1], _MISSING)
                if now is not before and now is not _MISSING:
                    found.append((path, "value", now))
        return found


_MISSING = object()
#: Arrays smaller than this are compared as bytes (NumPy's comparison costs more to start).
SMALL_ARRAY = 1 << 16


def _same_bits(array: np.ndarray, before: np.ndarray) -> bool:
    """Whether ``array`` still holds, bit for bit, what its copy ``before`` holds (compared
    as unsigned integers, so that NaN equals NaN and -0.0 differs from 0.0; 10x faster than
    comparing ``tobytes()``, which reorders a column-major array)."""
    if array.shape != before.shape or array.dtype != before.dtype:
        return False
    if array.nbytes < SMALL_ARRAY or array.dtype.itemsize not in (1, 2, 4, 8):
        return array.tobytes() == before.tobytes()
    bits = f"u{array.dtype.itemsize}"
    return bool(np.array_equal(array.view(bits), before.view(bits)))


def _children(value) -> list[tuple]:
    """The (step, child) pairs the snapshot looks into: the call's (args, kwargs), list
    and tuple items, string-keyed dict items, fields of the library's records."""
    if isinstance(value, list | tuple):
        return [(("item", k), v) for k, v in enumerate(value)]
    if isinstance(value, dict):
        return [(("key", k), v) for k, v in value.items() if isinstance(k, str)]
    if is_dataclass(value) and type(value) in RECORDS.values():
        return [(("field", f.name), getattr(value, f.name)) for f in fields(value)]
    return []


def _rebindable(value) -> bool:
    """Whether a call can give ``value`` a new item or field (a list, a dict, a record
    that is not frozen)."""
    if isinstance(value, list | dict):
        return True
    return is_dataclass(value) and not frozen(value)
