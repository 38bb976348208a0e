"""The course: from Whitted ray tracing to path tracing, one function at a time.

The course is the second of ptlab's two trees: it imports the renderer (everything of ptlab
outside ``ptlab.course``), which imports nothing of it (docs/architecture.md). Each chapter
(``docs/NN-name.md``, which ``ptlab exercise docs NN`` prints) asks the student to write one
or a few functions of the renderer. ``ptlab exercise start NN`` copies the chapter's
exercise file (signatures, docstrings, hints, ``NotImplementedError`` bodies); ``ptlab
exercise check NN FILE`` runs the chapter's checks (``ptlab.course.grader``): unit checks
against known answers, the material harness where it applies, and a statistical comparison
of a render made with the student's functions as its pieces (``ptlab.rendering.pieces``)
with the library's. The student's code runs in a sandbox (``ptlab.course.sandbox``).

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
