"""Stand-ins, in the grader's process, for the objects of a student's process.

The grader's checks are written as if they had the student's module in hand: they call
``module.trace_paths(...)``, build ``module.Lambertian(albedo)`` and put it in a scene.
They get ``RemoteModule``, ``RemoteFunction`` and ``RemoteObject`` instead: attribute access
asks the student's process, calling one sends the call there (``Submission.call``), and
what comes back is plain data or more stand-ins. A stand-in answers nothing on its own:
no special method (``__len__``, ``__array__``, ``__eq__``, ...) and no name starting with
``_`` reaches the student's process, so NumPy and the checks treat it as an opaque object.

An exception the student's code raised comes back as a ``StudentError`` whose class has the
name of the student's exception (``type(error).__name__`` reads ``ZeroDivisionError``), with
its message and the line of the student's file it came from.
"""

from __future__ import annotations

import contextlib
import inspect
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from ptlab.course.sandbox.rules import Rules

#: Longest name of a student's class or exception shown as such.
MAX_NAME = 60


class StudentProcess(Protocol):
    """What a stand-in needs of the student's process: of the ``Submission`` that runs it
    (``ptlab.course.sandbox.submission``)."""

    path: Path
    rules: Rules

    def request(self, operation: str, *arguments, during: str): ...

    def call(self, function: RemoteFunction, args: tuple, kwargs: dict): ...


def _safe_name(name: str, fallback: str) -> str:
    return name if name.isidentifier() and len(name) <= MAX_NAME else fallback


class StudentError(Exception):
    """An exception raised by the student's code in its own process.

    Attributes:
        type_name: the name of the exception's class (``"ValueError"``).
        where: ``file.py:line`` of the student's file where it came from, or None.
        not_implemented: the exception was a ``NotImplementedError`` (code not written yet).
    """

    def __init__(self, type_name: str, message: str, where: str | None, not_implemented: bool):
        super().__init__(message)
        self.type_name, self.where, self.not_implemented = type_name, where, not_implemented

    def describe(self) -> str:
        """One line for the student: the error, its message and where it came from."""
        place = self.where or "raised outside your file"
        if self.not_implemented:
            name = f"{self} " if str(self) else ""
            return f"{name}is not written yet: it still raises NotImplementedError ({place})"
        if self.type_name == "NotInKitError":  # the library's answer, left out of the kit
            return f"{self} ({place})"
        return f"{self.type_name}: {self} ({place})"


class ArgumentChanged(StudentError):  # noqa: N818 (a verdict, like the errors it stands beside)
    """The student's function changed an argument it may only read (the grader's verdict,
    ``ptlab.course.sandbox.rules.Arguments``)."""

    def __init__(self, message: str):
        super().__init__("ArgumentChanged", message, None, False)

    def describe(self) -> str:
        return str(self)


_error_classes: dict[str, type] = {}
_object_classes: dict[str, type] = {}


def student_error(type_name: str, message: str, where: str | None, not_implemented: bool) -> StudentError:
    """A ``StudentError`` of a class named ``type_name`` (made once per name)."""
    name = _safe_name(type_name, "StudentError")
    cls = _error_classes.get(name)
    if cls is None:
        cls = _error_classes[name] = type(name, (StudentError,), {"__module__": "student"})
    return cls(name, message, where, not_implemented)


class RemoteFunction:
    """A function, method or class of the student's process; calling it runs it there.

    Attributes:
        kind: ``"function"``, ``"method"`` or ``"class"``.
        origin: the dotted name of ptlab's own function or class this is, according to the
            student's process (``ptlab.course.sandbox.ownership`` looks at the file itself).
        arguments: what it may do to its arguments (see ``__init__``).
    """

    def __init__(self, submission: StudentProcess, tag: dict):
        self._submission, self._handle = submission, tag["function"]
        self.__name__ = self.__qualname__ = tag["name"]
        self.kind, self.origin = tag["kind"], tag["origin"]
        #: What it may do to its arguments (``ptlab.course.sandbox.rules.Arguments``): set by the
        #: module it was taken from, for the graded functions; None drops every change.
        self.arguments = None
        if tag["parameters"] is not None:
            # (names or an order Python would not accept: no signature)
            with contextlib.suppress(TypeError, ValueError):
                self.__signature__ = inspect.Signature(
                    [
                        inspect.Parameter(name, inspect._ParameterKind(kind))
                        for name, kind in tag["parameters"]
                    ]
                )

    @property
    def is_class(self) -> bool:
        return self.kind == "class"

    def __call__(self, *args, **kwargs):
        return self._submission.call(self, args, kwargs)

    def __repr__(self) -> str:
        return f"<the student's {self.kind} {self.__name__}>"


class RemoteObject:
    """Any other object of the student's process: its attributes are fetched from there
    (functions and methods once, then kept), and set there."""

    def __init__(self, submission: StudentProcess, handle: int, type_name: str):
        object.__setattr__(self, "_submission", submission)
        object.__setattr__(self, "_handle", handle)
        object.__setattr__(self, "_type_name", type_name)
        object.__setattr__(self, "_callables", {})

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if name in self._callables:
            return self._callables[name]
        try:
            value = self._submission.request("get", self._handle, name, during=self._name_of(name))
        except StudentError as error:
            if error.type_name == "AttributeError":
                raise AttributeError(str(error)) from None
            raise
        if isinstance(value, RemoteFunction):
            self._callables[name] = value
        return value

    def __setattr__(self, name: str, value) -> None:
        if name.startswith("_"):
            raise AttributeError(f"cannot set {name} on the student's object")
        self._callables.pop(name, None)
        self._submission.request("set", self._handle, name, value, during=f"setting {self._name_of(name)}")

    def _name_of(self, attribute: str) -> str:
        return f"{self._type_name}.{attribute}"

    def __repr__(self) -> str:
        return f"{self._type_name} object"


def remote_object(submission: StudentProcess, handle: int, type_name: str) -> RemoteObject:
    """A ``RemoteObject`` whose class is named like the student's (for messages)."""
    name = _safe_name(type_name, "StudentObject")
    cls = _object_classes.get(name)
    if cls is None:
        cls = _object_classes[name] = type(name, (RemoteObject,), {"__module__": "student"})
        STAND_INS.add(cls)
    return cls(submission, handle, name)


class RemoteModule(RemoteObject):
    """The student's module (object 0 of its process). Its functions get the grader's
    rules for their arguments, looked up by the name the grader asked for."""

    def __init__(self, submission: StudentProcess, handle: int = 0):
        super().__init__(submission, handle, "module")

    def __getattr__(self, name: str):
        value = super().__getattr__(name)
        if isinstance(value, RemoteFunction):
            value.arguments = self._submission.rules.arguments.get(name)
        return value

    def _name_of(self, attribute: str) -> str:
        return attribute

    def __repr__(self) -> str:
        return f"<the student's file {self._submission.path.name}>"


#: Every class of stand-in (the pickler looks an object's exact type up here).
STAND_INS: set[type] = {RemoteFunction, RemoteObject, RemoteModule}


def submission_of(proxy: RemoteObject | RemoteFunction) -> StudentProcess:
    """The ``Submission`` a stand-in belongs to."""
    return object.__getattribute__(proxy, "_submission")
