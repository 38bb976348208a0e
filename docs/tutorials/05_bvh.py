"""Chapter 5 tutorial: what the SAH and front-to-back traversal save.

Builds the NumPy BVH over the Cornell box with a ball on the short block, twice: with the
library's pieces (SAH splits, near child first) and with the homework's habits (split at
the median of the longest axis, low child first). Both find the same hits; the script
prints each tree's SAH cost and the boxes a camera ray enters on average, and writes a
heat map per tree of the boxes each camera ray enters (same colour scale: brighter is
more work).

    python docs/tutorials/05_bvh.py                  # writes bvh.png, bvh-wrong.png
    python docs/tutorials/05_bvh.py --res 64 --out /tmp/t
"""

from __future__ import annotations

import numpy as np
import trimesh

import ptlab
import ptlab.accel.numpy_bvh as numpy_bvh
from ptlab.camera import generate_rays
from ptlab.exercises.chapters.ch05_bvh import sah_cost
from ptlab.exercises.plug import plugged
from ptlab.exercises.tutorial import tutorial_options

#: A ray's tag, carried in its tmin: ray i starts at t = i * TAG (see ``boxes_entered``).
TAG = 1e-6


def median_split_costs(bin_count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost=1.0):
    """The homework's build as a cost: equal counts on both sides, along the longest axis."""
    left_n = np.cumsum(bin_count, axis=0)[:-1]
    right_n = bin_count.sum(axis=0) - left_n
    cost = np.abs(left_n - right_n).astype(float)
    longest = np.argmax(node_hi - node_lo, axis=1)
    cost[:, np.arange(3)[None, :] != longest[:, None]] = np.inf
    cost[(left_n == 0) | (right_n == 0)] = np.inf
    return cost


def low_child_first(first_child, axis, dirs):
    """The homework's traversal order: always the left (low) child first."""
    return first_child, first_child + 1


def boxes_entered(bvh: numpy_bvh.NumpyBVH, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """(N,) the boxes each ray enters on its way through ``bvh`` to its closest hit.

    ``slab_test`` is not told which rays it tests, so every ray carries a tag in its tmin
    (ray i ignores hits before t = i * TAG: nothing here is that close to the camera) and
    a counting slab test reads the tags back.
    """
    count = np.zeros(len(origins), np.intp)

    def counting_slab_test(o, inv_d, box_min, box_max, tmin, tmax):
        hit, t_enter = slab_test(o, inv_d, box_min, box_max, tmin, tmax)
        np.add.at(count, np.rint(tmin[hit] / TAG).astype(np.intp), 1)
        return hit, t_enter

    slab_test = numpy_bvh.slab_test
    tag = (np.arange(len(origins)) * TAG).astype(np.float32)
    with plugged(numpy_bvh, slab_test=counting_slab_test):
        bvh.intersect(origins, dirs, tmin=tag)
    return count


def main() -> None:
    args, out = tutorial_options(__doc__, res=128, spp=1, spp_help="camera rays per pixel")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = ptlab.load_scene("cornell-box")
    ball = trimesh.creation.icosphere(subdivisions=3, radius=60)
    ball.apply_translation([185, 225, 170])
    triangles = np.concatenate([scene.triangles, ball.vertices[ball.faces]])
    print(f"{len(triangles)} triangles: the Cornell box and a ball of {len(ball.faces)}")

    res, spp = args.res, args.spp
    pixel = np.repeat(np.arange(res * res), spp)
    u = np.random.default_rng(0).random((len(pixel), 2), dtype=np.float32)
    origins, dirs = generate_rays(scene.camera, res, res, pixel % res, pixel // res, u)

    counts = {}
    for name, pieces in [("bvh", {}), ("bvh-wrong", dict(split_costs=median_split_costs,
                                                         child_order=low_child_first))]:
        with plugged(numpy_bvh, **pieces):
            bvh = numpy_bvh.NumpyBVH(triangles)
            entered = boxes_entered(bvh, origins, dirs)
        counts[name] = np.bincount(pixel, weights=entered) / spp
        label = "SAH, near child first" if name == "bvh" else "median split, low child first"
        print(f"{label:30} SAH cost {sah_cost(bvh.bvh):5.1f}, {bvh.bvh.depth} levels, "
              f"{entered.mean():5.1f} boxes entered per camera ray")
    top = max(np.percentile(c, 99) for c in counts.values())   # a few grazing rays enter many more
    for name, per_pixel in counts.items():
        plt.imsave(out / f"{name}.png", per_pixel.reshape(res, res), cmap="inferno", vmin=0,
                   vmax=top)
    print(f"wrote {out / 'bvh.png'} and {out / 'bvh-wrong.png'}: boxes entered per camera ray, "
          f"inferno colours from black (0) to pale yellow ({top:.0f} or more)")


if __name__ == "__main__":
    main()
