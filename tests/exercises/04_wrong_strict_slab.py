"""A typical wrong chapter-4 answer: the slab test of the lecture slide, "the ray meets
the box iff t_enter < t_exit and t_exit >= 0", with a strict ``<``. A flat box (zero
thickness along an axis, like the BVH leaves around the Cornell box's axis-aligned walls)
has t_enter == t_exit for every ray through it, so those walls vanish from the picture."""

import numpy as np

EXPECTED_FAILURES = ("flat boxes", "render")


def slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    with np.errstate(invalid="ignore"):
        t0 = (box_min - origins) * inv_dirs
        t1 = (box_max - origins) * inv_dirs
    t_near = np.minimum(t0, t1)
    t_far = np.maximum(t0, t1)
    t_enter = np.fmax(np.fmax.reduce(t_near, axis=1), tmin)
    t_exit = np.fmin(np.fmin.reduce(t_far, axis=1), tmax)
    return (t_enter < t_exit) & (t_exit >= 0), t_enter
