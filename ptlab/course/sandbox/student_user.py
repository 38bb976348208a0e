"""The user a student's code runs as: another one when the grader is root.

A process of the grader's own user may do what the grader may: signal it, ptrace it, write
its results. When the grader runs as root (as it does in the container that
docs/grading-security.md recommends), the student's process becomes an unprivileged user
as it starts in its sandbox (``--student-user``, by default ``nobody``), with no
supplementary groups, in a private folder it owns; the kernel then counts its processes
against that user's limit. The sandbox's view holds the Python that runs the grader
(``ptlab.course.sandbox.sandbox``), so the user needs no right to read it where it is installed.
``student_user(name)`` resolves the option once per grader.
"""

from __future__ import annotations

import argparse
import os
import pwd
from dataclasses import dataclass

from ptlab.errors import PtlabError

#: The user students' code runs as when the grader is root and no ``--student-user`` is given.
DEFAULT_STUDENT_USER = "nobody"
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

    Raises ``PtlabError`` when ``name`` is no user or names another user without root.
    """
    if isinstance(name, StudentUser):
        if not is_root():
            raise PtlabError(f"{name.name}: only root can run students' code as another user")
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
    return StudentUser(entry.pw_name, entry.pw_uid, entry.pw_gid)


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
