"""A typical wrong chapter-5 answer: the homework's own BVH. It splits every node at the
median of its longest axis (equal counts on both sides, areas ignored) down to single
triangles, and always visits the low child first, whichever way the ray goes. All of it
gives the right hits, as any valid split and child order do (so the closest hits and the
render earn nothing without a right child order): the tree is worse by the SAH's measure,
and rays going down an axis test many more boxes."""

import numpy as np

EXPECTED_FAILURES = ("SAH costs", "empty sides", "best split", "near child first", "closest hits",
                     "tree quality", "traversal order", "render")


def split_costs(bin_count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost=1.0):
    left_n = np.cumsum(bin_count, axis=0)[:-1]
    right_n = bin_count.sum(axis=0) - left_n
    cost = np.abs(left_n - right_n).astype(float)            # the median: equal counts
    longest = np.argmax(node_hi - node_lo, axis=1)
    cost[:, np.arange(3)[None, :] != longest[:, None]] = np.inf
    cost[(left_n == 0) | (right_n == 0)] = np.inf
    return cost


def best_split(cost, size, max_leaf_size):
    k = cost.shape[1]
    flat = cost.transpose(1, 0, 2).reshape(k, -1)
    best = flat.argmin(axis=1)
    split_bin, split_axis = np.divmod(best, 3)
    return split_bin, split_axis, size <= 1


def child_order(first_child, axis, dirs):
    return first_child, first_child + 1
