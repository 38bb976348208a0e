"""A student's file, imported in a process of its own, and the grader's end of the talk.

``Submission(path, ...)`` reads the submission once (``ptlab.course.sandbox.intake``: a syntax
error is reported without running anything), starts a fresh interpreter for it in the
student's sandbox (``ptlab.course.sandbox.sandbox``: a private folder holding the submission's
files, the chapter's kit in ptlab's place, namespaces of its own, the student's user when
the grader is root; ``ptlab.course.sandbox.child``); waits, at most the import's own time
limit, for it to import the file; and gives the grader ``submission.module``, a stand-in
for the student's module (``ptlab.course.sandbox.proxies``).

Every request is pickled to the student's process (which may unpickle the grader's data:
it is the grader's), and every reply is plain data (``ptlab.course.sandbox.plain_data``), by a
deadline: the check's time limit, and a limit per call. A reply that is late, missing (the
process ended) or malformed raises ``SubmissionFailed``, which ends the check: it is a
``BaseException``, so that no ``except Exception`` in the grader's code takes it for a
mistake of one call and goes on. ``close()`` ends the process and everything it started
(``ptlab.course.sandbox.processes``) and closes the pipes.

Objects sent in many calls and never changed (a ``Scene``, a ray-query structure) cross
once per check: later requests refer to the copy the student's process already has. An
Embree structure cannot be pickled and is rebuilt there from its triangles.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import pickle
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Literal, NoReturn

import numpy as np

import ptlab.course.sandbox.sandbox as sandbox
from ptlab.course.sandbox.channel import (
    Channel,
    ChannelClosedError,
    ChannelError,
    ChannelTimeoutError,
    enlarge,
)
from ptlab.course.sandbox.child import ChildSetup, Limits
from ptlab.course.sandbox.code_ran import CodeRan
from ptlab.course.sandbox.copies import copies_in, describe_copies, is_a_copy
from ptlab.course.sandbox.intake import RefusedSubmission, Taken, private_folder, remove_folder, take_in
from ptlab.course.sandbox.kit import kit_for
from ptlab.course.sandbox.ownership import library_answer as borrowed_answer
from ptlab.course.sandbox.plain_data import RECORDS, Decoder, MalformedError, frozen
from ptlab.course.sandbox.processes import LINUX, ProcessGuard, process_table
from ptlab.course.sandbox.proxies import (
    STAND_INS,
    ArgumentChanged,
    RemoteFunction,
    RemoteModule,
    RemoteObject,
    StudentError,
    remote_object,
    student_error,
)
from ptlab.course.sandbox.proxies import submission_of as process_of
from ptlab.course.sandbox.readable import Unreadable, unreadable_in_text
from ptlab.course.sandbox.rules import Arguments, Rules
from ptlab.course.sandbox.student_user import StudentUser, student_user
from ptlab.rendering.memory import keep_freed_memory

#: Environment variables the student's process keeps (the rest may hold the grader's secrets).
KEPT_ENVIRONMENT = (
    "PATH",
    "LANG",
    "LC_ALL",
    "LC_CTYPE",
    "TZ",
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
)
#: The largest reply, in bytes (a few renders' worth of arrays).
MAX_REPLY = 1 << 30
#: Seconds the import of the student's file may take, at most (less if the check's whole
#: limit is less): a file that hangs at import fails within it.
IMPORT_TIME_LIMIT = 60.0


class SubmissionFailed(BaseException):
    """The student's process cannot go on: too slow, ended, or a reply out of the schema.

    Attributes:
        kind: ``"timeout"``, ``"ended"``, ``"malformed"`` or ``"import"``.
        during: what the grader was asking for (``"Lambertian.eval"``), or None.
    """

    def __init__(self, message: str, kind: str, during: str | None = None):
        super().__init__(message)
        self.kind, self.during = kind, during


class ImportFailed(SubmissionFailed):
    """The student's file cannot be imported (a syntax error, an exception at import, a
    submission that is refused, or an import that took longer than its limit: ``kind``
    ``"import"``, or ``"import timeout"``)."""

    def __init__(self, message: str, kind: str = "import"):
        super().__init__(message, kind)


class UnreadableResultError(StudentError):
    """The student's function returned something the schema cannot carry."""


