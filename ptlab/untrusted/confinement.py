"""What the student's process may not do, whoever it runs as: rules kept by an audit hook.

Python raises an audit event before it opens a file, compiles code, starts a program, sends
a signal, makes a socket (PEP 578, ``sys.addaudithook``); a hook can refuse by raising, and
a hook once added cannot be removed. ``confine`` adds one to the student's process, after
its traps are set (``ptlab.untrusted.traps``) and before the student's file is imported.
It refuses:

* reading ptlab's code (its ``.py`` and ``.pyc`` files, the exercises' answers): every
  module the student's code may use is already imported in the fork server, so only a
  copy of the library's answers would be read;
* compiling or decoding code that holds ptlab's answers (``ptlab.untrusted.copies``),
  which covers a copy assembled or downloaded at run time, and building code objects
  from bytes (``marshal``, ``types.CodeType``) outside Python's own import system;
* writing, renaming or removing files outside the process's private folder (the grader's
  results, the progress record, other students' files), and opening folders outside it
  (a folder's descriptor would let ``dir_fd`` reach into it);
* reading or listing anything outside its private folder but Python's and ptlab's
  installed files (``readable_places``), a few device files, its own ``/proc/<pid>``, any
  process's ``/proc/<pid>/stat`` and what libraries read to count processors and memory:
  not the grader's command line (``/proc/<grader>/cmdline``), the list of processes,
  other folders' names;
* signals to any process but its own and those it started;
* sockets but Unix ones in its folder (the grader's fork server listens on one outside it);
* starting programs (where the chapter does not need it; the kernel refuses them too, see
  ``ptlab.untrusted.no_exec``) and loading or calling C functions through ``ctypes``.

These rules hold against Python code. Code that escapes Python (C code reached through a
library that writes files itself, or a write into the interpreter's own memory) escapes
them; against that, the grader relies on the operating system: the student user when the
grader is root (``ptlab.untrusted.student_user``) and the kernel's refusal of programs.
docs/grading-security.md says what is left.
"""

from __future__ import annotations

import ast
import os
import re
import socket
import sys
import threading
from pathlib import Path

from ptlab.untrusted.copies import Answers, copies_in, describe_copies, is_a_copy

#: The ptlab package: the code the student's process may not read.
PTLAB = Path(__file__).resolve().parent.parent
#: Folders of ptlab that hold nothing but code (the exercises' answers and templates).
CODE_FOLDERS = (PTLAB / "exercises" / "solutions", PTLAB / "exercises" / "templates")
CODE_SUFFIXES = (".py", ".pyc", ".pyo", ".pth")
#: Files anyone may write (they hold nothing).
ALWAYS_WRITABLE = ("/dev/null",)
WRITE_FLAGS = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_TRUNC | os.O_APPEND
#: Events that change the file system: the positions of their paths, and of their folder
#: descriptors (-1 or None when there is none).
FILE_CHANGES = {
    "os.rename": ((0, 1), (2, 3)),
    "os.remove": ((0,), (1,)),
    "os.rmdir": ((0,), (1,)),
    "os.mkdir": ((0,), (2,)),
    "os.symlink": ((1,), (2,)),
    "os.link": ((1,), (2, 3)),
    "os.chmod": ((0,), (2,)),
    "os.chown": ((0,), (3,)),
    "os.utime": ((0,), (3,)),
    "os.truncate": ((0,), ()),
    "os.chflags": ((0,), ()),
    "os.lchflags": ((0,), ()),
    "os.setxattr": ((0,), ()),
    "os.removexattr": ((0,), ()),
    "shutil.rmtree": ((0,), ()),
    "sqlite3.connect": ((0,), ()),
}
PROGRAM_EVENTS = (
    "subprocess.Popen",
    "os.system",
    "os.exec",
    "os.posix_spawn",
    "os.spawn",
    "os.startfile",
    "pty.spawn",
)
#: ctypes' events: loading a library or a symbol, reading memory at an address.
CTYPES_EVENTS = (
    "ctypes.dlopen",
    "ctypes.dlsym",
    "ctypes.dlsym/handle",
    "ctypes.cdata",
    "ctypes.string_at",
    "ctypes.wstring_at",
    "ctypes.call_function",
)
#: Files outside the private folder that anyone may read, and folders whose files anyone
#: may read and list (what libraries read to count processors and memory).
READABLE_FILES = ("/dev/null", "/dev/zero", "/dev/urandom", "/dev/random", "/proc/cpuinfo", "/proc/meminfo")
READABLE_FOLDERS = ("/sys/devices/system/cpu", "/sys/fs/cgroup")
#: Any process's ``stat`` (its parent and state, which the hook itself reads to tell a
#: process's descendants), but no other file of another process (its command line).
PROCESS_STAT = re.compile(r"/proc/[0-9]+/stat")
#: Frames whose decoding of bytecode is Python's own import system.
IMPORT_SYSTEM = ("<frozen importlib._bootstrap_external>", "<frozen importlib._bootstrap>")


