# %% [markdown]
# # Chapter 4 tutorial: the slab test, and the flat boxes a strict test misses
#
# A BVH skips every box a ray misses, so the test that decides is ray against axis-aligned
# box. A box is the intersection of three slabs, the regions between two parallel planes;
# along the ray `o + t d` slab k is crossed at `(box_min[k] - o[k]) / d[k]` and
# `(box_max[k] - o[k]) / d[k]`, and the ray is inside the box from `t_enter`, the latest of
# the three entries (and `tmin`), to `t_exit`, the earliest of the three exits (and `tmax`).
# It hits where `t_enter <= t_exit`. Chapter 4's exercise is that test, `slab_test` (the
# chapter's page: `ptlab exercise docs 4`).
#
# This tutorial asks the library's `slab_test` about a unit box and a flat one, counts the
# flat boxes in the Cornell box's BVH, then renders the Cornell box's normals through the
# NumPy BVH with the library's pieces and with the lecture slide's strict
# `t_enter < t_exit`.

# %%
"""Chapter 4 tutorial: the slab test, and the flat boxes a strict test misses.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/04_bounding_boxes.py       # writes bounding-boxes.png, bounding-boxes-wrong.png
    python docs/tutorials/04_bounding_boxes.py --res 64 --out /tmp/t
"""

from __future__ import annotations

import numpy as np

import ptlab
from ptlab.accel.numpy_bvh import build_bvh, slab_test
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.rendering.pieces import BVHPieces, Pieces

args, out = tutorial_options(__doc__, res=256, spp=4)


# %% [markdown]
# ## The mistake: a strict test
#
# The lecture slide says a ray hits the box when `t_enter < t_exit`, strictly. For a box of
# zero thickness along one axis, the box around a flat wall, every ray through it has
# `t_enter == t_exit`, and the strict test misses it. Here is that test, written over whole
# arrays as the library's is: `inv_dirs = 1 / d`, where a zero component gives `±inf`, so
# that rays parallel to a slab need no special case.


# %%
def strict_slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    """The classic mistake: a hit only where t_enter < t_exit, strictly."""
    with np.errstate(invalid="ignore"):
        t0 = (box_min - origins) * inv_dirs
        t1 = (box_max - origins) * inv_dirs
    t_enter = np.fmax(np.fmax.reduce(np.minimum(t0, t1), axis=1), tmin)
    t_exit = np.fmin(np.fmin.reduce(np.maximum(t0, t1), axis=1), tmax)
    return t_enter < t_exit, t_enter


# %% [markdown]
# ## Five rays, two tests
#
# Rays into the unit box from either side, from inside it, beside it, and one through the
# flat box that is the square `z = 1`. A ray that starts inside a box enters it at `tmin`.

# %%
rays = {
    "into the unit box along +x": ([-1, 0.5, 0.5], [1, 0, 0], [0, 0, 0], [1, 1, 1]),
    "into it along -x": ([2, 0.5, 0.5], [-1, 0, 0], [0, 0, 0], [1, 1, 1]),
    "starting inside it": ([0.5, 0.5, 0.5], [0, 1, 0], [0, 0, 0], [1, 1, 1]),
    "beside it, along +x": ([-1, 2, 0.5], [1, 0, 0], [0, 0, 0], [1, 1, 1]),
    "through the flat box": ([0.5, 0.5, 0], [0, 0, 1], [0, 0, 1], [1, 1, 1]),
}
origins, dirs, lo, hi = (np.array(a, np.float32) for a in zip(*rays.values(), strict=True))
with np.errstate(divide="ignore"):
    inv_dirs = 1 / dirs
for test in (slab_test, strict_slab_test):
    hit, t_enter = test(origins, inv_dirs, lo, hi, 0.0, np.inf)
    print(f"{test.__name__}:")
    for name, h, t in zip(rays, hit, t_enter, strict=True):
        print(f"  {name:28} {'hit at t = ' + format(t, '.2f') if h else 'miss'}")

# %% [markdown]
# ## Flat boxes are everywhere
#
# The Cornell box's walls, floor and ceiling are axis-aligned, so the leaves of its BVH
# around them are flat boxes.

# %%
scene = ptlab.load_scene("cornell-box")
bvh = build_bvh(scene.triangles)
flat = np.any(bvh.box_min == bvh.box_max, axis=1)
print(
    f"the Cornell box's BVH: {len(flat)} boxes, {flat.sum()} of them flat (leaves around "
    f"the axis-aligned walls)"
)

# %% [markdown]
# ## The two pictures
#
# The `normals` integrator colours each camera ray's first hit by its surface normal. The
# NumPy BVH (`backend="numpy"`) is walked with the pieces it is given:
# `Pieces(bvh=BVHPieces(slab_test=...))` puts the strict test in its place (in this process,
# `workers=1`: worker processes may not have this file's function). With it, the walls
# inside flat boxes vanish.

# %%
options = dict(spp=args.spp, res=args.res, integrator="normals", workers=1, backend="numpy")
write_image(out / "bounding-boxes.png", ptlab.render(scene, **options))
strict = Pieces(bvh=BVHPieces(slab_test=strict_slab_test))
write_image(out / "bounding-boxes-wrong.png", ptlab.render(scene, **options, pieces=strict))
print(
    f"wrote {out / 'bounding-boxes.png'} and {out / 'bounding-boxes-wrong.png'} (the second "
    f"with the strict test)"
)
show_pictures(out)
