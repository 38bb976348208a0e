"""A student's submission, read once, and the private folder each of its processes runs in.

``take_in(path)`` reads the submission before anything of it runs: a regular file (not a
symbolic link, not inside the installed ptlab), and, for a submission that is a folder of
its own (``with_folder``), the other regular Python files beside it (at most ``MAX_FILES``
of them). Its bytes are kept:
every check's process gets a fresh private folder holding exactly them
(``private_folder``), owned by the student's user and closed to everyone else, so a file
changed while grading goes on, a link to the library's answers, or another student's file
beside it change nothing. The SHA-256 of the graded file is that of the bytes graded.
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path

from ptlab.course.sandbox.child import PTLAB
from ptlab.course.sandbox.student_user import StudentUser

#: Files and bytes beside the graded one that are taken with it, at most.
MAX_FILES = 64
MAX_BYTES = 16 << 20


class RefusedSubmission(Exception):  # noqa: N818 (a verdict on the submission)
    """The submission cannot be graded as it is handed in (the message says why)."""


@dataclass(frozen=True)
class Taken:
    """A submission as read, once.

    Attributes:
        path: where it was handed in (for messages).
        files: {file name: bytes}: the graded file and, for a folder, the Python files beside it.
        sha256: of the graded file's bytes.
        tree: the graded file's syntax tree (read, never run, by the grader).
    """

    path: Path
    files: dict[str, bytes]
    sha256: str
    tree: ast.Module

    @property
    def name(self) -> str:
        return self.path.name


def take_in(path: str | Path, with_folder: bool = False, library: bool = False) -> Taken:
    """Read the submission at ``path`` (see the module docstring); ``library``: it is one of
    ptlab's own answer files, which may lie in the package.

    Raises:
        RefusedSubmission: a link, not a regular file, inside ptlab, too large, or not Python.
    """
    path = Path(path)
    if path.is_symlink():
        raise RefusedSubmission(f"{path} is a symbolic link: hand in the file itself")
    if not library and Path(os.path.realpath(path)).is_relative_to(PTLAB):
        raise RefusedSubmission(
            f"{path} is part of ptlab itself, not a submission: copy the "
            f"exercise with 'ptlab exercise start' and write your own"
        )
    files = read_files(path, with_folder)
    source = files[path.name]
    return Taken(path, files, hashlib.sha256(source).hexdigest(), _parse(path, source))


def read_files(path: str | Path, with_folder: bool = False) -> dict[str, bytes]:
    """{file name: bytes} of the submission at ``path``, as ``take_in`` reads it: the file
    itself, and with ``with_folder`` the Python files beside it; nothing of it is parsed.

    Raises:
        RefusedSubmission: ``path`` is a link, not a regular file, or too large.
    """
    path = Path(path)
    files = {path.name: _read_regular(path)}
    if with_folder:
        files.update(_beside(path))
    return files


def _beside(path: Path) -> dict[str, bytes]:
    """The regular Python files beside ``path`` (not links, not hidden), or none if there are
    more than ``MAX_FILES`` or ``MAX_BYTES`` of them: a folder like that is not one
    student's exercise, and the file goes alone."""
    found: dict[str, bytes] = {}
    for other in sorted(path.parent.iterdir()):
        if other.name == path.name or other.suffix != ".py" or other.name.startswith("."):
            continue
        try:
            found[other.name] = _read_regular(other)
        except RefusedSubmission:
            continue  # a link or a special file beside it: not handed in
        if len(found) >= MAX_FILES or sum(map(len, found.values())) > MAX_BYTES:
            return {}
    return found


def _read_regular(path: Path) -> bytes:
    """The bytes of ``path``, which must be a regular file and not a symbolic link."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise RefusedSubmission(f"{path}: no such file") from None
    except OSError as error:
        if os.path.islink(path):
            raise RefusedSubmission(f"{path} is a symbolic link: hand in the file itself") from None
        raise RefusedSubmission(f"{path}: cannot read it: {error.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            raise RefusedSubmission(f"{path} is not a regular file")
        with os.fdopen(descriptor, "rb", closefd=False) as file:
            data = file.read(MAX_BYTES + 1)
    finally:
        os.close(descriptor)
    if len(data) > MAX_BYTES:
        raise RefusedSubmission(f"{path}: larger than {MAX_BYTES >> 20} MiB")
    return data


def _parse(path: Path, source: bytes) -> ast.Module:
    try:
        return ast.parse(source, filename=str(path))
    except SyntaxError as error:
        raise RefusedSubmission(f"{path}:{error.lineno}: syntax error: {error.msg}") from None
    except (ValueError, RecursionError, MemoryError) as error:
        raise RefusedSubmission(
            f"{path}: not a Python file Python can read ({type(error).__name__})"
        ) from None


def private_folder(taken: Taken, user: StudentUser | None) -> Path:
    """A new folder holding the submission's files, owned by ``user`` (or this process's
    user) and closed to every other user but root."""
    folder = Path(tempfile.mkdtemp(prefix="ptlab-student-"))
    for name, data in taken.files.items():
        (folder / name).write_bytes(data)
    if user is not None:
        for path in (folder, *folder.iterdir()):
            os.chown(path, user.uid, user.gid)
    return folder


def remove_folder(folder: Path) -> None:
    """Remove a private folder and whatever the student's code left in it."""
    shutil.rmtree(folder, ignore_errors=True)
