"""The command that a failing render check suggests: ``ptlab exercise inspect`` at the pixel
where the student's image differs most from the library's (``ptlab.course.inspection``
runs it)."""

from __future__ import annotations

import numpy as np

from ptlab.course.messages import text


def suggestion(number: int, student: np.ndarray, library: np.ndarray, seed: int) -> str:
    """What a failing render check of chapter ``number`` adds: the ``ptlab exercise inspect``
    command for the pixel where the student's image differs most from the library's
    (``student``, ``library``: (H, W, 3) images or (passes, H, W, 3) of a render of seed
    ``seed``, whose first samples the command traces again)."""
    if student.ndim == 4:
        student, library = student.mean(axis=0), library.mean(axis=0)
    difference = np.nan_to_num(np.abs(np.asarray(student, np.float64) - library), nan=np.inf).sum(axis=2)
    y, x = np.unravel_index(int(np.argmax(difference)), difference.shape)
    return text("inspect.suggest", chapter=number, x=int(x), y=int(y), seed=seed)
