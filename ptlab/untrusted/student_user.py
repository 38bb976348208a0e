"""The user a student's code runs as: another one when the grader is root.

A process of the grader's own user may do what the grader may: signal it, ptrace it, write
its results. When the grader runs as root (as it does in the container that
docs/grading-security.md recommends), the student's process becomes an unprivileged user
before it imports anything (``--student-user``, by default ``nobody``), with no
supplementary groups, in a private folder it owns; it can then neither signal, ptrace nor
write over the grader, and the limit on its number of processes applies. Being root, the
grader also gives it a network namespace of its own, with no way out
(``isolate_network``). When the grader is not root it cannot change users: it makes
itself non-dumpable (``ptlab.untrusted.processes.make_undumpable``) and the docs say what
remains open.

``student_user(name)`` resolves the option once per grader, and checks that the user can
read the Python that runs ptlab (a Python in /root, mode 700, cannot be read by ``nobody``):
the grader refuses to start rather than fail every student's import.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import pwd
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from ptlab.errors import PtlabError

#: The user students' code runs as when the grader is root and no ``--student-user`` is given.
DEFAULT_STUDENT_USER = "nobody"
CLONE_NEWNET = 0x40000000
#: The lowest uid ``pool_user`` takes (below are the system's own users).
FIRST_POOL_UID = 1000


@dataclass(frozen=True)
class StudentUser:
    """An unprivileged user to run students' code as."""

    name: str
    uid: int
    gid: int


def is_root() -> bool:
    return hasattr(os, "geteuid") and os.geteuid() == 0


def student_user(name: str | StudentUser | None = None) -> StudentUser | None:
    """The user students' code runs as: ``name`` (a user name or number, or a
    ``StudentUser`` made already, such as a ``pool_user``), by default ``nobody`` when this
    process is root and None (this process's own user) otherwise.

    Raises ``PtlabError`` when ``name`` is no user, names another user without root, or
    cannot read the Python and the ptlab that run the grader.
    """
    if isinstance(name, StudentUser):
        if not is_root():
            raise PtlabError(f"{name.name}: only root can run students' code as another user")
        _check_can_run_ptlab(name)
        return name
    if name is None:
        name = DEFAULT_STUDENT_USER if is_root() else None
    if name is None:
        return None
    entry = _password_entry(name)
    if entry.pw_uid == os.geteuid():
        return None  # the grader's own user: nothing to change
    if not is_root():
        raise PtlabError(
            f"--student-user {name}: only root can run students' code as another "
            f"user (this grader runs as {pwd.getpwuid(os.geteuid()).pw_name})"
        )
    user = StudentUser(entry.pw_name, entry.pw_uid, entry.pw_gid)
    _check_can_run_ptlab(user)
    return user


def pool_user(user: StudentUser, slot: int) -> StudentUser:
    """The user of ``slot`` in the pool of students graded at the same time
    (``grade-all --workers K`` as root): slot 0 is ``user`` itself, slot k the k-th uid
    below ``user``'s that names no user in the password database (for ``nobody``, 65534:
    65533, 65532, ...), in ``user``'s group. Root may become a uid that names nobody; such a
    uid owns no process and no file but those of its student, so the kernel keeps each
    student's process limit, signals and private folder apart from the others'.

    Raises ``PtlabError`` when there are not that many such uids above ``FIRST_POOL_UID``.
    """
    uid, found = user.uid, 0
    while found < slot:
        uid -= 1
        if uid < FIRST_POOL_UID:
            raise PtlabError(
                f"--student-user {user.name}: no {slot} unused uids below {user.uid} for "
                f"students graded at once; use --workers 1 or a user with a higher uid"
            )
        if not _names_a_user(uid):
            found += 1
    if slot == 0:
        return user
    return StudentUser(f"{user.name}+{slot} (uid {uid})", uid, user.gid)


def _names_a_user(uid: int) -> bool:
    try:
        pwd.getpwuid(uid)
    except KeyError:
        return False
    return True


def add_student_user_argument(parser: argparse.ArgumentParser) -> None:
    """The graders' ``--student-user`` option."""
    parser.add_argument(
        "--student-user",
        metavar="USER",
        help=f"run the student's code as USER (a name or a number); only root "
        f"may, and by default root runs it as {DEFAULT_STUDENT_USER!r}. "
        f"'--student-user root' runs it as root: never for grades that "
        f"count (docs/grading-security.md)",
    )


def _password_entry(name: str) -> pwd.struct_passwd:
    try:
        return pwd.getpwuid(int(name)) if name.isdigit() else pwd.getpwnam(name)
    except KeyError:
        raise PtlabError(f"--student-user {name}: there is no such user") from None


_checked: set[StudentUser] = set()


def _check_can_run_ptlab(user: StudentUser) -> None:
    """Start Python as ``user`` and import what a student's process uses; a ``PtlabError``
    naming the first folder that user cannot enter if that fails (once per user)."""
    if user in _checked:
        return
    try:
        ran = subprocess.run(
            [sys.executable, "-I", "-c", "import numpy, ptlab.untrusted.child"],
            user=user.uid,
            group=user.gid,
            extra_groups=[],
            stdin=subprocess.DEVNULL,
            capture_output=True,
            timeout=120,
            cwd="/",
        )
        failed = ran.returncode != 0
    except OSError:
        failed = True
    if failed:
        blocked = _closed_folder([Path(sys.executable), *map(Path, sys.path), Path(__file__)])
        where = f"{blocked} is closed to other users" if blocked else "it cannot import ptlab"
        raise PtlabError(
            f"--student-user {user.name}: that user cannot run this Python and ptlab "
            f"({where}); install them where every user can read them (see "
            f"docs/grading-security.md), or name a user who can"
        )
    _checked.add(user)


def _closed_folder(paths: list[Path]) -> Path | None:
    """The first folder above ``paths`` that other users may not enter (no o+x), if any."""
    for path in paths:
        for folder in reversed(path.absolute().parents):
            try:
                if not folder.stat().st_mode & 0o001:
                    return folder
            except OSError:
                continue
    return None


def become(user: StudentUser) -> None:
    """Turn this process (root) into ``user`` for good: no supplementary groups, and real,
    effective and saved ids all the user's, so that nothing can be taken back."""
    os.setgroups([])
    os.setresgid(user.gid, user.gid, user.gid)
    os.setresuid(user.uid, user.uid, user.uid)


def isolate_network() -> bool:
    """Give this process (root) a network namespace of its own: only a loopback device, down,
    so no connection leaves it. False where the kernel refuses (no CAP_SYS_ADMIN, as in a
    default Docker container, which docs/grading-security.md runs with --network none)."""
    libc = ctypes.CDLL(None, use_errno=True)
    return libc.unshare(CLONE_NEWNET) == 0
