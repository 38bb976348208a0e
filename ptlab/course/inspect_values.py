"""How ``ptlab exercise inspect`` compares the values a student's code computed with the
library's, and shows them (``ptlab.course.inspection``, ``ptlab.course.inspect_microfacet``)."""

from __future__ import annotations

from typing import Any

import numpy as np

#: Two values are the same to this relative and absolute tolerance (float32 rounding of two
#: right answers that compute alike differs by about 1e-6).
RTOL, ATOL = 1e-3, 1e-5


def same(a: Any, b: Any, rtol: float = RTOL, atol: float = ATOL) -> bool:
    """Are two recorded values the same (numbers and lists to ``rtol``, ``atol``)?"""
    if isinstance(a, bool | str) or isinstance(b, bool | str) or a is None or b is None:
        return a == b
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return x.shape == y.shape and bool(np.allclose(x, y, rtol=rtol, atol=atol, equal_nan=True))


def shown_value(value: Any, digits: int = 4) -> str:
    """A recorded value in a message: numbers in ``digits`` significant digits."""
    if isinstance(value, bool | str) or value is None:
        return str(value)
    array = np.asarray(value, dtype=np.float64)
    if array.ndim == 0:
        return f"{float(array):.{digits}g}"
    return "(" + ", ".join(f"{x:.{digits}g}" for x in array.ravel()) + ")"
