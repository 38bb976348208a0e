"""A typical wrong chapter-5 answer: the leaf rule "a node of at most max_leaf_size
triangles is a leaf", whatever its costs. The SAH costs and the traversal order are the
library's (called from this file's own functions: a student would have written them out);
the cheapest split is found right. The tree finds the right hits, but keeps
leaves of up to four triangles where one cheap split would have separated them: its SAH
cost is higher. The cause is best_split's leaf rule, not the costs."""

import numpy as np

from ptlab.accel import numpy_bvh

EXPECTED_FAILURES = ("best split", "tree quality")
#: Tree quality names best_split's leaf rule, not the costs' areas.
EXPECTED_HINTS = {"tree quality": ("your best_split builds a tree", "leaf only when its cheapest split",
                                   "see 'best split'")}
MISLEADING_HINTS = {"tree quality": ("surface area", "median")}

__all__ = ["split_costs", "best_split", "child_order"]


def split_costs(*args, **kwargs):
    costs = numpy_bvh.split_costs(*args, **kwargs)
    return costs


def child_order(*args):
    near, far = numpy_bvh.child_order(*args)
    return near, far


def best_split(cost, size, max_leaf_size):
    k = cost.shape[1]
    flat = cost.transpose(1, 0, 2).reshape(k, -1)
    best = flat.argmin(axis=1)
    split_bin, split_axis = np.divmod(best, 3)
    make_leaf = size <= max_leaf_size           # (the bug: the cost of splitting never asked)
    return split_bin, split_axis, make_leaf
