"""A partial chapter-5 answer without the SAH: every split that divides its node costs
the same and the middle plane along x is taken, but the traversal piece is real work: the
near child is the one on the side the ray comes from. It deserves the traversal checks'
points, and none of those of the SAH (costs, best split, tree quality)."""

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
    going_down = dirs[np.arange(len(first_child)), axis] < 0
    near = first_child + going_down
    return near, first_child + 1 - going_down
