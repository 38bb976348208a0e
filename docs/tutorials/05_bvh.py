# %% [markdown]
# # Chapter 5 tutorial: the BVH of Homework 6's bunny, its boxes, and what the SAH saves
#
# A bounding volume hierarchy is a binary tree of boxes: the root's box holds the whole
# scene, each inner node's two children split its triangles in two groups, and a ray that
# misses a node's box skips everything below it. How a node is split, and which child a ray
# visits first, decide how many boxes a ray enters on its way to its closest hit; they never
# change which hit it finds. Chapter 5's exercise is those two choices: the split costs of
# the surface area heuristic (SAH), the best split, and the order of the children (the
# chapter's page: `ptlab exercise docs 5`).
#
# This tutorial builds the NumPy BVH over the Stanford bunny of `games101-hw6` (4968
# triangles) twice, with the library's pieces (SAH splits, near child first) and with the
# homework's habits (split at the median of the longest axis, low child first), counts the
# boxes each camera ray enters in each tree, and draws the SAH tree's first levels over the
# bunny.

# %%
"""Chapter 5 tutorial: the BVH of Homework 6's bunny, its boxes, and what the SAH saves.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/05_bvh.py                  # writes bvh-boxes.png, bvh.png, bvh-wrong.png
    python docs/tutorials/05_bvh.py --res 64 --out /tmp/t
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from matplotlib.figure import Figure
from matplotlib.image import imsave

import ptlab
from ptlab.accel.numpy_bvh import BVHPieces, FlatBVH, NumpyBVH
from ptlab.camera import generate_rays
from ptlab.course.chapters.ch05_bvh import sah_cost
from ptlab.course.tutorial import show_pictures, tutorial_options

args, out = tutorial_options(__doc__, res=240, spp=1, spp_help="camera rays per pixel")


# %% [markdown]
# ## The homework's habits, as pieces of the build and the walk
#
# The build asks `split_costs` what each candidate split (a plane between bins of
# triangles, along each axis) would cost, and takes the cheapest. The SAH's cost is what a
# random ray would pay: `c_trav + (N_L S_L + N_R S_R) / S`, the triangles on each side
# weighted by the chance `S_L / S` that a ray through the node passes through that side's
# box. The homework instead cuts at the median of the longest axis: as a cost, zero where
# the two sides hold equally many triangles, and infinite on the other axes. The walk asks
# `child_order` which child to visit first: the library takes the near one, on the side the
# ray comes from, so that its hits let the far child's box be culled; the homework always
# takes the low (left) one.


# %%
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


# %% [markdown]
# ## Counting the boxes a ray enters
#
# The tree's slab test (chapter 4) is one of its pieces too, so a slab test that counts
# the boxes it finds entered, and passes on the real test's answer, measures the work
# without changing it. It is not told which rays it is testing, so every ray carries a tag
# in its `tmin`: ray i ignores hits before `t = i * TAG`, far too close to the camera to
# matter here.

# %%
#: A ray's tag, carried in its tmin: ray i starts at t = i * TAG (see ``boxes_entered``).
TAG = 1e-7


def boxes_entered(
    triangles: np.ndarray, pieces: BVHPieces, origins: np.ndarray, dirs: np.ndarray
) -> tuple[NumpyBVH, np.ndarray]:
    """The NumPy BVH over ``triangles`` built and walked with ``pieces``, and (N,) the boxes
    each ray enters on its way through it to its closest hit.

    The tree's slab test is that of ``pieces``, counting the boxes it finds entered. It is
    not told which rays it tests, so every ray carries a tag in its tmin (ray i ignores hits
    before t = i * TAG: nothing here is that close to the camera) that it reads back.
    """
    count = np.zeros(len(origins), np.intp)

    def counting_slab_test(o, inv_d, box_min, box_max, tmin, tmax):
        hit, t_enter = pieces.slab_test(o, inv_d, box_min, box_max, tmin, tmax)
        np.add.at(count, np.rint(tmin[hit] / TAG).astype(np.intp), 1)
        return hit, t_enter

    bvh = NumpyBVH(triangles, pieces=replace(pieces, slab_test=counting_slab_test))
    tag = (np.arange(len(origins)) * TAG).astype(np.float32)
    bvh.intersect(origins, dirs, tmin=tag)
    return bvh, count


# %% [markdown]
# ## Two trees over the bunny
#
# The camera rays are the homework's view of the bunny, at its 4:3 shape, `--spp` rays per
# pixel at random points inside it. Each tree is built and walked with its pieces; both find
# the same hits. The SAH cost of a whole tree (`sah_cost`) is the triangle tests and node
# visits a random ray would pay; the boxes entered are what these camera rays paid.

# %%
scene = ptlab.load_scene("games101-hw6")
print(f"{scene.triangle_count} triangles: the Stanford bunny of Homework 6, scaled by 60")

height, spp = args.res, args.spp
width = height * 4 // 3  # the homework's 1280 x 960 shape
pixel = np.repeat(np.arange(width * height), spp)
u = np.random.default_rng(0).random((len(pixel), 2), dtype=np.float32)
origins, dirs = generate_rays(scene.camera, width, height, pixel % width, pixel // width, u)

counts, trees = {}, {}
for name, pieces in [
    ("bvh", BVHPieces()),
    ("bvh-wrong", BVHPieces(split_costs=median_split_costs, child_order=low_child_first)),
]:
    bvh, entered = boxes_entered(scene.triangles, pieces, origins, dirs)
    trees[name] = bvh.bvh
    counts[name] = np.bincount(pixel, weights=entered, minlength=width * height) / spp
    label = "SAH, near child first" if name == "bvh" else "median split, low child first"
    print(
        f"{label:30} SAH cost {sah_cost(bvh.bvh):5.1f}, {bvh.bvh.depth} levels, "
        f"{entered.mean():5.1f} boxes entered per camera ray, "
        f"{entered[entered > 0].mean():5.1f} per ray that enters the root's box"
    )

# %% [markdown]
# Each tree's count per pixel becomes a heat map, on one colour scale for both (matplotlib's
# inferno, from black for none to pale yellow for the most): brighter is more work. The top
# of the scale is the 99th percentile, since a few grazing rays enter many more boxes.

# %%
top = max(np.percentile(c, 99) for c in counts.values())
for name, per_pixel in counts.items():
    imsave(out / f"{name}.png", per_pixel.reshape(height, width), cmap="inferno", vmin=0, vmax=top)
print(
    f"wrote {out / 'bvh.png'} and {out / 'bvh-wrong.png'}: boxes entered per camera ray, "
    f"inferno colours from black (0) to pale yellow ({top:.0f} or more)"
)


# %% [markdown]
# ## The SAH tree's boxes
#
# To draw a box over the image, its 12 edges are projected through the pinhole camera of
# chapter 1 (a point's offset from the eye, along `right` and `up`, divided by its distance
# along `forward` and by the image plane's half-size). A node's level is one more than its
# parent's; in the flattened tree the two children of node k sit at `child[k]` and
# `child[k] + 1`, after their parent.

# %%
#: The tree levels whose boxes ``bvh-boxes.png`` draws (the root is level 0), one colour each.
LEVELS = (1, 2, 3, 4)


def node_levels(tree: FlatBVH) -> np.ndarray:
    """(M,) the level of each node (the root's is 0): children come after their parent."""
    level = np.zeros(len(tree.child), np.intp)
    for node in np.flatnonzero(tree.child >= 0):
        level[tree.child[node] : tree.child[node] + 2] = level[node] + 1
    return level


def box_edges(box_min: np.ndarray, box_max: np.ndarray) -> np.ndarray:
    """(12, 2, 3) the edges of a box: pairs of corners that differ in one coordinate."""
    corners = np.array([[(box_min, box_max)[(k >> a) & 1][a] for a in range(3)] for k in range(8)])
    return np.array([(corners[k], corners[k | 1 << a]) for k in range(8) for a in range(3) if not k & 1 << a])


def project(camera, width: int, height: int, points: np.ndarray) -> np.ndarray:
    """(..., 2) the pixel coordinates (x right, y down) where ``points`` (..., 3) appear."""
    d = points - camera.position
    z = d @ camera.forward
    scale = math.tan(math.radians(camera.fov_y) / 2)
    x = (d @ camera.right) / (z * scale * width / height)
    y = (d @ camera.up) / (z * scale)
    return np.stack([(x + 1) / 2 * width, (1 - y) / 2 * height], axis=-1)


# %% [markdown]
# Drawn over the bunny's normals, the SAH tree's first levels split it where its triangles
# are, into boxes that overlap little and hug the ears, the head and the body.

# %%
normals = ptlab.render(scene, spp=4, res=(width, height), integrator="normals", workers=1)
tree, level = trees["bvh"], node_levels(trees["bvh"])
figure = Figure(figsize=(width / 100, height / 100), dpi=100)  # (drawn into a file: no window)
axes = figure.add_axes([0, 0, 1, 1])
axes.imshow(np.clip(normals, 0, 1))
for k, colour in zip(LEVELS, ("white", "yellow", "orange", "red"), strict=True):
    for node in np.flatnonzero(level == k):
        for edge in project(scene.camera, width, height, box_edges(tree.box_min[node], tree.box_max[node])):
            axes.plot(edge[:, 0], edge[:, 1], color=colour, linewidth=0.6)
axes.set_xlim(0, width)
axes.set_ylim(height, 0)
axes.axis("off")
figure.savefig(out / "bvh-boxes.png")
print(
    f"wrote {out / 'bvh-boxes.png'}: the boxes of levels {', '.join(map(str, LEVELS))} "
    f"(white, yellow, orange, red: {', '.join(str(int((level == k).sum())) for k in LEVELS)} "
    f"boxes) over the bunny's normals"
)
show_pictures(out)
