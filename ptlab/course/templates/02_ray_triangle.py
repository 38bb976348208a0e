"""Chapter 2: ray-triangle intersection, Möller-Trumbore.

The chapter's page: ``ptlab exercise docs 2`` (中文: ``--zh``).

Write ``ray_triangle``: where does each ray meet the plane of its triangle, and is that
point inside the triangle? The BVH (chapters 4 and 5) calls it for every ray that reaches
a leaf. Check your work with

    ptlab exercise check 2 02_ray_triangle.py

Everything is whole arrays: row i of every argument belongs to ray i, and you answer for
all rays at once with NumPy operations, never a Python loop over rays (the render check
calls your function on hundreds of thousands of rays, with a time limit).
"""

import numpy as np


def ray_triangle(origins, dirs, v0, e1, e2):
    """Möller-Trumbore intersection of rays with triangles, one triangle per ray.

    A point of the triangle (v0, v1, v2) is ``(1 - u - v) * v0 + u * v1 + v * v2``, a
    point of the ray ``o + t * d``. Setting them equal,

        o + t d = v0 + u e1 + v e2,    e1 = v1 - v0, e2 = v2 - v0,

    is a 3x3 linear system for (t, u, v). Cramer's rule solves it with

        s = o - v0,   s1 = d x e2,   s2 = s x e1,   det = s1 . e1,
        t = (s2 . e2) / det,   u = (s1 . s) / det,   v = (s2 . d) / det

    (GAMES101 lecture 13; Möller and Trumbore 1997). The ray's line meets the triangle
    where u >= 0, v >= 0 and u + v <= 1.

    Args:
        origins: (N, 3) ray origins ``o``.
        dirs: (N, 3) ray directions ``d``, not necessarily of length 1: ``t`` counts in
            units of ``|d|`` (do not normalise them).
        v0: (N, 3) first vertex of each ray's triangle.
        e1, e2: (N, 3) the triangle's edges ``v1 - v0`` and ``v2 - v0``.
        (The renderer passes float32 arrays; the checks pass float64.)

    Returns:
        t: (N,) ray parameter of the hit point, ``np.inf`` where the ray's line misses
            the triangle or is parallel to it (never NaN). A triangle *behind* the
            origin is a hit with negative ``t``: keeping only ``tmin < t < tmax`` is the
            caller's job.
        u, v: (N,) barycentric coordinates of the hit point (any value where t is inf).

    Hints:
        * A dot product of two (N, 3) arrays row by row is ``(a * b).sum(axis=1)``;
          ``np.cross(a, b)`` crosses them row by row.
        * Both faces count: a ray that sees the triangle's back has ``det < 0``, and is
          a hit all the same (no back-face culling).
        * ``det == 0`` means the ray is parallel to the triangle's plane: the division
          gives inf or NaN there (``np.errstate(divide="ignore", invalid="ignore")``
          silences the warnings); mark those rays as misses with ``t = inf`` yourself.
        * Build a boolean mask of the hits, then ``np.where(mask, t, np.inf)``.
    """
    raise NotImplementedError("ray_triangle")
