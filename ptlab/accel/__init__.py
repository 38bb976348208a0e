"""Ray-query backends behind one interface (see ``ptlab.accel.base``).

``make_accelerator(triangles, backend)`` builds one:

* ``"embree"``: Intel Embree through embreex (fast; the default when it imports);
* ``"numpy"``: the teaching BVH written in pure NumPy (``ptlab.accel.numpy_bvh``);
* ``"auto"``: embree if it can be imported, else numpy.
"""

from __future__ import annotations

import numpy as np

from ptlab.accel.base import Accelerator, Hits
from ptlab.accel.numpy_bvh import BVHPieces, NumpyBVH

BACKENDS = ("auto", "embree", "numpy")

__all__ = ["BACKENDS", "Accelerator", "BVHPieces", "Hits", "make_accelerator", "resolve_backend"]


def resolve_backend(backend: str) -> str:
    """Turn ``"auto"`` into the backend that will really be used."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    if backend != "auto":
        return backend
    try:
        import embreex  # noqa: F401
    except ImportError:
        return "numpy"
    return "embree"


def make_accelerator(
    triangles: np.ndarray, backend: str = "auto", bvh: BVHPieces | None = None
) -> Accelerator:
    """Build the ray-query structure for (T, 3, 3) ``triangles`` with the named backend;
    ``bvh``: the NumPy BVH's pieces, if not the library's (Embree has none to give)."""
    backend = resolve_backend(backend)
    if backend == "embree":
        if bvh is not None and bvh != BVHPieces():
            raise ValueError("Embree builds and walks its own tree: BVH pieces need backend='numpy'")
        from ptlab.accel.embree import EmbreeAccelerator

        return EmbreeAccelerator(triangles)
    return NumpyBVH(triangles, pieces=bvh)
