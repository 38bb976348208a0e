"""A bounding volume hierarchy (BVH) over triangles, built and traversed in pure NumPy.

The teaching backend of ``ptlab.accel`` (the fast one is Embree). Three pieces, each
small enough to be an exercise:

* **Build** (``build_bvh``): top-down, with the surface area heuristic (SAH) evaluated
  on a few bins of the triangle centroids, as in pbrt-v4 section 7.3.2 and I. Wald,
  "On fast Construction of SAH-based Bounding Volume Hierarchies", IEEE RT 2007.
  The tree is built one level at a time: every node of a level is binned and split by
  the same handful of whole-array operations, so Python loops only over the levels.
  The SAH itself is two small functions: ``split_costs`` (the cost of every candidate
  split) and ``best_split`` (the cheapest one, or a leaf).
* **Slab test** (``slab_test``): ray against axis-aligned box, as in A. Williams et al.,
  "An Efficient and Robust Ray-Box Intersection Algorithm", JGT 2005, and pbrt-v4
  section 6.1.2.
* **Traversal** (``NumpyBVH.intersect`` / ``occluded``): all rays walk the tree at
  once. Each ray has its own stack of nodes still to visit; every step pops one node
  for every unfinished ray, tests it, and either tests the leaf's triangles
  (``ptlab.accel.triangle.ray_triangle``) or pushes the two children, near one on top
  (``child_order``).

A scene of at most ``SMALL_SCENE`` triangles (the Cornell box has 32) skips the walk
(unless the tree is given pieces other than the library's, which only the walk uses):
every ray is tested against every triangle, one triangle at a time for all the rays
(``NumpyBVH._test_every_triangle``). Each step is then mostly plain arithmetic on whole
arrays, with the triangle's data broadcast, where a walk gathers every ray's node, box
and triangles before it can compute anything, and gathering is the slow part of NumPy.

``slab_test``, ``ray_triangle``, ``split_costs``, ``best_split`` and ``child_order`` are the
tree's pieces (``BVHPieces``): a tree is built and walked with the pieces it is given,
the library's unless told otherwise (the course gives a student's: chapters 2, 4 and 5).

The tree is stored as flat arrays (one row per node), the layout a GPU or a C
implementation would use too: node ``i`` has bounds ``box_min[i], box_max[i]``; an
inner node has children ``child[i]`` and ``child[i] + 1`` and was split along
``axis[i]``; a leaf has ``count[i] > 0`` triangles starting at ``first[i]`` in the
reordered triangle arrays.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ptlab.accel.base import Hits
from ptlab.accel.triangle import ray_triangle
from ptlab.vectors import cross, dot

#: The most triangles for which testing all of them surely beats walking the tree (7.4x
#: faster on the Cornell box: docs/performance.md). A tree given pieces other than the
#: library's walks whatever its size (``NumpyBVH``).
SMALL_SCENE = 64

# pbrt-v4's gamma(3) for float32: the relative rounding error of t computed by the slab test.
_GAMMA3 = 3 * np.finfo(np.float32).eps / (1 - 3 * np.finfo(np.float32).eps)


def slab_test(
    origins: np.ndarray,
    inv_dirs: np.ndarray,
    box_min: np.ndarray,
    box_max: np.ndarray,
    tmin: float | np.ndarray,
    tmax: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Ray against axis-aligned box, one box per ray (Williams et al. 2005; pbrt-v4 6.1.2).

    A box is the intersection of three slabs ``box_min[k] <= x[k] <= box_max[k]``; the
    ray is inside slab k for ``t`` between the two plane crossings, and inside the box
    on the overlap of the three intervals and of ``[tmin, tmax]``.

    Args:
        origins: (N, 3) ray origins.
        inv_dirs: (N, 3) ``1 / dirs``; a zero direction component gives ``±inf``.
        box_min, box_max: (N, 3) box corners. A box may be flat (``box_min[k] ==
            box_max[k]``, e.g. around an axis-aligned quad).
        tmin, tmax: scalars or (N,) arrays, the part of the ray to consider.

    Returns:
        hit: (N,) bool, True where the ray overlaps the box within ``[tmin, tmax]``.
        t_enter: (N,) where the ray enters the box (or ``tmin`` if it starts inside).
    """
    # A zero direction component with the origin exactly on that slab's plane gives
    # 0 * inf = NaN. np.minimum/np.maximum spread that NaN to both ends of the axis's
    # interval, then np.fmax/np.fmin (which skip NaN) ignore the axis: a ray running
    # inside a slab's boundary plane counts as inside the slab, so flat boxes work.
    with np.errstate(invalid="ignore"):
        t0 = (box_min - origins) * inv_dirs
        t1 = (box_max - origins) * inv_dirs
    t_near = np.minimum(t0, t1)
    t_far = np.maximum(t0, t1)
    t_enter = np.fmax(np.fmax(np.fmax(t_near[:, 0], t_near[:, 1]), t_near[:, 2]), tmin)
    t_exit = np.fmin(np.fmin(t_far[:, 0], t_far[:, 1]), t_far[:, 2])
    # Widen by 2*gamma(3) (pbrt-v4) so rounding never culls a box whose face a hit lies on.
    t_exit = np.fmin(t_exit * (1 + 2 * _GAMMA3), tmax)
    # <=, not <: for a flat box and a ray perpendicular to it, t_enter == t_exit.
    return t_enter <= t_exit, t_enter


