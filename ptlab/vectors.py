"""Arrays of 3-vectors, laid out for speed: (N, 3) in shape, (3, N) in memory.

Every batch of vectors (origins, directions, normals, colours) is an (N, 3) array, as the
interfaces promise, but stored column by column ("Fortran order": the x of every row, then
every y, then every z). NumPy then runs each operation as three long contiguous loops
instead of N loops of length 3, several times faster (docs/performance.md). ``a[:, 0]`` is
contiguous too.

Code that makes new (N, 3) arrays keeps the layout with ``vec3``, ``take_rows`` and ``cross``;
plain arithmetic between such arrays keeps it by itself (NumPy follows the inputs' layout).
``dot``, ``cross`` and ``normalize`` take any (..., 3) arrays: rows, one (3,) vector, or the
(N, K, 3) pairs of rays and triangles that ``ptlab.accel`` tests.
"""

from __future__ import annotations

import numpy as np


def vec3(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Stack (N,) components into an (N, 3) array stored column by column."""
    return np.stack([x, y, z]).T


def take_rows(a: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Rows ``index`` of an (N, K) column-major array (or an (N,) one), keeping the layout."""
    if a.ndim == 1:
        return a.take(index)
    # Gathering along the contiguous axis of the (K, N) transpose is the fast direction.
    return a.T.take(index, axis=1).T


def concatenate_rows(arrays: list[np.ndarray]) -> np.ndarray:
    """(N, K) arrays one after the other (or (N,) ones), keeping the column-major layout."""
    if arrays[0].ndim == 1:
        return np.concatenate(arrays)
    return np.concatenate([a.T for a in arrays], axis=1).T


def columns(a: np.ndarray) -> np.ndarray:
    """An (N, K) array in column-major layout (a no-op when it already is)."""
    return np.asfortranarray(a)


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot products of (..., 3) vectors -> (...): (N, 3) rows, one (3,) vector, (N, K, 3) pairs.

    Written out component by component: faster than ``(a * b).sum(-1)``.
    """
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 3) cross products of (..., 3) vectors (``a`` and ``b`` broadcast together)."""
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    # One column-major array (each component contiguous) whose components are written in
    # place: no np.stack or moveaxis copy.
    c = np.empty(np.broadcast_shapes(a.shape, b.shape), np.result_type(a, b), order="F")
    np.subtract(ay * bz, az * by, out=c[..., 0])
    np.subtract(az * bx, ax * bz, out=c[..., 1])
    np.subtract(ax * by, ay * bx, out=c[..., 2])
    return c


def normalize(v: np.ndarray) -> np.ndarray:
    """(..., 3) vectors scaled to unit length; vectors of length 0 stay 0 (never NaN)."""
    length = np.sqrt(dot(v, v))
    return v / np.where(length > 0, length, 1)[..., None]


def channels(colour: np.ndarray) -> np.ndarray:
    """A (3,) or (N, 3) colour as (3, 1) or (3, N), to scale (N,) rows channel by channel.

    ``(channels(c) * s).T`` is then an (N, 3) array in this module's column-major layout.
    """
    return colour[:, None] if colour.ndim == 1 else colour.T


#: Names that lived here and moved, for the students' files that still import them from here
#: (``ptlab.scattering`` gathered the smooth surface's formulas).
MOVED = {"reflect": "ptlab.scattering.reflect"}


def __getattr__(name: str):
    """An old name of this module (``MOVED``), from where it lives now (PEP 562)."""
    if name in MOVED:
        import importlib

        module, _, attribute = MOVED[name].rpartition(".")
        return getattr(importlib.import_module(module), attribute)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
