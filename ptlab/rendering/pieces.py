"""The exercise-sized pieces of the renderer, passed to a render in its setup.

A render is made of small functions with stable signatures: the primary rays, the
ray-triangle test and the BVH's (``BVHPieces``), the smooth surface's laws and the path
loop's steps (``PathPieces``), and the path loop itself. ``Pieces`` gathers them; a render
uses the library's unless it is given others (``ptlab.render(..., pieces=...)``), which is
how the course renders with a student's functions in place of the library's. Nothing in the
renderer is replaced at run time: each piece is found where the render's setup carries it.

A render with worker processes sends its pieces to them, which works for functions of a
module the workers can import; others (a notebook's own, a student's stand-ins) need a
render in this process (``workers=1``, or a thread pool as its executor).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ptlab.accel.numpy_bvh import BVHPieces
from ptlab.camera import generate_rays
from ptlab.integrators.path import PathPieces

__all__ = ["LIBRARY", "BVHPieces", "PathPieces", "Pieces"]


@dataclass(frozen=True)
class Pieces:
    """The functions a render is made of (the module docstring).

    Attributes:
        generate_rays: the camera's primary rays, as ``ptlab.camera.generate_rays``.
        trace_paths: a path loop in place of the library's, with the homework's signature
            ``(film, scene, accel, paths, sampler, settings) -> rays`` and called one job's
            paths at a time; None (default) for the library's own
            (``ptlab.integrators.path.trace_paths``, which keeps its batch full across jobs).
        bvh: the NumPy BVH's pieces (a render with other than the library's needs
            ``backend="numpy"``).
        path: the path loop's steps and the Whitted tracer's laws, which a render puts in
            its ``PathSettings``.
    """

    generate_rays: Callable[..., tuple[np.ndarray, np.ndarray]] = generate_rays
    trace_paths: Callable[..., int] | None = None
    bvh: BVHPieces = field(default_factory=BVHPieces)
    path: PathPieces = field(default_factory=PathPieces)


#: The library's own pieces, the default of every render.
LIBRARY = Pieces()
