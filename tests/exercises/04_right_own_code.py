"""A right chapter-4 answer, written as a student would from the lecture's slab test (not
the library's code): the ray meets the box iff t_enter <= t_exit and t_exit >= 0, with
``np.fmax`` and ``np.fmin``, which skip the NaN of ``0 * inf`` (a ray parallel to a slab,
starting on its plane). It must get full marks; the chapter's typical wrong answers are
this file with the mistake patched in (wrong_answers.toml)."""

import numpy as np


def slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    with np.errstate(invalid="ignore"):
        t0 = (box_min - origins) * inv_dirs
        t1 = (box_max - origins) * inv_dirs
    t_near = np.minimum(t0, t1)
    t_far = np.maximum(t0, t1)
    t_enter = np.fmax(np.fmax.reduce(t_near, axis=1), tmin)
    t_exit = np.fmin(np.fmin.reduce(t_far, axis=1), tmax)
    return (t_enter <= t_exit) & (t_exit >= 0), t_enter