class UnreadableCode(SubmissionFailed):
    """A graded name whose code the grader cannot read in the submission's files
    (``ptlab.course.sandbox.readable``): the check that uses it earns nothing, and its message
    asks for a teacher's look. Like every ``SubmissionFailed``, it ends the check (no
    ``except Exception`` of a check takes it for one call's mistake), and every later
    request of the same process raises it again.

    Attributes:
        name: the graded name, or the function whose call ran the code.
        why: the reason (``ptlab.course.sandbox.readable.Unreadable``).
    """

    def __init__(self, name: str, why: Unreadable):
        super().__init__(why.message(name), "unreadable", name)
        self.name, self.why = name, why


def shared_types() -> frozenset[type]:
    """The classes whose objects cross once per check (see the module docstring)."""
    from ptlab.accel.numpy_bvh import NumpyBVH
    from ptlab.scene import Scene

    kinds = [Scene, NumpyBVH]
    try:
        from ptlab.accel.embree import EmbreeAccelerator

        kinds.append(EmbreeAccelerator)
    except ImportError:  # no Embree here: nothing of that kind to send
        pass
    return frozenset(kinds)


def _is_pool_helper(pid: int) -> bool:
    """Is ``pid`` multiprocessing's resource tracker or fork server (``python -c "from
    multiprocessing.resource_tracker import main; ..."``)? By its command line, which the
    student's code could give a process of its own too: that process would then outlive a
    check's pool, not the check."""
    try:
        arguments = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:  # gone meanwhile
        return False
    helpers = (
        b"from multiprocessing.resource_tracker import main",
        b"from multiprocessing.forkserver import main",
    )
    command = arguments.index(b"-c") + 1 if b"-c" in arguments else len(arguments)
    return command < len(arguments) and arguments[command].startswith(helpers)


