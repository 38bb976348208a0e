"""Writing files atomically: to a temporary file beside the target, then a rename.

A crash or an interrupt while writing never leaves a truncated file under the final name:
readers see the old file or the new one, whole. ``check_writable_file`` and
``check_writable_folder`` try the same thing before a long render, so that a bad output
path is an error at once rather than at the end; ``path_kind`` looks at a path the user
gave without the OSError that ``Path.exists`` raises for a name too long.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path

from ptlab.errors import PtlabError


def write_atomically(path: str | Path, write: Callable[[str], None]) -> Path:
    """Call ``write(temporary_path)``, then move the result to ``path``."""
    path = Path(path)
    descriptor, temporary = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=path.suffix, dir=path.parent)
    os.close(descriptor)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(temporary, 0o666 & ~umask)  # mkstemp makes it private; give it normal permissions
    try:
        write(temporary)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)
    return path


def path_kind(path: str | Path) -> str | None:
    """What is at ``path``: "file", "folder", "other" (a device, a pipe) or None (nothing).

    Raises ``PtlabError`` for a path the system will not look up (a name too long or holding
    a NUL character, a folder on the way that may not be entered).
    """
    name = str(path)
    shown = name if len(name) <= 80 else f"{name[:60]}...({len(name)} characters)"
    if "\0" in name:
        raise PtlabError(f"{shown}: a file name cannot hold a NUL character")
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as error:
        raise PtlabError(f"{shown}: {error.strerror}") from None
    return "file" if stat.S_ISREG(mode) else "folder" if stat.S_ISDIR(mode) else "other"


def check_writable_file(path: str | Path) -> Path:
    """``path``, if ``write_atomically`` can write it; otherwise a ``PtlabError``."""
    path = Path(path)
    kind = path_kind(path)
    if kind == "folder":
        raise PtlabError(f"{path}: is a folder")
    if kind == "other":  # (a rename would replace a device such as /dev/null, as root)
        raise PtlabError(f"{path}: is not a regular file (a device or a pipe?): give a file name")
    parent = path_kind(path.parent)
    if parent != "folder":
        raise PtlabError(
            f"{path}: {path.parent} is not a folder"
            if parent
            else f"{path}: folder {path.parent} does not exist"
        )
    _try_writing_in(path.parent, path)
    return path


def check_writable_folder(path: str | Path) -> Path:
    """``path``, if it is a folder that files can be written in, or can be made one."""
    path = Path(path)
    if path_kind(path) not in (None, "folder"):
        raise PtlabError(f"{path}: exists and is not a folder")
    existing = next(p for p in (path.absolute(), *path.absolute().parents) if path_kind(p) is not None)
    if path_kind(existing) != "folder":
        raise PtlabError(f"{path}: {existing} is not a folder")
    _try_writing_in(existing, path)
    return path


def _try_writing_in(folder: Path, path: Path) -> None:
    # Permissions alone do not tell (root may write anywhere, but not in /proc or on a
    # read-only disk): make and remove a temporary file, as write_atomically would.
    try:
        descriptor, temporary = tempfile.mkstemp(prefix=".ptlab-check-", dir=folder)
    except OSError as error:
        raise PtlabError(f"{path}: cannot write in {folder}: {error.strerror}") from None
    os.close(descriptor)
    os.remove(temporary)
