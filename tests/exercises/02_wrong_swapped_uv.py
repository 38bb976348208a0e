"""A typical wrong chapter-2 answer: the barycentrics mixed up. The lecture's b1 (which
weighs v1, so goes with e1) is ``S1 . S / det`` and b2 is ``S2 . D / det``; this answer
swaps them. Hits and t are right, but every hit point lands on the mirror image of the
true one inside its triangle: the renderer builds the point from u and v, so shadows and
lighting come out in the wrong places."""

import numpy as np

EXPECTED_FAILURES = ("known hits", "outside each edge", "behind the origin", "both faces", "many rays",
                     "render")
#: What the messages must say: (u, v) pairs printed alike for the expected and the answer;
#: an error of 0.94 named as swapped barycentrics, not as float32 rounding.
EXPECTED_HINTS = {"behind the origin": ("(0.25, 0.5) and (0.6, 0.2)", "(0.5, 0.25) and (0.2, 0.6)",
                                        "swapped"),
                  "many rays": ("u and v are swapped",)}
MISLEADING_HINTS = {"many rays": ("float32",)}


def ray_triangle(origins, dirs, v0, e1, e2):
    s1 = np.cross(dirs, e2)
    det = (s1 * e1).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = origins - v0
        s2 = np.cross(s, e1)
        t = (s2 * e2).sum(axis=1) / det
        u = (s2 * dirs).sum(axis=1) / det
        v = (s1 * s).sum(axis=1) / det
    hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(hit, t, np.inf), u, v
