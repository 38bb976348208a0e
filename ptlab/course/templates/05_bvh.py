"""Chapter 5: the BVH, built with the SAH and traversed front to back.

The chapter's page: ``ptlab exercise docs 5`` (中文: ``--zh``).

ptlab's NumPy BVH (``ptlab.accel.numpy_bvh``) builds its tree top-down, one level at a
time: it sorts the triangles of every node of the level into B bins by their centroids,
along each axis, then asks your two functions which split to make. Its traversal asks
your third function which child each ray should visit first. Write

* ``split_costs``: the SAH cost of every candidate split of every node of a level;
* ``best_split``: the cheapest one for each node, or whether it should be a leaf;
* ``child_order``: the near and the far child of each ray's node.

Check your work with

    ptlab exercise check 5 05_bvh.py

Everything is whole arrays (K nodes at once, J rays at once): use NumPy operations along
the axes, never a Python loop over nodes or rays. (A loop over the few bins is fine.)
"""

import numpy as np


def split_costs(bin_count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost=1.0):
    """The SAH cost of every candidate split of K nodes, from their binned triangles.

    Split plane i (0 <= i < B - 1) of an axis puts bins 0..i on the left and bins
    i+1..B-1 on the right. With N_L and N_R triangles on the two sides, whose bounding
    boxes have surface areas S_L and S_R, in a node of surface area S, the surface area
    heuristic estimates the cost of a ray through the node as

        cost = traversal_cost + (N_L * S_L + N_R * S_R) / S

    triangle tests (S_L / S is the chance that a ray through the node hits the left box;
    pbrt-v4 7.3.2, Wald 2007).

    Args:
        bin_count: (B, K, 3) int, the number of triangles of node k whose centroid falls
            in bin b along axis a (a = 0, 1, 2 for x, y, z).
        bin_lo, bin_hi: (B, K, 3, 3) float32, the bounding box of those triangles: the
            last axis is x, y, z of the box's corner. An empty bin has
            ``bin_lo = +inf`` and ``bin_hi = -inf``.
        node_lo, node_hi: (K, 3) the bounding box of each node.
        traversal_cost: the cost of visiting a node, in units of one triangle test.

    Returns:
        (B - 1, K, 3) float: the cost of split plane i of node k along axis a; ``np.inf``
        where one side would hold no triangle (that split does not divide the node).

    Hints:
        * Surface area of boxes (..., 3): with ``e = hi - lo``,
          ``2 * (e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0])``.
        * ``np.cumsum(bin_count, axis=0)`` counts bins 0..i. The left box of plane i is
          the union of the boxes of bins 0..i: ``np.minimum.accumulate(bin_lo, axis=0)``
          and ``np.maximum.accumulate(bin_hi, axis=0)``. For the right side, do the same
          on the bins reversed (``[::-1]``), then reverse back.
        * An empty side's box is (inf, -inf): its "area" is inf, and 0 * inf is NaN. Set
          the cost of every split with an empty side to inf yourself, at the end.
    """
    raise NotImplementedError("split_costs")


def best_split(cost, size, max_leaf_size):
    """The cheapest split of each node, and whether the node should rather be a leaf.

    A leaf of N triangles costs N triangle tests. A node becomes a leaf when it may be
    one (N <= max_leaf_size) and its cheapest split costs no less than N; a node with
    more triangles is always split.

    Args:
        cost: (B - 1, K, 3) from ``split_costs``.
        size: (K,) int, the number of triangles in each node.
        max_leaf_size: int, the most triangles a leaf may hold.

    Returns:
        split_bin: (K,) int, the plane i of the cheapest split of each node (the last bin
            on its left side).
        split_axis: (K,) int, its axis: 0, 1 or 2.
        make_leaf: (K,) bool, True where the node becomes a leaf.

    Hints:
        * The cheapest split is the minimum over planes *and* axes together. Put the
          node axis first (``cost.transpose(1, 0, 2)``), flatten the other two
          (``.reshape(K, -1)``), take ``argmin(axis=1)``, and turn the flat index back
          into (plane, axis) with ``np.divmod(index, 3)``.
        * A node whose every cost is inf (all its centroids in one bin) cannot be divided
          by any plane: with N <= max_leaf_size it becomes a leaf by the rule above (inf
          >= N); otherwise the library splits it in the middle of its list itself.
    """
    raise NotImplementedError("best_split")


def child_order(first_child, axis, dirs):
    """Which child of its node each ray meets first.

    An inner node was split along ``axis``: child ``first_child`` holds the low side (the
    smaller coordinates), child ``first_child + 1`` the high side. Visiting the child the
    ray meets first lets its hits cull the other child's boxes (the slab test skips boxes
    farther than the best hit so far).

    Args:
        first_child: (J,) int, the index of the low child of each ray's node.
        axis: (J,) int, that node's split axis: 0, 1 or 2.
        dirs: (J, 3) float32, the rays' directions.

    Returns:
        near, far: (J,) int, the child to visit first and the other one.

    Hints:
        * ``dirs[np.arange(J), axis]`` picks, for each ray, its direction's component
          along its node's split axis.
        * A ray going up the axis (component > 0) meets the low child first; a ray going
          down meets the high child first.
    """
    raise NotImplementedError("child_order")