class Submission:
    """The student's submission, imported in a process of its own.

    Args:
        submission: the student's Python file, or the ``Taken`` submission read already
            (``ptlab.course.sandbox.intake.take_in``, once for all the checks of a grading).
        guard: the ``ProcessGuard`` that ends the process and all it starts.
        time_limit: seconds, from when the process has started, by which everything asked
            of it must be done.
        call_time_limit: seconds any one request may take (default: the whole ``time_limit``).
        on_output: called with each line the student's code prints (default: dropped).
        limits: the process's resource limits.
        rules: what the grader asks of the submission (``ptlab.course.sandbox.rules``).
        user: the user the student's code runs as, by name (``--student-user``) or a
            ``StudentUser`` (``student_user``); None for the default: ``nobody`` when the
            grader is root, else the grader's own user.
        import_time_limit: seconds the import may take (default ``IMPORT_TIME_LIMIT``, or
            ``time_limit`` if that is less).

    Raises:
        ImportFailed: the submission is refused, has a syntax error, or importing it raised
            or took too long.
    """

    def __init__(
        self,
        submission: str | Path | Taken,
        guard: ProcessGuard,
        time_limit: float,
        call_time_limit: float | None = None,
        on_output: Callable[[str], None] | None = None,
        limits: Limits | None = None,
        *,
        rules: Rules | None = None,
        user: str | StudentUser | None = None,
        import_time_limit: float | None = None,
    ):
        self.rules = rules or Rules()
        try:
            self.taken = (
                submission
                if isinstance(submission, Taken)
                else take_in(submission, library=self.rules.library)
            )
        except RefusedSubmission as refused:
            raise ImportFailed(str(refused)) from None
        self.path = self.taken.path
        self.tree = self.taken.tree
        self.library_answers_allowed = self.rules.library
        #: Whether the student's code runs in namespaces of its own (``sandbox.missing``):
        #: only then are its results for credit.
        self.sandboxed = sandbox.missing() is None
        # Without the sandbox the student's process could not read a Python under /root as
        # another user: it stays the grader's (and the result is not for credit).
        self.user = student_user(user) if self.sandboxed else None
        self.guard = guard
        self.time_limit = time_limit
        self.call_time_limit = call_time_limit
        self._requests = 0
        self._failure: SubmissionFailed | None = None
        self._shared: dict[int, tuple[int, object]] = {}
        self._shared_types = shared_types()
        self._special: tuple[int, frozenset[type]] | None = None
        # The student's folder: in the sandbox, made in memory there; else one of the grader's.
        self.folder = sandbox.FOLDER if self.sandboxed else private_folder(self.taken, self.user)
        try:
            self.process, self.channel = self._start(
                on_output, limits or Limits(cpu_seconds=int(time_limit) + 10)
            )
        except BaseException:
            self._remove_folder()
            raise
        # From here (the interpreter's start and the kit's imports count: about 0.2 s).
        started = time.monotonic()
        self.deadline = started + time_limit
        self.module = RemoteModule(self)
        self._wait_until_imported(started + min(import_time_limit or IMPORT_TIME_LIMIT, time_limit))

    # -- starting and ending -------------------------------------------------------------

    def _start(self, on_output, limits: Limits):
        keep_freed_memory()  # replies arrive in new buffers, as they do in the student's process
        self.guard.trust_current_children()
        request_r, request_w = os.pipe()
        reply_r, reply_w = os.pipe()
        output_r, output_w = os.pipe()
        for fd in (request_w, reply_w):
            enlarge(fd)
        #: The chapter's kit, which the student's process sees as ptlab.
        self.kit = kit_for(self.rules.left_out)
        view = sandbox.View(self.kit, self.taken.files, self.folder, self.rules.packages)
        #: The check of the code each reply says ran (``ptlab.course.sandbox.code_ran``); none for
        #: ptlab's own answer files.
        self.code_ran = (
            None if self.library_answers_allowed else CodeRan(self.taken, self.kit, self.rules.packages)
        )
        setup = ChildSetup(
            path=str(self.folder / self.taken.name),
            receive=request_r,
            send=reply_w,
            limits=limits,
            answers=self.rules.fingerprints,
            record_code=self.code_ran is not None,
        )
        environment = {name: os.environ[name] for name in KEPT_ENVIRONMENT if name in os.environ}
        scratch = "/tmp" if self.sandboxed else str(self.folder)  # (the sandbox's /tmp is its own)
        environment.update(HOME=str(self.folder), TMPDIR=scratch)
        cwd = "/" if self.sandboxed else self.folder
        try:
            process = sandbox.start(
                view,
                self.user,
                pass_fds=(request_r, reply_w),
                stdin=subprocess.PIPE,
                stdout=output_w,
                stderr=output_w,
                cwd=cwd,
                env=environment,
                start_new_session=True,
            )
        finally:
            for fd in (request_r, reply_w, output_w):
                os.close(fd)
        try:
            if process.stdin is not None:  # (always: stdin is a pipe)
                process.stdin.write(pickle.dumps(setup))
                process.stdin.close()
        except OSError:  # it ended at once: waiting for its import says how
            pass
        return process, Channel(request_w, reply_r, output_r, on_output)

    @property
    def pid(self) -> int:
        """The student's process."""
        return self.process.pid

    def close(self) -> None:
        """End the student's process and every process below it; close the pipes; remove
        its private folder."""
        self.guard.end(self.process.pid)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(5)
        self.channel.close()
        self._remove_folder()

    def _remove_folder(self) -> None:
        """Remove the student's folder where it is the grader's (the sandbox's ends with it)."""
        if not self.sandboxed:
            remove_folder(self.folder)

    def __enter__(self) -> Submission:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def end_started_processes(self) -> None:
        """End the processes the student's code started (its pools), not the process itself
        (in the sandbox, the student's Python is the grandchild of bubblewrap's process)
        nor multiprocessing's helpers of that process (``_is_pool_helper``), only what runs
        below them: multiprocessing starts its resource tracker and fork server once, for
        every later pool, and warned "resource_tracker: process died unexpectedly" at the
        next pool after they were ended. They end with the student's process (``close``)."""
        if LINUX:
            table = process_table()
            student = self.pid
            chain = {student}
            for _ in range(2 if self.sandboxed else 0):
                children = [pid for pid, parent in table.items() if parent == student]
                if len(children) != 1:
                    return
                student = children[0]
                chain.add(student)
            started = {pid for pid, parent in table.items() if parent == student}
            helpers = {pid for pid in started if _is_pool_helper(pid)}
            below_helpers = {pid for pid, parent in table.items() if parent in helpers}
            self.guard.end(*(started - helpers), *below_helpers, keep=chain | helpers)

    def import_by_file_name(self) -> RemoteModule | str:
        """The student's file imported again in its process, under its own name
        (``08_parallel``) with its folder on ``sys.path``, so that the processes the
        student's code starts can import it; or, if another module has that name, where
        that module is from."""
        found = self.request("import_by_stem", during=f"importing {self.path.name} by name")
        if isinstance(found, RemoteObject) and found._type_name == "module":
            return RemoteModule(self, found._handle)
        if isinstance(found, dict) and isinstance(found.get("taken_by"), str):
            return found["taken_by"]
        self._fail("malformed", f"importing {self.path.name} by name", "not a module")

    def _wait_until_imported(self, deadline: float) -> None:
        try:
            envelope, _ = self._receive(0, "importing your file", deadline)
        except SubmissionFailed as failure:
            self.close()
            if failure.kind == "timeout":
                limit = deadline - (self.deadline - self.time_limit)
                raise ImportFailed(
                    f"importing {self.path.name} took longer than {limit:.3g} s "
                    f"(does it run something at import?)",
                    "import timeout",
                ) from None
            raise ImportFailed(str(failure)) from None
        if "import_failed" in envelope and type(envelope["import_failed"]) is str:
            self.close()
            raise ImportFailed(_collapse_whitespace(envelope["import_failed"]))
        if envelope.get("ready") is not True or type(envelope.get("pid")) is not int:
            self.close()
            raise ImportFailed(f"importing {self.path.name}: the process sent a malformed reply")
        #: The student's process's id as its own code sees it (in the sandbox, in a pid
        #: namespace of its own), for checks of what that code reports of its processes.
        self.own_pid: int = envelope["pid"]

    # -- requests ------------------------------------------------------------------------

    def call(self, function: RemoteFunction, args: tuple, kwargs: dict):
        """Run the student's ``function`` on the grader's arguments. A graded function's
        changes to the arguments it writes (``Rules.arguments``) are copied into them here;
        a change to one it may only read fails the check (``ArgumentChanged``)."""
        arguments = function.arguments if function.kind == "function" else None
        value, changes = self.request(
            "call",
            function._handle,
            args,
            kwargs,
            arguments is not None,
            during=function.__name__,
            changes=True,
        )
        if arguments is not None:
            self._take_changes((args, kwargs), changes, arguments, function.__name__)
        return value

    def call_each(self, objects: list[RemoteObject], which: np.ndarray, method: str, *args):
        """``objects[which[k]].<method>`` on row k of ``args``, for all rows in one request
        (materials of the student's that shade one batch of hits)."""
        return self.request(
            "call_each",
            [o._handle for o in objects],
            which,
            method,
            args,
            during=f"{objects[0]._type_name}.{method}",
        )

    def request(self, operation: str, *arguments, during: str, changes: bool = False):
        """Send one request and return its decoded answer (with ``changes``: and the
        call's changes to its arguments)."""
        if self._failure is not None:
            raise self._failure
        self._requests += 1
        deadline, limit = self.deadline, self.time_limit
        if self.call_time_limit is not None and time.monotonic() + self.call_time_limit < deadline:
            deadline, limit = time.monotonic() + self.call_time_limit, self.call_time_limit
        parts = self._pickle((operation, *arguments))
        try:
            self.channel.send([self._requests.to_bytes(8, "little"), *parts], deadline)
        except ChannelTimeoutError:
            self._fail("timeout", during, limit=limit)
        except ChannelClosedError:
            self._fail("ended", during)
        envelope, decoder = self._receive(self._requests, during, deadline, limit)
        try:
            self._check_what_ran(envelope, during)
            self._raise_what_went_wrong(envelope, during)
            if "value" not in envelope:
                raise MalformedError("a reply without a value")
            value = decoder.decode(envelope["value"])
            if "nonfinite" in envelope:
                _count_nonfinite(decoder.decode(envelope["nonfinite"]))
            if not changes:
                return value
            found = envelope.get("writeback", [])
            if type(found) is not list:
                raise MalformedError("a call's changes that are not a list")
            return value, [self._change(entry, decoder) for entry in found]
        except MalformedError as error:
            self._fail("malformed", during, str(error))

    def _check_what_ran(self, envelope: dict, during: str) -> None:
        """Raise ``UnreadableCode`` (for good) if the code the reply says ran is not the
        grader's own code at the places it names (``ptlab.course.sandbox.code_ran``)."""
        if self.code_ran is None:
            return
        if "ran" not in envelope:
            raise MalformedError("a reply that does not say what code ran")
        why = self.code_ran.check(envelope["ran"])  # (plain JSON, checked there)
        if why is not None:
            self._failure = UnreadableCode(during, why)
            raise self._failure

    def _raise_what_went_wrong(self, envelope: dict, during: str) -> None:
        """Raise what a reply says went wrong: the student's code raised, its result cannot
        be sent, or the grader's arguments could not be received."""
        if "raised" in envelope:
            raise self._student_error(envelope["raised"])
        if "unreadable" in envelope and type(envelope["unreadable"]) is str:
            returned = f"{during} returned {envelope['unreadable']}"
            raise UnreadableResultError("TypeError", returned, None, False)
        if "unreceived" in envelope:
            raise RuntimeError(
                f"the grader could not send {during} its arguments: "
                f"{_collapse_whitespace(str(envelope['unreceived']))}"
            )

    def _receive(
        self, request_id: int, during: str, deadline: float | None = None, limit: float | None = None
    ):
        deadline = self.deadline if deadline is None else deadline
        try:
            parts = self.channel.receive(deadline, MAX_REPLY)
        except ChannelTimeoutError:
            self._fail("timeout", during, limit=limit)
        except ChannelClosedError:
            self._fail("ended", during)
        except ChannelError as error:
            self._fail("malformed", during, str(error))
        try:
            if not parts:
                raise MalformedError("an empty reply")
            envelope = json.loads(bytes(parts[0]))
            if type(envelope) is not dict or envelope.get("id") != request_id:
                raise MalformedError("a reply that does not answer the request")
        except (ValueError, RecursionError, UnicodeDecodeError, MalformedError) as error:
            self._fail("malformed", during, str(error)[:200])
        return envelope, Decoder(parts[1:], self._proxy)

    def _proxy(self, tag: dict):
        if "function" in tag:
            return RemoteFunction(self, tag)
        return remote_object(self, tag["object"], tag["type"])

    @staticmethod
    def _student_error(raised) -> StudentError:
        if type(raised) is not dict or set(raised) != {"type", "message", "where", "not_implemented"}:
            raise MalformedError("an error report without its fields")
        type_name, message, where, not_implemented = (
            raised[k] for k in ("type", "message", "where", "not_implemented")
        )
        if (
            type(type_name) is not str
            or type(message) is not str
            or not (where is None or type(where) is str)
            or type(not_implemented) is not bool
        ):
            raise MalformedError("an error report with a bad field")
        return student_error(
            _collapse_whitespace(type_name)[:60],
            _collapse_whitespace(message),
            None if where is None else _collapse_whitespace(where)[:200],
            not_implemented,
        )

    def _fail(self, kind: str, during: str, detail: str = "", limit: float | None = None) -> NoReturn:
        """Record the failure, end the process, raise ``SubmissionFailed`` (now and for
        every later request); ``limit`` is the time limit that ran out, if one did."""
        if kind == "timeout":
            limit = self.time_limit if limit is None else limit
            message = f"took longer than {limit:g} s and was stopped (in {during})"
        elif kind == "ended":
            try:
                code = self.process.wait(1)
            except subprocess.TimeoutExpired:
                code = None
            message = f"your code's process ended during {during} ({_exit_cause(code)})"
        else:
            message = f"your code's process sent a malformed reply during {during} ({detail})"
        self._failure = SubmissionFailed(message, kind, during)
        self.guard.end(self.process.pid)
        raise self._failure

    # -- the grader's data, to the student's process --------------------------------------

    def _pickle(self, value) -> list:
        """[pickle, *arrays' data]: arrays cross as their bytes, without a copy into the pickle."""
        arrays: list = []
        stream = io.BytesIO()
        _Pickler(stream, self, arrays).dump(value)
        return [stream.getbuffer(), *arrays]

    def _special_types(self) -> frozenset[type]:
        """The types the pickler treats apart (stand-ins, shared objects, arrays); made
        again only when a new class of stand-in has appeared."""
        if self._special is None or self._special[0] != len(STAND_INS):
            self._special = (len(STAND_INS), frozenset(STAND_INS | self._shared_types | {np.ndarray}))
        return self._special[1]

    def _share(self, value, arrays: list) -> tuple:
        """The reference to a shared object (with the object itself, the first time)."""
        if id(value) in self._shared:
            return ("shared", self._shared[id(value)][0])
        key = len(self._shared)
        self._shared[id(value)] = (key, value)  # (kept alive, so its id stays its own)
        stream = io.BytesIO()
        _Pickler(stream, self, arrays, top=value).dump(value)
        return ("shared", key, stream.getvalue())

    # -- a call's changes, to the grader's arguments --------------------------------------

    @staticmethod
    def _change(entry, decoder: Decoder) -> tuple:
        if (
            type(entry) is not list
            or len(entry) != 3
            or type(entry[0]) is not list
            or entry[1] not in ("array", "state", "value")
        ):
            raise MalformedError("a change that is not [path, how, value]")
        path = entry[0]
        if (
            len(path) < 2
            or not all(
                type(step) is list and len(step) == 2 and step[0] in ("item", "key", "field") for step in path
            )
            or path[0] not in (["item", 0], ["item", 1])
        ):
            raise MalformedError("a change with a bad path")
        return path, entry[1], decoder.decode(entry[2])

    def _take_changes(self, call: tuple, changes: list, arguments: Arguments, during: str) -> None:
        """Copy the changes to the arguments ``arguments.writes`` into the grader's; drop
        those to its scratch arguments; fail on any other."""
        for path, how, value in changes:
            (_, part), (_, key) = path[0], path[1]
            name = arguments.name(key) if part == 0 and type(key) is int else str(key)
            if name in arguments.scratch:
                continue
            if name not in arguments.writes:
                raise ArgumentChanged(
                    f"{during} changed its argument {name}, which it must only "
                    f"read (change a copy: {name}.copy(), or make a new array)"
                )
            self._write_back(call, path, how, value, during)

    def _write_back(self, call: tuple, path: list, how: str, value, during: str) -> None:
        try:
            container = call
            for step in path[:-1]:
                container = _step(container, *step)
            kind, key = path[-1]
            target = _step(container, kind, key)
            if how == "array":
                if not (
                    isinstance(target, np.ndarray)
                    and isinstance(value, np.ndarray)
                    and target.shape == value.shape
                ):
                    raise MalformedError("an array change that does not fit the argument")
                if target.flags.writeable:
                    np.copyto(target, value, casting="unsafe")
            elif how == "state":
                if not isinstance(target, np.random.Generator):
                    raise MalformedError("a generator state for something else")
                target.bit_generator.state = value
            else:
                _rebind(container, kind, key, value)
        except MalformedError as error:
            self._fail("malformed", during, str(error))
        except (TypeError, ValueError, KeyError) as error:  # a state numpy refuses, ...
            self._fail("malformed", during, f"a change the grader cannot make: {error}")


