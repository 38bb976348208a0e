"""Where a student's code runs: a fresh Python that sees nothing of ours but its kit.

The student's process is a new interpreter (``python -I``, exec'd, never forked from a
process that imported ptlab's answers), started by bubblewrap (``bwrap``, the sandbox of
Flatpak) in namespaces of its own:

* **mount**: its view of the file system is built from nothing and holds the system's
  libraries (``/usr``), the Python that runs the grader with its site-packages emptied,
  the few packages the chapter lets it import (NumPy, SciPy, and Embree where the chapter
  is not about ray queries), the chapter's kit in ptlab's place (``ptlab.course.sandbox.kit``:
  ptlab without the chapter's answers), its own writable folder holding the submission,
  and empty ``/tmp``, ``/var/tmp`` and ``/dev/shm``, all of these in memory and of a
  bounded size. The grader's files, the other students', ptlab's answers and the exercises
  are not in it: no path reaches them;
* **pid**: it is process 2 of a process tree of its own; ``/proc`` shows that tree only;
* **network**: no device but a loopback; **IPC** and **UTS** of its own;
* as root, it runs as the unprivileged student user (``ptlab.course.sandbox.student_user``),
  with no capability left (bubblewrap keeps only the right to change user, which
  ``BOOTSTRAP`` spends before anything else runs); not as root, as the grader's user,
  mapped into a user namespace that may make no other. Its results are for credit only
  from a root grader (``not_for_credit``);
* **no namespaces of its own**: a seccomp filter refuses it ``unshare``, ``setns`` and a
  ``clone`` into new namespaces (``ptlab.course.sandbox.no_namespaces``).

Why bubblewrap: it is small, audited and packaged by every Linux distribution
(``apt-get install bubblewrap``), it runs unprivileged where the kernel allows user
namespaces and as root everywhere, and it builds the view from an empty root, so what
it does not bind does not exist for the process. Python's own ``unshare`` and ``mount``
would be ours to get right.

Where the namespaces cannot be made (no ``bwrap``, or a kernel that refuses it), the
student's code still runs in a fresh interpreter whose ``ptlab`` is the kit, but ptlab
itself, the grader's files and its processes are within its reach: ``SandboxMissing``
says why, and the graders mark such results as not for credit.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path

import ptlab.course.sandbox.no_namespaces as no_namespaces
from ptlab.course.sandbox.student_user import StudentUser, is_root

#: The packages a student's process may import beyond the standard library and its kit.
PACKAGES = ("numpy", "scipy", "embreex")
#: The student's own folder, as its process sees it: a file system in memory, like /tmp.
FOLDER = Path("/home/student")
#: The largest each of the student's writable places may grow (its folder, /tmp, /var/tmp,
#: /dev/shm): they are memory, counted against the grader's machine.
SCRATCH_BYTES = 256 << 20
#: The system's folders of programs and libraries that Python needs (bound read-only).
SYSTEM = ("/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32")
#: Files of /etc that the dynamic loader and the C library read.
SYSTEM_FILES = ("/etc/ld.so.cache", "/etc/localtime", "/etc/nsswitch.conf")
#: What the student's process runs: become the student user, if asked (bubblewrap leaves it
#: only the right to, which this spends before anything else runs), then the child's main,
#: from the kit (on ``sys.path`` first where there is no sandbox to mount it in ptlab's place).
BOOTSTRAP = """\
import os, sys
uid, gid = int(sys.argv[1]), int(sys.argv[2])
if uid >= 0:
    os.setgroups([])
    os.setresgid(gid, gid, gid)
    os.setresuid(uid, uid, uid)
if sys.argv[3]:
    sys.path.insert(0, sys.argv[3])
from ptlab.course.sandbox.child import main
main()
"""


@dataclass(frozen=True)
class SandboxMissing:
    """Why this machine cannot make the student's namespaces (one line for the grader)."""

    reason: str

    def __str__(self) -> str:
        return self.reason


@dataclass(frozen=True)
class View:
    """What the student's process sees.

    Attributes:
        kit: the kit's folder (it holds ``ptlab/``).
        files: {name: bytes}: the submission's files, which its folder holds.
        folder: that folder: ``FOLDER`` in the sandbox, where it is made in memory with the
            files; without the sandbox, a folder of the grader's that holds them already.
        packages: the packages (import names) it may import.
    """

    kit: Path
    files: dict[str, bytes]
    folder: Path = FOLDER
    packages: tuple[str, ...] = PACKAGES


