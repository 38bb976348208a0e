"""The ray-query interface that every acceleration structure implements.

A renderer asks two questions of the scene's triangles (pbrt-v4, section 7.1):

* ``intersect``: where does each ray first hit a triangle, and which one?
* ``occluded``: does anything lie between each ray's origin and a distance ``tmax``
  along it? (the shadow-ray query, which may stop at the first hit it finds)

Both work on whole batches of rays at once. Directions need not be unit vectors:
distances ``t`` are measured in units of each ray's own direction length, so a shadow
ray can be given as ``direction = target - origin`` with ``tmax`` just under 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass
class Hits:
    """The closest hits of a batch of N rays.

    Attributes:
        t: (N,) float32 ray parameter of the hit; ``inf`` where the ray missed.
        prim: (N,) intp index of the triangle hit; -1 where the ray missed.
        u, v: (N,) float32 barycentric coordinates of the hit point, so that
            ``p = (1 - u - v) * v0 + u * v1 + v * v2`` (Möller-Trumbore's and Embree's u, v).
    """

    t: np.ndarray
    prim: np.ndarray
    u: np.ndarray
    v: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        """(N,) bool: True where the ray hit a triangle."""
        return self.prim >= 0


class Accelerator(Protocol):
    """Answers ray queries against a fixed set of triangles (see module docstring)."""

    name: str  # the backend's name, e.g. "embree"

    def intersect(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        tmin: float | np.ndarray = 0.0,
        tmax: float | np.ndarray = np.inf,
    ) -> Hits:
        """Closest hit with ``tmin < t < tmax`` for each ray.

        origins, dirs: (N, 3) float arrays; tmin, tmax: scalars or (N,) arrays.
        """
        ...

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, tmax: float | np.ndarray) -> np.ndarray:
        """(N,) bool, True where some triangle lies at ``0 < t < tmax`` along the ray."""
        ...
