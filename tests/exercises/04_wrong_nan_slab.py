"""A typical wrong chapter-4 answer: right in general, with ``<=``, but ``np.maximum`` and
``.max`` spread NaN. A ray with a zero direction component (``inv_dirs = ±inf``) that
starts exactly on that slab's plane computes ``0 * inf = NaN``; the NaN becomes t_enter,
every comparison with it is False, and the ray misses a box it runs along (or a flat box
it lies in)."""

import numpy as np

EXPECTED_FAILURES = ("parallel to a slab", "flat boxes")


def slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    t0 = (box_min - origins) * inv_dirs
    t1 = (box_max - origins) * inv_dirs
    t_enter = np.maximum(np.minimum(t0, t1).max(axis=1), tmin)
    t_exit = np.minimum(np.maximum(t0, t1).min(axis=1), tmax)
    return t_enter <= t_exit, t_enter