class _Pickler(pickle.Pickler):
    """Pickles the grader's data for the student's process: stand-ins as the handles of the
    objects they stand for, shared objects once, arrays as their raw bytes in a part of
    their own (``arrays``), and large arrays whose rows are all the same (one triangle or
    box tested against many rays) as one row."""

    def __init__(self, stream, submission: Submission, arrays: list, top=None):
        super().__init__(stream, protocol=pickle.HIGHEST_PROTOCOL)
        self.submission, self.arrays, self.top = submission, arrays, top
        self.special = submission._special_types()

    def persistent_id(self, value):
        kind = type(value)  # (called for every object pickled: exact types, looked up)
        if kind not in self.special or value is self.top:
            return None
        if kind is np.ndarray:
            return self._array(value)
        if kind in STAND_INS:
            if process_of(value) is not self.submission:
                raise pickle.PicklingError("an object of another student's process")
            return ("handle", value._handle)
        return self.submission._share(value, self.arrays)

    def _array(self, value: np.ndarray):
        if value.dtype.hasobject or value.dtype.fields is not None:
            return None  # (pickled as usual)
        order: Literal["C", "F"] = "F" if value.flags.f_contiguous and not value.flags.c_contiguous else "C"
        if _same_rows(value):
            return ("rows", value[:1].copy(), len(value), order)
        if not (value.flags.c_contiguous or value.flags.f_contiguous):
            value = np.ascontiguousarray(value)
        # (``.data`` is the array's memoryview: NumPy's stubs type memoryview(array) on Python 3.12 on.)
        self.arrays.append(value.reshape(-1, order=order).data.cast("B"))
        # One string, not a tuple: pickle asks persistent_id about each item of a tuple.
        shape = ",".join(map(str, value.shape))
        return f"array {len(self.arrays) - 1} {value.dtype.str} {shape} {order}"


