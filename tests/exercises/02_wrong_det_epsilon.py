"""A typical wrong chapter-2 answer: the division by det "guarded" with a small epsilon,
``/ (det + 1e-6)``. Hits far from parallel look right, but every t, u and v is off by about
1e-6 / det: small errors, larger than rounding, that the random rays show."""

import numpy as np

EXPECTED_FAILURES = ("many rays",)
EXPECTED_HINTS = {"many rays": ("a small error", "an epsilon added to det")}


def ray_triangle(origins, dirs, v0, e1, e2):
    s1 = np.cross(dirs, e2)
    det = (s1 * e1).sum(axis=1)
    s = origins - v0
    s2 = np.cross(s, e1)
    inv_det = 1 / (det + 1e-6)      # (the bug: exact hits need 1 / det)
    t = (s2 * e2).sum(axis=1) * inv_det
    u = (s1 * s).sum(axis=1) * inv_det
    v = (s2 * dirs).sum(axis=1) * inv_det
    hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(hit, t, np.inf), u, v
