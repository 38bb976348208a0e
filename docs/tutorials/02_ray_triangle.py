# %% [markdown]
# # Chapter 2 tutorial: what Möller-Trumbore finds, and what swapped barycentrics do
#
# A point on a ray is `o + t d`; a point of the triangle `(v0, v1, v2)` is
# `v0 + u e1 + v e2`, with `e1 = v1 - v0`, `e2 = v2 - v0` and barycentric weights
# `(1 - u - v, u, v)`. Where the two are equal the ray meets the triangle's plane: three
# equations in `t, u, v`, which Möller and Trumbore solve with two cross products and four
# dot products. The point is inside the triangle when `u >= 0`, `v >= 0` and `u + v <= 1`.
# Chapter 2's exercise is that function, `ray_triangle` (the chapter's page:
# `ptlab exercise docs 2`).
#
# This tutorial asks the library's `ptlab.accel.triangle.ray_triangle` about five telling
# rays, then path-traces the Cornell box through the NumPy BVH twice: with the library's
# intersection, and with the chapter's typical mistake, `u` and `v` swapped.

# %%
"""Chapter 2 tutorial: what Möller-Trumbore finds, and what swapped barycentrics do.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/02_ray_triangle.py         # writes ray-triangle.png, ray-triangle-wrong.png
    python docs/tutorials/02_ray_triangle.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import numpy as np

import ptlab
from ptlab.accel.triangle import ray_triangle
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.rendering.pieces import BVHPieces, Pieces

args, out = tutorial_options(__doc__, res=128, spp=16)

# %% [markdown]
# ## Five rays and one triangle
#
# The triangle `(0,0,0), (1,0,0), (0,1,0)` lies in the plane `z = 0`. `ray_triangle` takes
# one triangle per ray, as arrays, and answers for the *line*: a triangle behind the origin
# comes back with a negative `t` (keeping only `tmin < t < tmax` is the BVH's job), a
# triangle seen from below is hit too (ptlab counts both faces), and a miss, outside an
# edge or parallel to the plane, has `t = inf`.

# %%
v0, e1, e2 = np.zeros(3), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
rays = {
    "hit from above": ([0.25, 0.5, 1], [0, 0, -1]),
    "behind the origin": ([0.25, 0.5, 1], [0, 0, 1]),
    "back face, from below": ([0.25, 0.5, -2], [0, 0, 1]),
    "outside the edge v1-v2": ([0.6, 0.6, 1], [0, 0, -1]),
    "parallel to the plane": ([0.25, 0.5, 1], [1, 0, 0]),
}
origins, dirs = (np.array(a, dtype=float) for a in zip(*rays.values(), strict=True))
t, u, v = ray_triangle(origins, dirs, v0, e1, e2)
for name, t_i, u_i, v_i in zip(rays, t, u, v, strict=True):
    shown = f"t = {t_i:5.2f}, u = {u_i:.2f}, v = {v_i:.2f}" if np.isfinite(t_i) else "t = inf"
    print(f"  {name:24} {shown}")


# %% [markdown]
# ## The mistake: u and v swapped
#
# `u` weighs `v1` (it goes with `e1`) and `v` weighs `v2`. Swapped, the hit is still found at
# the right `t`, but the renderer builds every hit point from `u` and `v` (more accurate
# than `o + t d`), so each point lands at its mirror image inside its triangle, and every
# shading point and shadow ray moves with it.


# %%
def swapped_uv_ray_triangle(origins, dirs, v0, e1, e2):
    """The classic mistake: the barycentrics swapped (v weighing v1, u weighing v2)."""
    t, u, v = ray_triangle(origins, dirs, v0, e1, e2)
    return t, v, u


# %% [markdown]
# ## The two pictures
#
# The NumPy BVH (`backend="numpy"`) is built and walked with the pieces it is given:
# `Pieces(bvh=BVHPieces(ray_triangle=...))` puts the wrong test in its leaves. Both renders
# run in this process (`workers=1`), since worker processes may not have this file's
# function. In the second picture the blocks' faces and the floor are lit as if they were
# elsewhere: triangle-shaped patches of light and shadow where the two triangles of a quad
# meet.

# %%
scene = ptlab.load_scene("cornell-box")
options = dict(spp=args.spp, res=args.res, workers=1, backend="numpy")
write_image(out / "ray-triangle.png", ptlab.render(scene, **options))
swapped_uv = Pieces(bvh=BVHPieces(ray_triangle=swapped_uv_ray_triangle))
write_image(out / "ray-triangle-wrong.png", ptlab.render(scene, **options, pieces=swapped_uv))
print(
    f"wrote {out / 'ray-triangle.png'} and {out / 'ray-triangle-wrong.png'} (the second with u and v swapped)"
)
show_pictures(out)
