"""A typical wrong chapter-2 answer, written the way the homework's scalar
``rayTriangleIntersect`` is often written: it culls back faces (only ``det > 0`` counts)
and keeps only hits in front of the origin (``t > 0``). In ptlab both faces are hits, and
a negative ``t`` is returned: the BVH keeps ``tmin < t < tmax`` itself."""

import numpy as np

EXPECTED_FAILURES = ("behind the origin", "both faces", "many rays")


def ray_triangle(origins, dirs, v0, e1, e2):
    s1 = np.cross(dirs, e2)
    det = (s1 * e1).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = origins - v0
        s2 = np.cross(s, e1)
        t = (s2 * e2).sum(axis=1) / det
        u = (s1 * s).sum(axis=1) / det
        v = (s2 * dirs).sum(axis=1) / det
    hit = (det > 1e-8) & (t > 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(hit, t, np.inf), u, v
