"""Exercises: from Whitted ray tracing to path tracing, one function at a time.

Each chapter (``docs/NN-name.md``, which ``ptlab exercise docs NN`` prints) asks the student
to write one or a few functions of the renderer. ``ptlab exercise start NN`` copies the
chapter's exercise file (signatures, docstrings, hints, ``NotImplementedError`` bodies);
``ptlab exercise check NN FILE`` plugs the student's functions into the renderer in place of
the library's own and runs the chapter's checks (``ptlab.course.grader``): unit checks
against known answers, the material harness where it applies, and a statistical comparison
of a render with the library's.

A chapter is a module ``ptlab.course.chapters.chNN_name`` that defines ``CHAPTER``;
its exercise file is ``templates/NN_name.py`` and the library's own answer, in the same
form, ``solutions/NN_name.py`` (which graders and tests use as the model answer).
"""

from __future__ import annotations

import importlib
import pkgutil

from ptlab.course.chapter import HERE, Chapter
from ptlab.errors import PtlabError

__all__ = ["Chapter", "all_chapters", "chapter"]


def all_chapters() -> list[Chapter]:
    """Every chapter, in order."""
    found = []
    for info in pkgutil.iter_modules([str(HERE / "chapters")]):
        module = importlib.import_module(f"ptlab.course.chapters.{info.name}")
        found.append(module.CHAPTER)
    return sorted(found, key=lambda c: c.number)


def chapter(number: int | str) -> Chapter:
    """The chapter ``number`` (``3`` or ``"03"``); a ``PtlabError`` if there is none."""
    try:
        wanted = int(number)
    except (TypeError, ValueError):
        wanted = None
    for found in all_chapters():
        if found.number == wanted:
            return found
    available = ", ".join(f"{c.number:02d}" for c in all_chapters())
    raise PtlabError(f"chapter {number!r}: there is no such chapter (chapters: {available})")
