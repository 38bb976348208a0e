"""The command that a failing render check suggests: ``ptlab exercise inspect`` at the pixel
where the student's image differs most from the library's (``ptlab.course.inspection``
runs it), naming the file being graded as the student gave it (``graded_file``), ready to
paste."""

from __future__ import annotations

import shlex
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import numpy as np

from ptlab.course.messages import text

#: The file the suggested command names, quoted for a shell (``graded_file``); None: unknown.
_GRADED_FILE: ContextVar[str | None] = ContextVar("graded_file", default=None)


@contextmanager
def graded_file(path: str | Path) -> Iterator[None]:
    """A ``with`` block grading ``path`` (as the student typed it): ``suggestion`` names it.
    Outside one, the command names a placeholder ("YOUR_FILE")."""
    token = _GRADED_FILE.set(shlex.quote(str(path)))
    try:
        yield
    finally:
        _GRADED_FILE.reset(token)


def suggestion(number: int, student: np.ndarray, library: np.ndarray, seed: int) -> str:
    """What a failing render check of chapter ``number`` adds: the ``ptlab exercise inspect``
    command for the pixel where the student's image differs most from the library's
    (``student``, ``library``: (H, W, 3) images or (passes, H, W, 3) of a render of seed
    ``seed``, whose first samples the command traces again)."""
    if student.ndim == 4:
        student, library = student.mean(axis=0), library.mean(axis=0)
    difference = np.nan_to_num(np.abs(np.asarray(student, np.float64) - library), nan=np.inf).sum(axis=2)
    y, x = np.unravel_index(int(np.argmax(difference)), difference.shape)
    file = _GRADED_FILE.get() or text("inspect.your_file")
    return text("inspect.suggest", chapter=number, file=file, x=int(x), y=int(y), seed=seed)