#: Arrays at least this large are looked at for rows that are all the same.
SAME_ROWS_BYTES = 1 << 18


def _same_rows(array: np.ndarray) -> bool:
    """Whether every row of a large 2-D array is, bit for bit, its first (most arrays that
    are not differ in their second row, which is looked at first)."""
    if (
        array.ndim != 2
        or len(array) < 2
        or array.nbytes < SAME_ROWS_BYTES
        or array.dtype.kind not in "biuf"
        or array.dtype.fields is not None
    ):
        return False
    bits = array.view(f"u{array.dtype.itemsize}")
    first = bits[0]
    if (bits[1] != first).any():
        return False
    return bool((bits.min(axis=0) == first).all() and (bits.max(axis=0) == first).all())


def _step(container, kind: str, key):
    """One step of a change's path into the grader's arguments."""
    if (
        kind == "item"
        and isinstance(container, list | tuple)
        and type(key) is int
        and 0 <= key < len(container)
    ):
        return container[key]
    if kind == "key" and isinstance(container, dict) and type(key) is str and key in container:
        return container[key]
    if (
        kind == "field"
        and type(container) in RECORDS.values()
        and type(key) is str
        and key in {f.name for f in fields(container)}
    ):
        return getattr(container, key)
    raise MalformedError(f"a change at {kind} {key!r}, which the arguments do not have")


