"""Chapter 4: bounding boxes, the slab test.

The chapter's page: ``ptlab exercise docs 4`` (中文: ``--zh``).

Write ``slab_test``: does each ray pass through its axis-aligned box, and where does it
enter? The BVH (chapter 5) asks this for every node it visits. Check your work with

    ptlab exercise check 4 04_bounding_boxes.py

Everything is whole arrays: row i of every argument belongs to ray i, and you answer for
all rays at once with NumPy operations, never a Python loop over rays (the render check
runs your function on millions of ray-box pairs, with a time limit).
"""

import numpy as np


def slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    """Ray against axis-aligned box, one box per ray.

    A box is the overlap of three slabs, ``box_min[k] <= x[k] <= box_max[k]`` for the
    axes k = x, y, z. Along a ray ``o + t * d``, slab k is crossed at
    ``t = (box_min[k] - o[k]) / d[k]`` and ``t = (box_max[k] - o[k]) / d[k]``; the ray is
    inside the box for the ``t`` that lie in all three of those intervals and in
    ``[tmin, tmax]``.

    Args:
        origins: (N, 3) ray origins (float32).
        inv_dirs: (N, 3) ``1 / dirs``, computed for you: a zero direction component
            gives ``+inf`` or ``-inf``.
        box_min, box_max: (N, 3) the corners of each ray's box. A box may be flat:
            ``box_min[k] == box_max[k]`` around an axis-aligned quad such as the Cornell
            box's floor.
        tmin, tmax: Python floats or (N,) arrays: the part of each ray to consider.

    Returns:
        hit: (N,) bool, True where the ray meets the box for some t in [tmin, tmax].
        t_enter: (N,) float, where it enters: the latest of the three near crossings
            and ``tmin`` (so ``tmin`` for a ray that starts inside the box). Only read
            where ``hit`` is True.

    Hints:
        * For a negative direction component the ``box_max`` plane is crossed first:
          ``np.minimum`` and ``np.maximum`` of the two crossings give each slab's near
          and far t whatever the sign.
        * The ray is in the box from t_enter (the largest near t, and tmin) to t_exit
          (the smallest far t, and tmax). Is ``t_enter == t_exit`` a hit? Think of a
          flat box.
        * A ray with ``d[k] == 0`` that starts exactly on a slab's plane computes
          ``0 * inf = NaN``: it runs inside that slab (its boundary belongs to the box), so
          that axis must not restrict it. ``np.maximum`` and ``np.minimum`` spread NaN
          (a NaN in t0 or t1 makes both that axis's near and far t NaN); ``np.fmax`` and
          ``np.fmin`` skip it (``np.fmax.reduce(a, axis=1)`` over the three axes).
        * That ``0 * inf`` is meant, so NumPy's "RuntimeWarning: invalid value encountered
          in multiply" says nothing wrong here. Compute the crossings inside
          ``with np.errstate(invalid="ignore"):`` to keep it quiet.
    """
    raise NotImplementedError("slab_test")
