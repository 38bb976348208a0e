"""NaN and infinite values in what a student's code gave back: a check fails on any, and says
where the first one is.

NaN compares False with everything: a check written as "fail if the error exceeds the
tolerance" passes when the error is NaN, and ``np.mean`` or ``np.max`` of an array with one
NaN in it is NaN. So the checks look for non-finite values first (``require_finite``), and
the comparisons are written the other way round, "pass only if the error is within the
tolerance", which NaN fails (the grading contract: non-finite values fail, docs/DESIGN.md).

The places are said in the student's terms: a row of the arrays their function returned
(``at_row``), a pixel of a picture, counted from the top left, in a pass of a render
(``at_pixel``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ptlab.course.chapter import CheckFailed, checked_array
from ptlab.course.messages import aside, text

CHANNELS = ("red", "green", "blue")


def channel_name(channel: int) -> str:
    """Colour ``channel`` (0, 1, 2) in words, in the active language."""
    return text(f"channel.{CHANNELS[channel]}")


#: ``where(index, shape)``: the place of element ``index`` of an array of ``shape``, in words.
Where = Callable[[tuple[int, ...], tuple[int, ...]], str]


def at_row(index: tuple[int, ...], shape: tuple[int, ...]) -> str:
    """ "row 17 of 500" of an (N,) array, "row 17 of 500, column 2" of an (N, K) one."""
    place = text("at_row", row=index[0], rows=shape[0])
    return place + "".join(text("at_column", column=i) for i in index[1:])


def at_pixel(index: tuple[int, ...], shape: tuple[int, ...]) -> str:
    """ "pixel (x=5, y=3) (red)" of an (H, W, 3) picture, with "in pass 2 of 12" (counted
    from 1) for (passes, H, W, 3) pass images (``ptlab.course.renders.pass_images``)."""
    *passes, y, x, channel = index
    place = text("at_pixel", x=x, y=y, channel=channel_name(channel))
    if passes:
        place += text("in_pass", number=passes[0] + 1, passes=shape[0])
    return place


def require_finite(values, what: str, where: Where = at_row, hint: str = "") -> None:
    """Fail the check if ``values`` (an array of any shape) hold a NaN or an infinity: "``what``
    has NaN at ``where(first such index)``", with how many more there are and ``hint`` (what
    may cause them)."""
    values = np.asarray(values)
    if values.dtype.kind not in "fc":  # integers and booleans are always finite
        return
    bad = ~np.isfinite(values)
    if not bad.any():
        return
    index = tuple(int(i) for i in np.unravel_index(np.flatnonzero(bad)[0], values.shape))
    value = values[index]
    kind = "NaN" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    others = int(bad.sum()) - 1
    raise CheckFailed(
        text("not_finite", what=what, kind=kind, where=where(index, values.shape))
        + (text("not_finite.more", others=others) if others else "")
        + aside(hint)
    )


def finite_array(value, name: str, shape: tuple, nan_hint: str = "", where: Where = at_row) -> np.ndarray:
    """``ptlab.course.chapter.checked_array`` (what the student's function ``name``
    returned, as float64 of ``shape``), saying where the first NaN or infinity is."""
    result = np.asarray(value, dtype=np.float64)
    if result.shape == tuple(shape):
        require_finite(result, text("returned", name=name), where, nan_hint)
    return checked_array(result, name, shape, nan_hint)