@dataclass
class FlatBVH:
    """A BVH as flat arrays; M nodes, node 0 is the root (see the module docstring).

    Attributes:
        box_min, box_max: (M, 3) node bounds.
        child: (M,) index of the first child of an inner node (the second is
            ``child + 1``); -1 for a leaf.
        axis: (M,) axis along which an inner node was split.
        first, count: (M,) a leaf's triangles are ``order[first:first + count]``;
            ``count`` is 0 for inner nodes.
        order: (T,) triangle indices in leaf order.
        depth: number of levels (a root-only tree has depth 1).
    """

    box_min: np.ndarray
    box_max: np.ndarray
    child: np.ndarray
    axis: np.ndarray
    first: np.ndarray
    count: np.ndarray
    order: np.ndarray
    depth: int


def _half_area(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Half the surface area of boxes (..., 3); 0 for empty boxes (lo = inf, hi = -inf)."""
    ext = np.maximum(hi - lo, 0)
    return ext[..., 0] * ext[..., 1] + ext[..., 1] * ext[..., 2] + ext[..., 2] * ext[..., 0]


def _bin_bounds(
    key: np.ndarray, lo: np.ndarray, hi: np.ndarray, shape: tuple[int, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """The bounds of the points in each bin: two new arrays of ``shape`` (..., 3 axes,
    3 coordinates), empty (``inf``, ``-inf``) but where the flat row ``key[p, a]`` (that of
    point p's bin along axis a) takes the minimum of the (P, 3) ``lo[p]`` and the maximum of
    the (P, 3) ``hi[p]`` that fall into it.

    key: (P, 3) row indices; lo, hi: (P, 3) C-contiguous. Works on flat 1-D indices because
    ``ufunc.at`` is about 5x faster there than when it updates rows; one axis at a time, so
    that the indices take a third of the memory.
    """
    bin_lo, bin_hi = np.full(shape, np.inf, lo.dtype), np.full(shape, -np.inf, hi.dtype)
    for axis in range(3):
        index = (key[:, axis, None] * 3 + np.arange(3)).ravel()
        np.minimum.at(bin_lo.reshape(-1), index, lo.ravel())
        np.maximum.at(bin_hi.reshape(-1), index, hi.ravel())
    return bin_lo, bin_hi


def _running(op: np.ufunc, a: np.ndarray) -> np.ndarray:
    """Running ``op`` (e.g. running minimum) along axis 0 of ``a``, as a new array.

    A loop over the few bins: about 10x faster than ``op.accumulate(a, axis=0)`` here.
    """
    out = a.copy()
    for i in range(1, len(out)):
        op(out[i - 1], out[i], out=out[i])
    return out


def split_costs(
    bin_count: np.ndarray,
    bin_lo: np.ndarray,
    bin_hi: np.ndarray,
    node_lo: np.ndarray,
    node_hi: np.ndarray,
    traversal_cost: float = 1.0,
) -> np.ndarray:
    """SAH cost of every candidate split of K nodes binned into B bins along each axis.

    Split plane i (0 <= i < B - 1) of an axis puts bins 0..i on the left and i+1..B-1 on
    the right; with N_L, N_R triangles in boxes of surface areas S_L, S_R, in a node of
    area S, it is expected to cost ``traversal_cost + (N_L S_L + N_R S_R) / S`` triangle
    tests (the SAH: pbrt-v4 7.3.2, Wald 2007). The sweep accumulates counts and bounds
    from each end, so every plane costs O(1).

    Args:
        bin_count: (B, K, 3) triangles in bin b of node k along axis a.
        bin_lo, bin_hi: (B, K, 3, 3) bounds of those triangles (last axis x, y, z);
            an empty bin has ``bin_lo = inf``, ``bin_hi = -inf``.
        node_lo, node_hi: (K, 3) bounds of each node.
        traversal_cost: cost of visiting a node, in units of one triangle test.

    Returns:
        (B - 1, K, 3) cost of plane i of node k along axis a; ``inf`` where one side
        would be empty (such a split would not divide the node).
    """
    left_n = np.cumsum(bin_count, axis=0)[:-1]
    right_n = bin_count.sum(axis=0) - left_n
    left_a = _half_area(_running(np.minimum, bin_lo)[:-1], _running(np.maximum, bin_hi)[:-1])
    right_a = _half_area(
        _running(np.minimum, bin_lo[::-1])[-2::-1], _running(np.maximum, bin_hi[::-1])[-2::-1]
    )
    # Half areas: the factor 2 cancels in the ratio. `tiny` keeps a degenerate node finite.
    node_a = np.maximum(_half_area(node_lo, node_hi), np.finfo(float).tiny)
    cost = traversal_cost + (left_n * left_a + right_n * right_a) / node_a[:, None]
    cost[(left_n == 0) | (right_n == 0)] = np.inf
    return cost


def best_split(
    cost: np.ndarray, size: np.ndarray, max_leaf_size: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cheapest split of each node, and whether the node should rather be a leaf.

    A leaf of N triangles costs N triangle tests; a node is made a leaf when it may be
    one (``N <= max_leaf_size``) and its cheapest split costs no less (pbrt-v4 7.3.2).
    Ties go to the lowest plane, then the lowest axis.

    Args:
        cost: (B - 1, K, 3) from ``split_costs``.
        size: (K,) triangles in each node.
        max_leaf_size: the most triangles a leaf may hold.

    Returns:
        split_bin: (K,) the plane (the last bin on the left side) of the cheapest split.
        split_axis: (K,) its axis, 0, 1 or 2.
        make_leaf: (K,) bool, True where the node becomes a leaf.
    """
    k = cost.shape[1]
    flat = cost.transpose(1, 0, 2).reshape(k, -1)  # (node, plane * 3 + axis)
    best = flat.argmin(axis=1)
    split_bin, split_axis = np.divmod(best, 3)
    make_leaf = (size <= max_leaf_size) & (flat[np.arange(k), best] >= size)
    return split_bin, split_axis, make_leaf


def build_bvh(
    triangles: np.ndarray,
    max_leaf_size: int = 4,
    max_bins: int = 12,
    traversal_cost: float = 1.0,
    pieces: BVHPieces | None = None,
) -> FlatBVH:
    """Top-down binned-SAH BVH (pbrt-v4 7.3.2; Wald 2007), one tree level at a time.

    For a node with N triangles and half surface area A, splitting into (N_L, A_L) and
    (N_R, A_R) is expected to cost ``traversal_cost + (N_L A_L + N_R A_R) / A`` triangle
    tests (the SAH), against N for making it a leaf. Candidate splits are the planes
    between ``max_bins`` equal bins of the node's centroid bounds, along each axis. Nodes
    with more than ``max_leaf_size`` triangles are always split; if all their centroids
    coincide, the split is at the median (any split is as good as another there).
    Time and memory grow in proportion to the triangles (docs/performance.md).

    Args:
        triangles: (T, 3, 3) vertex k of triangle i at ``triangles[i, k]``.
        max_leaf_size: the most triangles a leaf may hold.
        max_bins: number of SAH bins per axis (fewer on levels whose nodes are all smaller).
        traversal_cost: cost of visiting a node, in units of one triangle test.
        pieces: the SAH's ``split_costs`` and ``best_split`` (default: the library's).

    Returns:
        The tree as a ``FlatBVH``.
    """
    pieces = pieces or BVHPieces()
    tris = np.asarray(triangles, dtype=np.float64)
    if len(tris) == 0:
        raise ValueError("a BVH needs at least one triangle")
    n_tris = len(tris)
    order = np.empty(n_tris, np.intp)
    levels = []  # per level: the arrays of its nodes
    # The nodes of the level being built: where their triangles will sit in `order`.
    start, size = np.array([0]), np.array([n_tris])
    # Their triangles, node after node: index, bounds and centroid. (Kept in this order,
    # rather than gathered through `order` each level, they are read in sequence.)
    tri = np.arange(n_tris)
    tri_lo, tri_hi = tris.min(axis=1), tris.max(axis=1)
    centroid = 0.5 * (tri_lo + tri_hi)
    next_id = 1
    while start.size:
        k = start.size
        offset = np.cumsum(size) - size  # where each node's run begins in `tri`

        # Node bounds and centroid bounds: min/max over each node's run of triangles.
        box_lo = np.minimum.reduceat(tri_lo, offset)
        box_hi = np.maximum.reduceat(tri_hi, offset)
        c_lo = np.minimum.reduceat(centroid, offset)
        c_hi = np.maximum.reduceat(centroid, offset)

        # Bin every centroid along every axis; extent 0 puts everything in bin 0. Deep
        # levels hold only small nodes: fewer bins than triangles would be wasted work.
        n_bins = max(2, min(max_bins, size.max()))
        extent = c_hi - c_lo
        scale = np.divide(n_bins, extent, out=np.zeros_like(extent), where=extent > 0)
        bins = np.minimum(
            ((centroid - np.repeat(c_lo, size, axis=0)) * np.repeat(scale, size, axis=0)).astype(np.intp),
            n_bins - 1,
        )

        split_bin, split_axis, is_leaf, median = _choose_splits(
            bins, n_bins, tri_lo, tri_hi, box_lo, box_hi, size, offset, max_leaf_size, traversal_cost, pieces
        )

        # Partition each splitting node's run: left side first (stable sort by side).
        node = np.repeat(np.arange(k), size)  # node of each triangle of this level
        go_right = bins[np.arange(len(tri)), split_axis[node]] > split_bin[node]
        rank = np.arange(len(tri)) - offset[node]
        go_right = np.where(median[node], rank >= size[node] // 2, go_right)
        go_right &= ~is_leaf[node]
        sorted_ = np.argsort(2 * node + go_right, kind="stable")
        n_right = np.bincount(node, weights=go_right, minlength=k).astype(np.intp)
        # A leaf's triangles take their place in `order`; the others go on to the next level.
        in_leaf = is_leaf[node]
        order[(rank + start[node])[in_leaf]] = tri[in_leaf]
        sorted_ = sorted_[~in_leaf[sorted_]]
        tri, tri_lo, tri_hi, centroid = (a.take(sorted_, axis=0) for a in (tri, tri_lo, tri_hi, centroid))

        inner = np.flatnonzero(~is_leaf)
        child = np.full(k, -1)
        child[inner] = next_id + 2 * np.arange(inner.size)
        next_id += 2 * inner.size
        levels.append(
            (box_lo, box_hi, child, split_axis, np.where(is_leaf, start, 0), np.where(is_leaf, size, 0))
        )

        # The children, in id order: left and right of each splitting node.
        n_left = size[inner] - n_right[inner]
        start = np.stack([start[inner], start[inner] + n_left], axis=1).ravel()
        size = np.stack([n_left, n_right[inner]], axis=1).ravel()

    box_min, box_max, child, axis, first, count = (np.concatenate(a) for a in zip(*levels, strict=True))
    return FlatBVH(
        box_min=box_min,
        box_max=box_max,
        child=child,
        axis=axis,
        first=first,
        count=count,
        order=order,
        depth=len(levels),
    )


#: The most (bin, node) cells binned at once, per triangle of the level: a deep level has
#: more cells than triangles (many small nodes, each with all the bins), and binning its
#: nodes a few at a time keeps the bins' memory a small part of the build's.
CELLS_PER_TRIANGLE = 0.25


def _choose_splits(
    bins: np.ndarray,
    n_bins: int,
    tri_lo: np.ndarray,
    tri_hi: np.ndarray,
    box_lo: np.ndarray,
    box_hi: np.ndarray,
    size: np.ndarray,
    offset: np.ndarray,
    max_leaf_size: int,
    traversal_cost: float,
    pieces: BVHPieces,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The split of each of K nodes of a level (``split_costs``, ``best_split``), from its
    triangles' (P, 3) bins along each axis and (P, 3) bounds, node after node (node k's
    from ``offset[k]``, ``size[k]`` of them), and the nodes' (K, 3) bounds.

    Returns (K,) each: split_bin, split_axis, make_leaf (as ``best_split``), and median:
    True where the node must be split but no plane divides it (all its centroids coincide),
    to be split at its median instead (along axis 0).
    """
    k = len(size)
    split_bin, split_axis = np.empty(k, np.intp), np.empty(k, np.intp)
    is_leaf, median = np.empty(k, bool), np.empty(k, bool)
    group = max(1, int(CELLS_PER_TRIANGLE * len(bins)) // n_bins)  # nodes binned at once
    for first in range(0, k, group):
        nodes = slice(first, min(first + group, k))
        m = nodes.stop - first
        tris = slice(offset[first], offset[nodes.stop] if nodes.stop < k else len(bins))
        node = np.repeat(np.arange(m), size[nodes])
        # Per (bin, node, axis): triangle count and bounds of its triangles. Bins come
        # first so that the sweeps in split_costs run over contiguous (node, axis) slices.
        key = (bins[tris] * m + node[:, None]) * 3 + np.arange(3)  # (P, 3)
        bin_count = np.bincount(key.ravel(), minlength=n_bins * m * 3).reshape(n_bins, m, 3)
        # (float32: these only rank the candidate splits, and half the bytes build faster)
        bin_lo, bin_hi = _bin_bounds(
            key, tri_lo[tris].astype(np.float32), tri_hi[tris].astype(np.float32), (n_bins, m, 3, 3)
        )
        cost = pieces.split_costs(bin_count, bin_lo, bin_hi, box_lo[nodes], box_hi[nodes], traversal_cost)
        split_bin[nodes], split_axis[nodes], is_leaf[nodes] = pieces.best_split(
            cost, size[nodes], max_leaf_size
        )
        median[nodes] = ~is_leaf[nodes] & np.isinf(cost[split_bin[nodes], np.arange(m), split_axis[nodes]])
    split_axis[median] = 0
    return split_bin, split_axis, is_leaf, median


class NumpyBVH:
    """The ``Accelerator`` interface (``ptlab.accel.base``) on a NumPy SAH BVH.

    Rays may be float32 or float64; the traversal runs in float32, like Embree.

    Its speed per ray, and why its defaults are what they are, are in docs/performance.md
    ("The NumPy BVH on small scenes"): a triangle test costs more here than a node visit,
    so narrow leaves were fastest.

    Args:
        triangles: (T, 3, 3) array, vertex k of triangle i at ``triangles[i, k]``.
        max_leaf_size, traversal_cost: see ``build_bvh``.
        every_triangle: test every ray against every triangle instead of walking the tree;
            None (default) for ``SMALL_SCENE`` triangles or fewer (module docstring), with
            the library's pieces: a tree given others always walks the tree, through them.
        pieces: the functions it is built and walked with (default: the library's).
    """

    name = "numpy"

    def __init__(
        self,
        triangles: np.ndarray,
        max_leaf_size: int = 4,
        traversal_cost: float = 1.0,
        every_triangle: bool | None = None,
        pieces: BVHPieces | None = None,
    ):
        self.pieces = pieces = pieces or BVHPieces()
        tris = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
        self.bvh = bvh = build_bvh(
            tris, max_leaf_size=max_leaf_size, traversal_cost=traversal_cost, pieces=pieces
        )
        if every_triangle is None:
            every_triangle = len(tris) <= SMALL_SCENE and pieces == BVHPieces()
        self.every_triangle = bool(every_triangle)
        # For testing every triangle: each one's index, v0, edges and plane (normal . x =
        # offset), largest first: a ray that finds a near hit early has fewer planes ahead
        # of it to pass.
        self._triangles = []
        if self.every_triangle:
            tris32 = tris.astype(np.float32)
            normals = np.cross(tris32[:, 1] - tris32[:, 0], tris32[:, 2] - tris32[:, 0])
            for k in np.argsort(-np.linalg.norm(normals, axis=1), kind="stable"):
                v0, v1, v2 = tris32[k]
                self._triangles.append((int(k), v0, v1 - v0, v2 - v0, normals[k], float(normals[k] @ v0)))
        # Everything the traversal reads is float32, like the rays, and stored
        # component-major, (3, M): see `_traverse`.
        self._box_min = _component_major(bvh.box_min)
        self._box_max = _component_major(bvh.box_max)
        self._is_leaf = bvh.count > 0
        # Triangles in leaf order, as Möller-Trumbore wants them: v0 and two edges.
        tris = tris[bvh.order]
        self._v0 = _component_major(tris[:, 0])
        self._e1 = _component_major(tris[:, 1] - tris[:, 0])
        self._e2 = _component_major(tris[:, 2] - tris[:, 0])

    def intersect(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        tmin: float | np.ndarray = 0.0,
        tmax: float | np.ndarray = np.inf,
    ) -> Hits:
        """Closest hit with ``tmin < t < tmax`` for each ray; see ``ptlab.accel.base``."""
        return self._traverse(origins, dirs, tmin, tmax, any_hit=False)

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, tmax: float | np.ndarray) -> np.ndarray:
        """(N,) bool, True where a triangle lies at ``0 < t < tmax``; see ``base``."""
        return self._traverse(origins, dirs, 0.0, tmax, any_hit=True).hit

    def _traverse(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        tmin: float | np.ndarray,
        tmax: float | np.ndarray,
        any_hit: bool,
    ) -> Hits:
        """Walk the tree with all rays at once; ``any_hit`` stops a ray at its first hit.

        The state of the unfinished rays is kept in compacted arrays, column j for ray
        ``ray[j]``: each step pops one node per ray, and rays that are done leave the
        arrays, so the work of a step is proportional to the rays still busy. (Leaving
        costs a copy of all the state, so it waits until a quarter of the rays are done;
        until then a done ray stays, set up to miss every box. That made ``occluded``,
        whose rays finish at all different steps, about 20% faster.) Hits go straight
        into the (N,) result arrays, at index ``ray[j]``.

        Vectors are stored component-major, (3, n), and handed to ``slab_test`` and
        ``ray_triangle`` as (n, 3) views (``.T``): then each of their x, y, z columns
        is contiguous, which made the whole traversal about 20% faster.
        """
        o = _component_major(origins)
        d = _component_major(dirs)
        if o.shape != d.shape or o.shape[0] != 3:
            raise ValueError(f"origins and dirs must both be (N, 3), not {o.T.shape} and {d.T.shape}")
        n = o.shape[1]
        t_lo = np.broadcast_to(np.asarray(tmin, dtype=np.float32), n).copy()
        t_best = np.broadcast_to(np.asarray(tmax, dtype=np.float32), n).copy()
        hits = Hits(
            t=np.full(n, np.inf, np.float32),
            prim=np.full(n, -1, np.intp),
            u=np.zeros(n, np.float32),
            v=np.zeros(n, np.float32),
        )
        if self.every_triangle:
            self._test_every_triangle(o, d, t_lo, t_best, any_hit, hits)
            return hits
        with np.errstate(divide="ignore"):
            inv_d = 1 / d  # ±inf for zero components: see slab_test

        ray = np.arange(n)
        # stack[k, j]: the k-th node on ray j's stack; every ray starts at the root, 0.
        stack = np.zeros((self.bvh.depth + 1, n), np.int32)  # it never holds more
        sp = np.zeros(n, np.intp)  # stack pointer: where the top node is
        while ray.size:
            # Pop. A ray that is done pops junk (index clipped), but cannot hit it (below).
            col = np.arange(ray.size)
            node = stack.take(sp * ray.size + col, mode="clip")
            sp -= 1
            hit, _ = self.pieces.slab_test(
                o.T,
                inv_d.T,
                self._box_min.take(node, axis=1).T,
                self._box_max.take(node, axis=1).T,
                t_lo,
                t_best,
            )
            at_leaf = hit & self._is_leaf.take(node)
            j = np.flatnonzero(hit ^ at_leaf)  # rays at an inner node
            if j.size:
                self._push_children(j, node.take(j), d, stack, sp)
            j = np.flatnonzero(at_leaf)
            if j.size:
                found = self._intersect_leaf(j, node.take(j), o, d, t_lo, t_best, ray, hits)
                if any_hit:
                    sp[j.compress(found)] = -1
            done = sp < 0
            n_done = np.count_nonzero(done)
            if n_done > ray.size // 4:
                # Compact. compress, not a[:, keep]: several times faster.
                keep = ~done
                ray, o, d, inv_d, t_lo, t_best, stack, sp = (
                    a.compress(keep, axis=-1) for a in (ray, o, d, inv_d, t_lo, t_best, stack, sp)
                )
            elif n_done:
                # Too few done to be worth compacting: make them miss every box.
                k = np.flatnonzero(done)
                t_lo[k], t_best[k] = np.inf, -np.inf
        return hits

    def _test_every_triangle(
        self, o: np.ndarray, d: np.ndarray, t_lo: np.ndarray, t_best: np.ndarray, any_hit: bool, hits: Hits
    ) -> None:
        """``_traverse`` without the tree: every ray against every triangle, one triangle
        at a time, each ray keeping its nearest hit with ``t_lo < t < t_best`` (the first
        of equal ones, largest triangle first), written into ``hits``.

        The test is Möller-Trumbore's (``ptlab.accel.triangle``) rearranged around the
        triangle's normal n = e1 x e2, which is computed once: with det = -d . n and
        s = o - v0, Cramer's rule gives t = s . n / det first, a dozen operations on whole
        arrays that need nothing gathered (t is where the ray meets the triangle's plane).
        Only the rays that meet the plane between ``t_lo`` and their nearest hit so far
        (about a third, in the Cornell box) are gathered for the rest: with w = s x d,
        u = w . e2 / det and v = -w . e1 / det.
        """
        ox, oy, oz = o
        dx, dy, dz = d
        for k, v0, e1, e2, (nx, ny, nz), offset in self._triangles:
            with np.errstate(divide="ignore", invalid="ignore"):  # (rays in the plane)
                along = dx * nx + dy * ny + dz * nz  # d . n = -det
                t = (offset - (ox * nx + oy * ny + oz * nz)) / along
            rows = np.flatnonzero((t > t_lo) & (t < t_best))  # (never NaN or inf)
            if rows.size == 0:
                continue
            w = cross(o.take(rows, axis=1).T - v0, d.take(rows, axis=1).T)
            inv_det = -1 / along.take(rows)
            u, v = dot(w, e2) * inv_det, -dot(w, e1) * inv_det
            inside = (u >= 0) & (v >= 0) & (u + v <= 1)
            rows = rows.compress(inside)
            hits.prim[rows] = k
            if any_hit:
                t_best[rows] = -np.inf  # found (only hit or not matters): test no more
                continue
            t_best[rows] = hits.t[rows] = t.take(rows)
            hits.u[rows], hits.v[rows] = u.compress(inside), v.compress(inside)

    def _intersect_leaf(
        self,
        j: np.ndarray,
        node: np.ndarray,
        o: np.ndarray,
        d: np.ndarray,
        t_lo: np.ndarray,
        t_best: np.ndarray,
        ray: np.ndarray,
        hits: Hits,
    ) -> np.ndarray:
        """Test rays ``j`` against the triangles of their leaf ``node``, keeping hits
        with ``t_lo < t < t_best``: ``t_best`` is lowered in place, ``hits`` filled in
        at ``ray[j]``. Returns (len(j),) bool: which rays found a hit.

        Every (ray, triangle of its leaf) pair goes to ``ray_triangle`` in one batch, and
        each ray keeps its nearest hit (the first of equal ones, in the leaf's order).
        """
        first, count = self.bvh.first.take(node), self.bvh.count.take(node)
        start = np.cumsum(count) - count  # where each ray's pairs begin
        owner = np.repeat(np.arange(len(j)), count)  # the ray (index into j) of each pair
        tri = np.repeat(first - start, count) + np.arange(len(owner))
        rows = j.take(owner)
        t, u, v = self.pieces.ray_triangle(
            o.take(rows, axis=1).T,
            d.take(rows, axis=1).T,
            self._v0.take(tri, axis=1).T,
            self._e1.take(tri, axis=1).T,
            self._e2.take(tri, axis=1).T,
        )
        t = np.where((t > t_lo.take(rows)) & (t < t_best.take(rows)), t, np.float32(np.inf))
        nearest = np.minimum.reduceat(t, start)
        found = nearest < np.inf
        # The first pair of each ray that has its nearest t.
        best = np.flatnonzero(t == nearest.take(owner))
        best = best[np.unique(owner.take(best), return_index=True)[1]]
        best = best.compress(found.take(owner.take(best)))
        rows = rows.take(best)
        t_best[rows] = t.take(best)
        r = ray.take(rows)
        hits.t[r], hits.u[r], hits.v[r] = t.take(best), u.take(best), v.take(best)
        hits.prim[r] = self.bvh.order.take(tri.take(best))
        return found

    def _push_children(
        self, j: np.ndarray, node: np.ndarray, d: np.ndarray, stack: np.ndarray, sp: np.ndarray
    ) -> None:
        """Push the two children of inner ``node`` on the stacks of rays ``j``: the far
        one first, so the near one (``child_order``) is popped next and its hits can
        cull the far one."""
        n = d.shape[1]
        near, far = self.pieces.child_order(
            self.bvh.child.take(node), self.bvh.axis.take(node), d.take(j, axis=1).T
        )
        top = sp.take(j) * n + j
        stack.put(top + n, far)
        stack.put(top + 2 * n, near)
        sp[j] += 2


def child_order(first_child: np.ndarray, axis: np.ndarray, dirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which child of each inner node a ray meets first (pbrt-v4 7.3.5's ``dirIsNeg``).

    Child ``first_child`` holds the triangles on the low side of the split plane along
    ``axis``, child ``first_child + 1`` the high side. A ray going up that axis meets
    the low child first; a ray going down meets the high child first. Visiting the near
    child first finds near hits early, and they cull the far child's boxes.

    Args:
        first_child: (J,) index of the low child of each ray's node.
        axis: (J,) the node's split axis, 0, 1 or 2.
        dirs: (J, 3) the rays' directions.

    Returns:
        near, far: (J,) node indices, the child to visit first and the other one.
    """
    backwards = dirs[np.arange(len(axis)), axis] < 0  # meets the high child first
    return first_child + backwards, first_child + ~backwards


@dataclass(frozen=True)
class BVHPieces:
    """The functions a tree is built and walked with: the library's by default, any of
    them a student's in the course's chapters (each with the signature of the library's)."""

    ray_triangle: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]] = ray_triangle
    slab_test: Callable[..., tuple[np.ndarray, np.ndarray]] = slab_test
    split_costs: Callable[..., np.ndarray] = split_costs
    best_split: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]] = best_split
    child_order: Callable[..., tuple[np.ndarray, np.ndarray]] = child_order


def _component_major(vectors: np.ndarray) -> np.ndarray:
    """(3, N) float32 C-contiguous copy of (N, 3) ``vectors``."""
    return np.ascontiguousarray(np.asarray(vectors, dtype=np.float32).T)
