# %%
"""Chapter 4 tutorial: the slab test, and the flat boxes a strict test misses.

Asks ``ptlab.accel.numpy_bvh.slab_test`` about a unit box and a flat box (the square z = 1)
and prints the answers, counts the flat boxes in the Cornell box's BVH, then renders the
Cornell box's normals with the NumPy BVH twice: with the library's pieces, and with the
lecture slide's strict ``t_enter < t_exit`` as the tree's slab test, which misses every
flat box: the walls inside them vanish.

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


def strict_slab_test(origins, inv_dirs, box_min, box_max, tmin, tmax):
    """The classic mistake: a hit only where t_enter < t_exit, strictly."""
    with np.errstate(invalid="ignore"):
        t0 = (box_min - origins) * inv_dirs
        t1 = (box_max - origins) * inv_dirs
    t_enter = np.fmax(np.fmax.reduce(np.minimum(t0, t1), axis=1), tmin)
    t_exit = np.fmin(np.fmin.reduce(np.maximum(t0, t1), axis=1), tmax)
    return t_enter < t_exit, t_enter


# %%
def main() -> None:
    args, out = tutorial_options(__doc__, res=256, spp=4)

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

    scene = ptlab.load_scene("cornell-box")
    bvh = build_bvh(scene.triangles)
    flat = np.any(bvh.box_min == bvh.box_max, axis=1)
    print(
        f"the Cornell box's BVH: {len(flat)} boxes, {flat.sum()} of them flat (leaves around "
        f"the axis-aligned walls)"
    )

    options = dict(spp=args.spp, res=args.res, integrator="normals", workers=1, backend="numpy")
    write_image(out / "bounding-boxes.png", ptlab.render(scene, **options))
    # The NumPy BVH is walked with the pieces it is given: here, the strict slab test.
    strict = Pieces(bvh=BVHPieces(slab_test=strict_slab_test))
    write_image(out / "bounding-boxes-wrong.png", ptlab.render(scene, **options, pieces=strict))
    print(
        f"wrote {out / 'bounding-boxes.png'} and {out / 'bounding-boxes-wrong.png'} (the second "
        f"with the strict test)"
    )
    show_pictures(out)


# %%
if __name__ == "__main__":
    main()