@functools.cache
def missing() -> SandboxMissing | None:
    """None when bubblewrap can make the namespaces here (tried once), else why not."""
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        return SandboxMissing(
            "bubblewrap is not installed (apt-get install bubblewrap): students' code runs "
            "without namespaces of its own, and its results are not for credit"
        )
    # (no reaper process in the probe's pid namespace: one that outlived bubblewrap's own
    # process would be left to whoever reaps orphans here, a grader that is a subreaper)
    # (and a sized file system in memory: bubblewrap older than 0.7 cannot make one)
    probe = [bwrap, *_namespaces(), "--as-pid-1", "--ro-bind", "/", "/"]
    probe += ["--size", str(SCRATCH_BYTES), "--tmpfs", "/tmp", "--", "true"]
    try:
        ran = subprocess.run(probe, capture_output=True, timeout=30, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired) as error:
        return SandboxMissing(f"bubblewrap cannot run here ({error}): results are not for credit")
    if ran.returncode != 0:
        said = " ".join(ran.stderr.decode(errors="replace").split())[:200]
        return SandboxMissing(
            f"bubblewrap cannot make namespaces here ({said}): students' code runs without "
            f"them, and its results are not for credit"
        )
    return None


def start(view: View, user: StudentUser | None, pass_fds: tuple[int, ...], **options) -> subprocess.Popen:
    """Start the student's process in ``view`` as ``user`` (None: this process's own), in
    the sandbox where ``missing()`` is None, else without it; ``pass_fds`` and ``options``
    are ``subprocess.Popen``'s.

    bubblewrap reads its arguments from a pipe (``--args``), so that its command line,
    which the student's code can read in its ``/proc``, names none of the grader's folders,
    and the submission's files from descriptors of files in memory, which it copies into
    the student's folder: nothing the student's code writes lands on the grader's disk.
    """
    sandboxed = missing() is None
    uid, gid = (user.uid, user.gid) if sandboxed and user is not None and is_root() else (-1, -1)
    kit = "" if sandboxed else str(view.kit)
    python = [sys.executable, "-I", "-c", BOOTSTRAP, str(uid), str(gid), kit]
    if not sandboxed:
        return subprocess.Popen(python, pass_fds=pass_fds, **options)
    files = {name: _in_memory(data) for name, data in view.files.items()}
    filters = [_in_memory(no_namespaces.program())] if no_namespaces.supported() else []
    read, write = os.pipe()
    try:
        arguments = _view_arguments(view, user, files)
        arguments += [argument for fd in filters for argument in ("--seccomp", str(fd))]
        os.write(write, b"".join(a.encode() + b"\0" for a in arguments))  # (a few kB: the pipe holds them)
        os.close(write)
        bwrap = [shutil.which("bwrap") or "bwrap", "--args", str(read), "--", *python]
        return subprocess.Popen(bwrap, pass_fds=(*pass_fds, read, *files.values(), *filters), **options)
    finally:
        for fd in (read, *files.values(), *filters):
            os.close(fd)
        with contextlib.suppress(OSError):
            os.close(write)


def not_for_credit() -> str | None:
    """Why results graded here do not count (None: they do): the sandbox cannot be made, or
    the grader is not root, so the student's code runs as the grader's own user (whose
    files, processes and bubblewrap's own process it could reach, were it to escape the
    view)."""
    why = missing()
    if why is not None:
        return str(why)
    if not is_root():
        return (
            "the grader is not root, so students' code runs as the grader's own user: "
            "grade as root for credit (docs/grading-security.md)"
        )
    return None


def _in_memory(data: bytes) -> int:
    """A descriptor of a file in memory holding ``data``, read from its start."""
    fd = os.memfd_create("ptlab-submission")
    os.write(fd, data)
    os.lseek(fd, 0, os.SEEK_SET)
    return fd


def _namespaces() -> list[str]:
    """A namespace of its own for everything. As root, no user namespace: bubblewrap's own
    process 1 stays root, out of the student user's reach (a user namespace would make it
    the student's, whose code could then ptrace it). Not as root, a user namespace that
    maps this process's user and may make no other."""
    found = ["--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try"]
    if not is_root():
        found += ["--unshare-user", "--disable-userns"]
    return ["--die-with-parent", "--new-session", *found]


def _view_arguments(view: View, user: StudentUser | None, files: dict[str, int]) -> list[str]:
    """bubblewrap's arguments, in the order it applies them: each mount lands on what the
    ones before it made. ``files``: {name: descriptor} of the submission's files."""
    found = [*_namespaces(), *_system(), *_python(view), *_students_folder(view, files)]
    found += ["--chdir", str(view.folder), "--hostname", "ptlab-student", "--cap-drop", "ALL"]
    if user is not None and is_root():
        found += ["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID"]
    return found


