"""ptlab's own answers, made unusable in the student's process before the student's file runs.

A chapter asks the student to write functions that the library has (``trace_paths``,
``Diffuse.eval``). The grader computes its references in its own process, so the student's
process never needs the library's versions: ``set_traps`` replaces the code of each of them
by a trap that raises ``LibraryAnswerCalled`` ("calls ptlab's own answer"). The code object
is replaced in place (``function.__code__``), so every name the function goes by is caught
at once: ``_lib = path.trace_paths``, ``from ptlab.rendering.jobs import trace_paths``, a
method inherited from ``Diffuse``. The library's code objects are dropped, so nothing in the
process can reach them again; reading ptlab's files to compile a fresh copy is refused by
``ptlab.untrusted.confinement``.
"""

from __future__ import annotations

import inspect
import sys
import types

from ptlab.untrusted.copies import ANSWER_METHODS, resolve


class LibraryAnswerCalled(BaseException):
    """The student's code called one of ptlab's own answers.

    A ``BaseException``, so that an ``except Exception`` in the student's code does not
    swallow it.
    """


def called() -> None:
    """Raise ``LibraryAnswerCalled`` for the trap that calls this (its code's qualified name
    is the answer's dotted name)."""
    origin = sys._getframe(1).f_code.co_qualname
    raise LibraryAnswerCalled(f"calls ptlab's own answer ({origin}), not yours: write it yourself")


def _trap(*args, **kwargs):
    # Resolved through builtins only: this code runs with the globals of the library
    # function it replaces.
    __import__("ptlab.untrusted.traps", fromlist=["called"]).called()


def set_traps(names: tuple[str, ...]) -> None:
    """Replace each of ``names`` (dotted: a function, or a class whose ``ANSWER_METHODS`` it
    defines) by a trap, for the rest of this process's life."""
    for name in names:
        value = resolve(name)
        if inspect.isclass(value):
            for method in ANSWER_METHODS:
                if method in value.__dict__:
                    _replace(value, method, value.__dict__[method], f"{name}.{method}")
        else:
            owner, _, attribute = name.rpartition(".")
            _replace(resolve(owner), attribute, value, name)


def _replace(owner, attribute: str, function, origin: str) -> None:
    code = _trap.__code__.replace(co_name=attribute, co_qualname=origin)
    try:
        function.__code__ = code
    except ValueError:  # a method with a closure (super()): rebind it where it lives
        setattr(owner, attribute, types.FunctionType(code, {"__builtins__": __builtins__}))
