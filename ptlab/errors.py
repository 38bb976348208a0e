"""Errors that are the user's to fix (a bad scene file, an absurd option).

The command line prints these as one line and exits with code 2, without a traceback;
anything else that goes wrong is a bug in ptlab and keeps its traceback.
"""

from numbers import Integral
from typing import TypeGuard


def is_integer(value: object) -> TypeGuard[int]:
    """True for an ``int`` or a NumPy integer (both are ``numbers.Integral``), not for a bool:
    ``spp=True`` is a mistake, not one sample. (No NumPy import: ``ptlab.cli`` imports this
    module before NumPy.)"""
    return isinstance(value, Integral) and not isinstance(value, bool)


def one_line(text: str) -> str:
    """``text`` with line breaks and other unprintable characters escaped (``\\n``), so that
    a name taken from the user's input (a TOML key, a file name) cannot break the line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class PtlabError(Exception):
    """A problem with the user's input, described in one line."""

    def __init__(self, message: object):
        super().__init__(one_line(str(message)))


class SceneError(PtlabError):
    """A scene file or one of its meshes is missing or malformed.

    The message names the file, the key (where there is one) and the problem.
    """

    def __init__(self, file: object, problem: str, key: str | None = None):
        where = f"{file}" if key is None else f"{file}: {key}"
        super().__init__(f"{where}: {problem}")


class NotInKitError(RuntimeError):
    """Raised by what a chapter's kit leaves out (``ptlab.course.sandbox.kit``): the student's
    code called the library's answer to the exercise, which its process does not have."""
