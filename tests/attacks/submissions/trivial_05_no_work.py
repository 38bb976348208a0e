"""A trivial chapter-5 answer: every split that divides its node costs the same, the
middle plane along x is taken, and the low child is always visited first. Any such
choice still builds a valid tree (the library partitions the triangles), so the BVH finds
every closest hit and the picture is right: no SAH, no front-to-back order."""

import numpy as np


def split_costs(bin_count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost=1.0):
    left = np.cumsum(bin_count, axis=0)[:-1]
    empty = (left == 0) | (left == bin_count.sum(axis=0))
    return np.where(empty, np.inf, 1.0)


def best_split(cost, size, max_leaf_size):
    k = len(size)
    split_bin = np.full(k, cost.shape[0] // 2, dtype=np.intp)
    split_axis = np.zeros(k, dtype=np.intp)
    return split_bin, split_axis, size <= 1


def child_order(first_child, axis, dirs):
    return first_child, first_child + 1