class Refused(PermissionError):  # noqa: N818 (a rule, not an error of the code)
    """What the student's code tried is not allowed while it is graded."""


def confine(folder: Path, answers: Answers, programs: bool) -> None:
    """Add the hook: from now on this process keeps the rules above. ``folder`` is its
    private folder, ``answers`` the fingerprints of the answers it may not compile (the
    chapter's), ``programs`` whether it may start programs."""
    if not programs:
        # multiprocessing starts its fork server, resource tracker and "spawn" workers with
        # a C call that raises no audit event; where the kernel would refuse them anyway,
        # the student reads why instead of a broken pipe.
        import multiprocessing.util

        multiprocessing.util.spawnv_passfds = _no_programs
    sys.addaudithook(_Rules(folder, answers, programs))


def _no_programs(*args, **kwargs):
    raise Refused(
        "your code may not start programs while it is graded (a process pool that "
        "starts new interpreters, 'forkserver' or 'spawn', is one; in this chapter "
        "your code has no need of one)"
    )


class _Rules:
    """The audit hook (called for every event, so it returns at once for the others)."""

    def __init__(self, folder: Path, answers: Answers, programs: bool):
        self.folder = Path(os.path.realpath(folder))
        self.answers, self.programs = answers, programs
        self.checking = threading.local()  # (compiling inside the hook raises events)
        self.handlers = {
            "open": self.open,
            "compile": self.compile,
            "marshal.loads": self.decode,
            "marshal.load": self.decode,
            "code.__new__": self.decode,
            "os.kill": self.signal,
            "os.killpg": self.signal,
            "socket.__new__": self.socket,
            "socket.connect": self.address,
            "socket.bind": self.address,
            "socket.sendto": self.address,
            "os.chdir": self.stay,
            "os.listdir": self.listing,
            "os.scandir": self.listing,
        }
        self.readable = readable_places()
        self.handlers.update(dict.fromkeys(FILE_CHANGES, self.change))
        self.handlers.update(dict.fromkeys(CTYPES_EVENTS, self.ctypes))
        if not programs:
            self.handlers.update(dict.fromkeys(PROGRAM_EVENTS, self.program))

    def __call__(self, event: str, arguments: tuple) -> None:
        handler = self.handlers.get(event)
        if handler is not None and not getattr(self.checking, "now", False):
            handler(event, arguments)

    # -- files ----------------------------------------------------------------------------

    def open(self, event: str, arguments: tuple) -> None:
        path, mode, flags = arguments
        if isinstance(path, int):
            return  # an open descriptor: checked when it was opened
        where = self._resolved(path)
        if where is None:
            return
        if where.is_relative_to(PTLAB) and (
            where.suffix in CODE_SUFFIXES
            or "__pycache__" in where.parts
            or any(where.is_relative_to(f) for f in CODE_FOLDERS)
        ):
            raise Refused(f"reading ptlab's own code ({where}) is not allowed while your code is graded")
        writes = (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
            isinstance(flags, int) and flags & WRITE_FLAGS
        )
        if writes and not self._mine(where) and str(where) not in ALWAYS_WRITABLE:
            raise Refused(
                f"your code may write only in its own folder (the current one) while "
                f"it is graded, not {where}"
            )
        if not writes and not self._mine(where) and where.is_dir():
            raise Refused(
                f"your code may open folders only in its own folder while it is graded, not {where}"
            )
        if not writes and not self._mine(where) and not self._readable(where):
            raise Refused(self._read_refusal(where))

    def listing(self, event: str, arguments: tuple) -> None:
        """Listing a folder: its own, Python's and ptlab's (Python's import system lists
        the folders it imports from)."""
        path = arguments[0] if arguments and arguments[0] is not None else "."
        if isinstance(path, int):
            return  # an open descriptor: of a folder it was allowed to open
        where = self._resolved(path)
        if where is None or self._mine(where) or self._readable(where):
            return
        try:
            caller = sys._getframe(2).f_code.co_filename  # (this method, the hook, its caller)
        except ValueError:
            caller = None
        if caller not in IMPORT_SYSTEM:
            raise Refused(self._read_refusal(where, "list"))

    def _readable(self, where: Path) -> bool:
        text = str(where)
        if text in READABLE_FILES or any(where.is_relative_to(f) for f in READABLE_FOLDERS):
            return True
        if where.is_relative_to(f"/proc/{os.getpid()}") or PROCESS_STAT.fullmatch(text):
            return True
        return any(where.is_relative_to(place) for place in self.readable)

    def _read_refusal(self, where: Path, verb: str = "read") -> str:
        return (
            f"your code may {verb} only its own folder and Python's and ptlab's installed "
            f"files while it is graded, not {where}"
        )

    def change(self, event: str, arguments: tuple) -> None:
        paths, folders = FILE_CHANGES[event]
        if any(arguments[k] not in (None, -1) for k in folders if k < len(arguments)):
            raise Refused(f"{event} with a folder descriptor is not allowed while your code is graded")
        for k in paths:
            path = arguments[k]
            if isinstance(path, int) and event != "os.truncate":
                raise Refused(f"{event} on a file descriptor is not allowed while your code is graded")
            where = None if isinstance(path, int) else self._resolved(path, follow=False)
            if where is not None and not self._mine(where):
                raise Refused(
                    f"your code may change files only in its own folder while it is "
                    f"graded, not {where} ({event})"
                )

    def stay(self, event: str, arguments: tuple) -> None:
        """Relative paths are judged from the private folder, so the process stays in it."""
        where = None if isinstance(arguments[0], int) else self._resolved(arguments[0])
        if where != self.folder:
            raise Refused("your code may not change its current folder while it is graded")

    def _resolved(self, path, follow: bool = True) -> Path | None:
        try:
            text = os.fsdecode(path)
        except TypeError:
            return None
        absolute = os.path.join(os.getcwd(), text)
        if not follow:  # (the link itself is what changes, not what it points to)
            head, tail = os.path.split(absolute)
            return Path(os.path.realpath(head)) / tail
        return Path(os.path.realpath(absolute))

    def _mine(self, where: Path) -> bool:
        return where == self.folder or where.is_relative_to(self.folder)

    # -- code ----------------------------------------------------------------------------

    def compile(self, event: str, arguments: tuple) -> None:
        source, filename = arguments[0], arguments[1]
        self.checking.now = True
        try:
            tree = source if isinstance(source, ast.AST) else ast.parse(source)
        except (SyntaxError, ValueError, TypeError, MemoryError, RecursionError):
            return  # compile() itself will say what is wrong
        finally:
            self.checking.now = False
        found = copies_in(tree, self.answers)
        if is_a_copy(found):
            raise Refused(
                f"compiling {describe_copies(found, os.path.basename(os.fsdecode(filename)))} "
                f"is not allowed while your code is graded"
            )

    def decode(self, event: str, arguments: tuple) -> None:
        try:
            caller = sys._getframe(2).f_code.co_filename  # (this method, the hook, its caller)
        except ValueError:  # called from C with no Python frame above
            caller = None
        if caller not in IMPORT_SYSTEM:
            raise Refused(f"making code from bytes ({event}) is not allowed while your code is graded")

    # -- processes, sockets, C ---------------------------------------------------------------

    def signal(self, event: str, arguments: tuple) -> None:
        self.checking.now = True  # (reading /proc/<target> below is the hook's, not the code's)
        try:
            self._signal(event, arguments)
        finally:
            self.checking.now = False

    def _signal(self, event: str, arguments: tuple) -> None:
        target, me = arguments[0], os.getpid()
        if event == "os.killpg" or target <= 0:
            group = os.getpgid(0) if target == 0 else abs(target)
            if group == os.getpgid(0) or _descends_from(group, me):
                return
        elif target == me or _descends_from(target, me):
            return
        raise Refused(
            f"your code may signal only its own processes while it is graded (not "
            f"{'group ' if event == 'os.killpg' or target <= 0 else 'pid '}{abs(target)})"
        )

    def socket(self, event: str, arguments: tuple) -> None:
        family = arguments[1]
        if family != socket.AF_UNIX:
            raise Refused("your code may not use the network while it is graded")

    def address(self, event: str, arguments: tuple) -> None:
        address = arguments[1]
        if isinstance(address, str | bytes) and len(address) and address[:1] not in ("\0", b"\0"):
            where = self._resolved(address)
            if where is not None and self._mine(where):
                return
        if isinstance(address, str | bytes):
            raise Refused("your code may use sockets only in its own folder while it is graded")

    def program(self, event: str, arguments: tuple) -> None:
        raise Refused(
            "your code may not start programs while it is graded (in this chapter it has no need to)"
        )

    def ctypes(self, event: str, arguments: tuple) -> None:
        raise Refused(f"calling C through ctypes ({event}) is not allowed while your code is graded")


def readable_places() -> tuple[Path, ...]:
    """The folders the student's process may read and list beyond its own: Python's
    installation and the folders it imports from (``sys.path``, which hold ptlab's
    installed files; its code stays refused above), and the folder ptlab is installed in."""
    places = {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, str(PTLAB.parent)}
    places.update(entry for entry in sys.path if os.path.isabs(entry))
    resolved = {Path(os.path.realpath(place)) for place in places}
    return tuple(sorted(place for place in resolved if place != Path("/")))


def _descends_from(pid: int, ancestor: int) -> bool:
    """Whether process ``pid`` is ``ancestor``'s child, grandchild, ... (Linux ``/proc``)."""
    for _ in range(64):
        try:
            stat = Path(f"/proc/{pid}/stat").read_bytes()
        except OSError:
            return False
        pid = int(stat[stat.rfind(b")") + 2 :].split()[1])
        if pid == ancestor:
            return True
        if pid <= 1:
            return False
    return False
