"""A right chapter-2 answer, written as a student would from the lecture's Möller-Trumbore
(not the library's code): both faces are hits, t may be negative, a miss is inf. It must
get full marks; the chapter's typical wrong answers are this file with the mistake patched
in (wrong_answers.toml)."""

import numpy as np


def ray_triangle(origins, dirs, v0, e1, e2):
    s1 = np.cross(dirs, e2)
    det = (s1 * e1).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = origins - v0
        s2 = np.cross(s, e1)
        t = (s2 * e2).sum(axis=1) / det
        u = (s1 * s).sum(axis=1) / det
        v = (s2 * dirs).sum(axis=1) / det
    hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(hit, t, np.inf), u, v