def _rebind(container, kind: str, key, value) -> None:
    if (kind == "item" and isinstance(container, list)) or (kind == "key" and isinstance(container, dict)):
        container[key] = value
    elif kind == "field" and is_dataclass(container) and not frozen(container):
        setattr(container, key, value)
    else:
        raise MalformedError(f"a new value at {kind} {key!r}, which cannot be given one")


def submission_of(proxy: RemoteObject | RemoteFunction) -> Submission:
    """The ``Submission`` a stand-in belongs to (``proxies.submission_of``, which knows it
    only as a ``StudentProcess``: every stand-in is a Submission's)."""
    submission = process_of(proxy)
    if not isinstance(submission, Submission):
        raise TypeError(f"a stand-in of {type(submission).__name__}, not of a Submission")
    return submission


def library_answer(module: RemoteModule, name: str) -> str | None:
    """The ptlab answer that the student's ``name`` is (``ptlab.integrators.path.trace_paths``),
    or None if it is the student's own code; the library's own answers (``solutions/``)
    are always their own.

    Raises:
        UnreadableCode: the text of the submission's files does not show the code that
            runs for ``name`` (``ptlab.course.sandbox.readable``): made from data, reached by a
            name built at run time, or imported from outside them. (What runs is checked
            at every call: ``Submission.request``.)
    """
    submission = submission_of(module)
    if submission.library_answers_allowed:
        return None
    found = borrowed_answer(submission.tree, name)
    if found is None:
        value = getattr(module, name, None)
        found = value.origin if isinstance(value, RemoteFunction) else None
    if found is None:
        why = unreadable_in_text(submission.taken, name)
        if why is not None:
            raise UnreadableCode(name, why)
    return found