def _system() -> list[str]:
    """/usr and its links, the files of /etc that the loader reads, /proc, /dev, and empty
    /tmp, /var/tmp and /dev/shm of the sandbox's own."""
    found = []
    for place in SYSTEM:
        if os.path.islink(place):
            found += ["--symlink", os.readlink(place), place]
        elif os.path.isdir(place):
            found += ["--ro-bind", place, place]
    system_files = [file for file in SYSTEM_FILES if os.path.isfile(file)]
    for folder in _folders_above(system_files):
        found += ["--perms", "0755", "--dir", folder]
    for file in system_files:
        found += ["--ro-bind", file, file]
    found += ["--proc", "/proc", "--dev", "/dev"]
    for scratch in ("/dev/shm", "/tmp", "/var/tmp"):
        found += ["--size", str(SCRATCH_BYTES), "--perms", "1777", "--tmpfs", scratch]
    return found


def _python(view: View) -> list[str]:
    """The Python where it lies, its site-packages emptied, the allowed packages and the
    kit (as ``ptlab``) put back."""
    found = []
    prefixes = python_prefixes()
    # (bubblewrap makes the folders above a mount closed to all but root: open them)
    for folder in _folders_above(prefixes):
        found += ["--perms", "0755", "--dir", folder]
    for prefix in prefixes:
        found += ["--ro-bind", prefix, prefix]
    for packages in site_packages():
        found += ["--tmpfs", packages]  # (empty: what was installed there is not seen)
    for place in package_folders(view.packages):
        found += ["--ro-bind", place, place]
    found += ["--ro-bind", str(view.kit / "ptlab"), os.path.join(sysconfig.get_paths()["purelib"], "ptlab")]
    return found


def _students_folder(view: View, files: dict[str, int]) -> list[str]:
    """The student's folder, in memory, writable by it alone, holding the submission's files
    (read-only: the grader's copies)."""
    folder = str(view.folder)
    found = ["--perms", "0755", "--dir", os.path.dirname(folder)]
    found += ["--size", str(SCRATCH_BYTES), "--perms", "1777", "--tmpfs", folder]
    for name, fd in files.items():
        found += ["--perms", "0644", "--file", str(fd), os.path.join(folder, name)]
    return found


def python_prefixes() -> list[str]:
    """The folders of the Python that runs the grader (its virtual environment's and the
    base installation's), outside /usr."""
    prefixes = {
        os.path.realpath(p) for p in (sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix)
    }
    prefixes.add(os.path.dirname(os.path.dirname(os.path.realpath(sys.executable))))
    return sorted(p for p in prefixes if not any(_under(p, s) for s in SYSTEM) and p != "/")


def site_packages() -> list[str]:
    """Every folder Python imports installed packages from, in this environment and the
    base one (hidden in the view, then the allowed packages bound back)."""
    found: set[str] = set()
    for scheme_vars in ({}, {"base": sys.base_prefix, "platbase": sys.base_exec_prefix}):
        paths = sysconfig.get_paths(vars=scheme_vars)
        found.update(paths[key] for key in ("purelib", "platlib"))
    found.update(p for p in sys.path if p.endswith(("site-packages", "dist-packages")))
    return sorted(p for p in {os.path.realpath(p) for p in found} if os.path.isdir(p))


def package_folders(packages: tuple[str, ...]) -> list[str]:
    """The installed folders of ``packages`` (import names), with the shared libraries
    that wheels bring beside them (``numpy.libs``)."""
    found = []
    for name in packages:
        spec = importlib.util.find_spec(name)
        if spec is None:
            continue
        if spec.submodule_search_locations:
            folder = os.path.realpath(next(iter(spec.submodule_search_locations)))
        elif spec.origin:
            folder = os.path.realpath(spec.origin)
        else:
            continue
        found.append(folder)
        libs = os.path.join(os.path.dirname(folder), f"{name}.libs")
        if os.path.isdir(libs):
            found.append(os.path.realpath(libs))
    return found


def _folders_above(places: list[str]) -> list[str]:
    """The folders above ``places`` that none of them holds, from the top down."""
    found: list[str] = []
    for place in places:
        folder = os.path.dirname(place)
        above = []
        while folder != "/" and not any(_under(folder, p) for p in places):
            above.append(folder)
            folder = os.path.dirname(folder)
        found += [f for f in reversed(above) if f not in found]
    return found


def _under(path: str, folder: str) -> bool:
    return path == folder or path.startswith(folder.rstrip("/") + "/")
