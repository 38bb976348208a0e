# %%
"""Chapter 2 tutorial: what Möller-Trumbore finds, and what a missing test does.

Traces a few rays at one triangle with ``ptlab.accel.triangle.ray_triangle`` and prints
their t, u, v (a hit, one behind the origin, one through the back face, one outside an
edge, one parallel), then path-traces the Cornell box through the NumPy BVH twice: with
the library's intersection, and with the chapter's typical mistake, u and v swapped: the
renderer builds each hit point from u and v, so the points land in the wrong places.

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


def swapped_uv_ray_triangle(origins, dirs, v0, e1, e2):
    """The classic mistake: the barycentrics swapped (v weighing v1, u weighing v2)."""
    t, u, v = ray_triangle(origins, dirs, v0, e1, e2)
    return t, v, u


# %%
def main() -> None:
    args, out = tutorial_options(__doc__, res=128, spp=16)

    # The triangle (0,0,0), (1,0,0), (0,1,0) in the plane z = 0, and five rays.
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

    scene = ptlab.load_scene("cornell-box")
    options = dict(spp=args.spp, res=args.res, workers=1, backend="numpy")
    write_image(out / "ray-triangle.png", ptlab.render(scene, **options))
    # The NumPy BVH is built and walked with the pieces it is given: here, the wrong test.
    swapped_uv = Pieces(bvh=BVHPieces(ray_triangle=swapped_uv_ray_triangle))
    write_image(out / "ray-triangle-wrong.png", ptlab.render(scene, **options, pieces=swapped_uv))
    print(
        f"wrote {out / 'ray-triangle.png'} and {out / 'ray-triangle-wrong.png'} "
        f"(the second with u and v swapped)"
    )
    show_pictures(out)


# %%
if __name__ == "__main__":
    main()