def import_nothing_from_here() -> None:
    """Take the current folder off ``sys.path`` (``python -m`` puts it first), so that
    nothing the grader imports later, nor its fork server, can come from a module planted
    there. The folder ptlab itself was found in stays (a checkout installed with ``pip
    install -e`` and graded from its root): the processes a grading starts must import
    ptlab from there too, and only the grader's own user may write to it."""
    here = os.getcwd()
    home = str(Path(__file__).resolve().parents[3])
    sys.path[:] = [
        entry for entry in sys.path if entry not in ("", here) or os.path.abspath(entry or ".") == home
    ]


def copied_answer(module: RemoteModule) -> str | None:
    """ "a copy of ptlab's own answer (...)" if the student's file holds copies of the
    rules' answers that add up to one (``ptlab.course.sandbox.copies``), else None."""
    submission = submission_of(module)
    found = copies_in(submission.tree, submission.rules.fingerprints)
    return describe_copies(found, submission.path.name) if is_a_copy(found) else None


def _exit_cause(code: int | None) -> str:
    if code is None:
        return "it stopped answering"
    if code > 128 and code - 128 in signal.valid_signals():
        code = 128 - code  # (bubblewrap reports its child's signal as 128 + the signal)
    if code >= 0:
        return f"it exited with code {code}: os._exit or sys.exit?"
    name = signal.Signals(-code).name if -code in signal.valid_signals() else f"signal {-code}"
    cause = {
        "SIGXCPU": "its CPU-time limit",
        "SIGXFSZ": "its file-size limit",
        "SIGSEGV": "a crash",
        "SIGABRT": "a crash",
        "SIGKILL": "killed, perhaps for memory",
    }
    return f"{name}: {cause.get(name, 'a signal')}"


def _collapse_whitespace(text: str) -> str:
    return " ".join(text.split())


def _count_nonfinite(found) -> None:
    """Count as the grader's own the samples that ``add_to_film`` left out in the student's
    process during a call ([rows, depths], two equal int64 arrays), so that a render's
    tally of NaN samples (``ptlab.integrators.wavefront.counting_nonfinite``) has them."""
    from ptlab.integrators.wavefront import count_nonfinite

    if (
        type(found) is not list
        or len(found) != 2
        or not all(isinstance(a, np.ndarray) and a.dtype == np.int64 and a.ndim == 1 for a in found)
        or len(found[0]) != len(found[1])
        or len(found[0]) == 0
    ):
        raise MalformedError("a count of NaN samples that is not two equal arrays of integers")
    count_nonfinite(found[0], found[1])
