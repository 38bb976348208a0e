"""Chapter 5's checks: the BVH, built with the SAH and traversed front to back.

The student writes three pieces of ``ptlab.accel.numpy_bvh``: ``split_costs`` (the SAH
cost of every candidate split of a node, from binned counts and bounds), ``best_split``
(the cheapest split, or a leaf) and ``child_order`` (which child a ray meets first).
Known answers come from the SAH's definition (pbrt-v4 7.3.2; Wald 2007), computed here
plane by plane with plain loops. Then the pieces go into the NumPy BVH: its closest hits
and shadow-ray answers must equal brute force (every ray against every triangle); the
tree's SAH cost must be close to the library's (a median split or a cost without the
areas builds a correct tree that is measurably worse); front-to-back traversal must test
as few boxes as the library's; and the Cornell box must look the same. The meshes' random
parts, the rays, the nodes and the directions come from the grading seed
(``ptlab.course.chapter.grading_rng``), new for each grading.
"""

from __future__ import annotations

import copy

import numpy as np

from ptlab.accel.numpy_bvh import BVHPieces, NumpyBVH, build_bvh
from ptlab.course.chapter import Chapter, ChapterCheck, ChapterRender, CheckFailed, grading_rng, require
from ptlab.course.messages import aside, check_name, text
from ptlab.rendering.pieces import Pieces

#: Tree quality: the student's tree may cost this much more than the library's (ties
#: between equally good splits broken another way change the tree a little; on the test
#: mesh a median split costs 46% more, a cost without the areas 128% more).
SAH_TOLERANCE = 0.03
#: Traversal order: the student's traversal may test this many more boxes than the
#: library's on the row of balls (visiting the far child first enters about 6 times more).
VISIT_TOLERANCE = 0.05
PIECES = ("split_costs", "best_split", "child_order")


# -- meshes and rays ------------------------------------------------------------------------


def _quad(corner, edge1, edge2) -> np.ndarray:
    """(2, 3, 3) triangles of the parallelogram corner + a edge1 + b edge2."""
    c, e1, e2 = (np.asarray(a, dtype=np.float64) for a in (corner, edge1, edge2))
    return np.array([[c, c + e1, c + e1 + e2], [c, c + e1 + e2, c + e2]])


def _block(lo, hi) -> np.ndarray:
    """(12, 3, 3) triangles of the axis-aligned box [lo, hi]."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    size = hi - lo
    x, y, z = np.diag(size)
    return np.concatenate(
        [
            _quad(lo, y, x),
            _quad(lo, x, z),
            _quad(lo, z, y),
            _quad(hi, -x, -y),
            _quad(hi, -z, -x),
            _quad(hi, -y, -z),
        ]
    )


def _ball(centre, radius: float, rings: int = 8, segments: int = 12) -> np.ndarray:
    """(2 * rings * segments, 3, 3) triangles of a UV sphere (some degenerate at the poles)."""
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, segments + 1)
    theta, phi = np.meshgrid(theta, phi, indexing="ij")
    p = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)], -1)
    p = np.asarray(centre, dtype=np.float64) + radius * p
    a, b, c, d = p[:-1, :-1], p[:-1, 1:], p[1:, 1:], p[1:, :-1]
    return np.concatenate(
        [np.stack([a, b, c], -2).reshape(-1, 3, 3), np.stack([a, c, d], -2).reshape(-1, 3, 3)]
    )


def uneven_mesh() -> np.ndarray:
    """(756, 3, 3): a room 0..556 with two blocks, a ball in one corner and a cloud of 400
    small triangles in another: big and small triangles unevenly spread, where the SAH's
    areas matter."""
    rng = grading_rng(8)
    cloud = rng.uniform(380, 520, (400, 1, 3)) + rng.normal(scale=6, size=(400, 3, 3))
    return np.concatenate(
        [
            _block([0, 0, 0], [556, 556, 556]),
            _block([130, 0, 65], [295, 165, 230]),
            _block([265, 0, 295], [430, 330, 460]),
            _ball([110, 90, 440], 80, rings=10, segments=16),
            cloud,
        ]
    )


def row_of_balls() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eight balls in a row along x, and 4000 rays along the row from both ends:
    (T, 3, 3) triangles, (N, 3) origins, (N, 3) directions."""
    tris = np.concatenate([_ball([3.0 * i, 0, 0], 1.0) for i in range(8)])
    rng = grading_rng(9)
    n = 4000
    forward = np.arange(n) % 2 == 0
    origins = np.column_stack([np.where(forward, -5.0, 26.0), rng.uniform(-0.8, 0.8, (n, 2))])
    dirs = np.column_stack([np.where(forward, 1.0, -1.0), rng.normal(scale=0.05, size=(n, 2))])
    return tris, origins.astype(np.float32), dirs.astype(np.float32)


def _random_rays(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) float32 origins (most in the room, some outside) and random directions."""
    rng = grading_rng(10)
    origins = np.where(rng.random((n, 1)) < 0.8, rng.uniform(1, 555, (n, 3)), rng.uniform(-300, 856, (n, 3)))
    return origins.astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32)


def _brute_force(tris: np.ndarray, origins: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Every ray against every triangle, in float32 like the BVH: (N, T) t, inf for misses
    and for t <= 0. In blocks of 256 rays, to keep the (256, T, 3) temporaries small."""
    from ptlab.accel.triangle import ray_triangle

    v0 = tris[:, 0].astype(np.float32)
    e1 = (tris[:, 1] - tris[:, 0]).astype(np.float32)
    e2 = (tris[:, 2] - tris[:, 0]).astype(np.float32)
    blocks = []
    for start in range(0, len(origins), 256):
        block = slice(start, start + 256)
        t, _, _ = ray_triangle(origins[block, None], dirs[block, None], v0, e1, e2)
        t[~(t > 0)] = np.inf
        blocks.append(t)
    return np.concatenate(blocks)


def sah_cost(bvh, traversal_cost: float = 1.0) -> float:
    """The SAH cost of a built tree (a ``FlatBVH``): the expected number of triangle tests
    (a node visit costing ``traversal_cost``) for a random ray through the root's box."""
    extent = np.maximum(bvh.box_max - bvh.box_min, 0)
    area = extent[:, 0] * extent[:, 1] + extent[:, 1] * extent[:, 2] + extent[:, 2] * extent[:, 0]
    leaf = bvh.count > 0
    return float((traversal_cost * area[~leaf].sum() + (bvh.count * area)[leaf].sum()) / area[0])


# -- the student's pieces, checked as the library calls them ---------------------------------


def _pieces(module, *names: str) -> dict:
    """The student's functions ``names``, wrapped to fail clearly (and never hang the build)
    when they return something the BVH cannot use."""
    functions = dict(zip(names, require(module, *names), strict=True))
    wrappers = {
        "split_costs": _checked_split_costs,
        "best_split": _checked_best_split,
        "child_order": _checked_child_order,
    }
    return {name: wrappers[name](function) for name, function in functions.items()}


def _checked_split_costs(split_costs):
    def checked(bin_count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost=1.0):
        b, k, _ = bin_count.shape
        left = np.cumsum(bin_count, axis=0)[:-1]
        empty = (left == 0) | (left == bin_count.sum(axis=0))
        with np.errstate(all="ignore"):
            cost = np.asarray(
                split_costs(*copy.deepcopy((bin_count, bin_lo, bin_hi, node_lo, node_hi)), traversal_cost),
                dtype=np.float64,
            )
        if cost.shape != (b - 1, k, 3):
            raise CheckFailed(text("ch05.costs_shape", expected=(b - 1, k, 3), shape=cost.shape))
        _require_no_nan(cost)
        if not np.isinf(cost[empty]).all():
            raise CheckFailed(text("ch05.empty_inf"))
        return cost

    return checked


def _require_no_nan(cost: np.ndarray) -> None:
    """Costs may be inf (a split that does not divide its node), never NaN."""
    nan = np.argwhere(np.isnan(cost))
    if len(nan):
        plane, node, axis = nan[0]
        raise CheckFailed(text("ch05.costs_nan", count=len(nan), plane=plane, axis="xyz"[axis], node=node))


def _checked_best_split(best_split):
    def checked(cost, size, max_leaf_size):
        planes, k, _ = cost.shape
        must_split, single = size > max_leaf_size, size < 2
        result = best_split(cost.copy(), size.copy(), max_leaf_size)
        if not (isinstance(result, tuple) and len(result) == 3):
            raise CheckFailed(text("ch05.three_arrays"))
        split_bin, split_axis, make_leaf = (np.asarray(a) for a in result)
        if not split_bin.shape == split_axis.shape == make_leaf.shape == (k,):
            shapes = (split_bin.shape, split_axis.shape, make_leaf.shape)
            raise CheckFailed(text("ch05.split_shapes", k=k, shapes=", ".join(map(str, shapes))))
        if split_bin.dtype.kind not in "iu" or split_axis.dtype.kind not in "iu":
            raise CheckFailed(text("ch05.integers"))
        if make_leaf.dtype != bool:
            raise CheckFailed(text("ch05.leaf_bool"))
        if not (
            np.all((split_bin >= 0) & (split_bin < planes)) and np.all((split_axis >= 0) & (split_axis < 3))
        ):
            raise CheckFailed(text("ch05.split_range", last=planes - 1))
        if np.any(make_leaf & must_split):
            raise CheckFailed(text("ch05.must_split", max_leaf_size=max_leaf_size))
        if np.any(~make_leaf & single):
            raise CheckFailed(text("ch05.single_leaf"))
        return split_bin.astype(np.intp), split_axis.astype(np.intp), make_leaf

    return checked


def _checked_child_order(child_order):
    def checked(first_child, axis, dirs):
        first_child = first_child.copy()  # the grader's own, for the test below
        result = child_order(first_child.copy(), axis.copy(), dirs.copy())
        if not (isinstance(result, tuple) and len(result) == 2):
            raise CheckFailed(text("ch05.two_arrays"))
        near, far = (np.asarray(a) for a in result)
        if near.shape != first_child.shape or far.shape != first_child.shape:
            raise CheckFailed(
                text("ch05.order_shapes", expected=first_child.shape, near=near.shape, far=far.shape)
            )
        if not np.all(
            ((near == first_child) & (far == first_child + 1))
            | ((near == first_child + 1) & (far == first_child))
        ):
            raise CheckFailed(text("ch05.both_children"))
        return near.astype(np.intp), far.astype(np.intp)

    return checked


# -- unit checks --------------------------------------------------------------------------


#: Two nodes binned as ``build_bvh`` bins them (``_binned_example``): (bin_count, bin_lo,
#: bin_hi, node_lo, node_hi), the arguments of ``split_costs`` before ``traversal_cost``.
BinnedExample = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _binned_example(stream: int, flat_node: bool = False) -> BinnedExample:
    """Two nodes (9 and 12 triangles, given as boxes) binned into 5 bins per axis as
    ``build_bvh`` bins them: ``(bin_count, bin_lo, bin_hi, node_lo, node_hi)``.

    Node 0's centroids bunch up at both ends of x (the middle bins stay empty). With
    ``flat_node``, node 1 lies in the plane z = 5, like a wall of the Cornell box: all its
    centroids fall into bin 0 along z, and no z split divides it.
    """
    rng = grading_rng(stream)
    b = 5
    count = np.zeros((b, 2, 3), np.intp)
    bin_lo = np.full((b, 2, 3, 3), np.inf, np.float32)
    bin_hi = np.full((b, 2, 3, 3), -np.inf, np.float32)
    node_lo, node_hi = np.zeros((2, 3)), np.zeros((2, 3))
    for node, n in enumerate((9, 12)):
        lo = rng.uniform(0, 10, (n, 3))
        hi = lo + rng.uniform(0.2, 3, (n, 3))
        if node == 0:
            lo[:, 0] = rng.choice([0.0, 8.0], n) + rng.uniform(0, 0.5, n)
            hi[:, 0] = lo[:, 0] + rng.uniform(0.2, 1, n)
        if node == 1 and flat_node:
            lo[:, 2] = hi[:, 2] = 5.0
        node_lo[node], node_hi[node] = lo.min(axis=0), hi.max(axis=0)
        centroid = (lo + hi) / 2
        c_lo, extent = centroid.min(axis=0), np.ptp(centroid, axis=0)
        scale = np.divide(b, extent, out=np.zeros(3), where=extent > 0)
        bins = np.minimum(((centroid - c_lo) * scale).astype(np.intp), b - 1)
        for axis in range(3):
            for i in range(b):
                inside = bins[:, axis] == i
                count[i, node, axis] = inside.sum()
                if inside.any():
                    bin_lo[i, node, axis] = lo[inside].min(axis=0)
                    bin_hi[i, node, axis] = hi[inside].max(axis=0)
    return count, bin_lo, bin_hi, node_lo, node_hi


def _expected_costs(count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost: float) -> np.ndarray:
    """The SAH cost of every split, plane by plane with plain loops (pbrt-v4 7.3.2)."""

    def area(lo, hi):
        e = np.maximum(hi - lo, 0)
        return 2 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])

    def side(bins, node, axis):
        """Triangles and surface area of the union of the boxes of ``bins``."""
        full = [i for i in bins if count[i, node, axis] > 0]
        if not full:
            return 0, 0.0
        lo = np.min([bin_lo[i, node, axis] for i in full], axis=0).astype(np.float64)
        hi = np.max([bin_hi[i, node, axis] for i in full], axis=0).astype(np.float64)
        return sum(count[i, node, axis] for i in full), area(lo, hi)

    b, k, _ = count.shape
    cost = np.full((b - 1, k, 3), np.inf)
    for node in range(k):
        for axis in range(3):
            for plane in range(b - 1):
                n_left, s_left = side(range(plane + 1), node, axis)
                n_right, s_right = side(range(plane + 1, b), node, axis)
                if n_left and n_right:
                    cost[plane, node, axis] = traversal_cost + (n_left * s_left + n_right * s_right) / area(
                        node_lo[node], node_hi[node]
                    )
    return cost


def _merged_costs(count, bin_lo, bin_hi, node_lo, node_hi, traversal_cost: float, merge_lo, merge_hi):
    """The SAH costs with each side's box merged from its bins' boxes by the ufuncs
    ``merge_lo`` and ``merge_hi``, running over the bins from each end, empty ones
    (bounds inf, -inf) included: a vectorised ``split_costs``, right with ``np.minimum``
    and ``np.maximum``, and a typical mistake's costs with others."""

    def half_area(lo, hi):
        e = np.maximum(hi - lo, 0)
        return e[..., 0] * e[..., 1] + e[..., 1] * e[..., 2] + e[..., 2] * e[..., 0]

    def side(reverse: bool):
        lo, hi, n = (a[::-1] if reverse else a for a in (bin_lo, bin_hi, count))
        area = half_area(merge_lo.accumulate(lo, axis=0), merge_hi.accumulate(hi, axis=0))
        n = np.cumsum(n, axis=0)
        return (area[::-1][1:], n[::-1][1:]) if reverse else (area[:-1], n[:-1])

    (left_area, left_n), (right_area, right_n) = side(False), side(True)
    node_area = half_area(np.asarray(node_lo, np.float64), np.asarray(node_hi, np.float64))
    with np.errstate(all="ignore"):
        cost = traversal_cost + (left_n * left_area + right_n * right_area) / node_area[:, None]
    return np.where((left_n == 0) | (right_n == 0), np.inf, cost)


#: The mistakes in the bounds of a split's sides that the SAH checks name: a lower bound
#: merged with maximum, or an upper bound with minimum, as ``_merged_costs`` has them.
MERGE_MISTAKES = {
    "ch05.hint.merge_hi": (np.minimum, np.minimum),
    "ch05.hint.merge_lo": (np.maximum, np.maximum),
}


def _cost_mistake(got: np.ndarray, example: BinnedExample, traversal_cost: float) -> str:
    """The hint for the mistake whose costs ``got`` are (every finite one of them within
    rounding), of ``MERGE_MISTAKES`` and ``traversal_cost`` left out (0) or hard-coded
    (the homework's 1); "" for none."""
    mistakes = [
        (hint, _merged_costs(*example, traversal_cost, *merges)) for hint, merges in MERGE_MISTAKES.items()
    ]
    mistakes += [
        ("ch05.hint.traversal_cost", _merged_costs(*example, c_trav, np.minimum, np.maximum))
        for c_trav in (0.0, 1.0)
        if c_trav != traversal_cost
    ]
    for hint, costs in mistakes:
        finite = np.isfinite(costs) & np.isfinite(got)
        if finite.any() and np.allclose(got[finite], costs[finite], rtol=1e-4):
            return text(hint)
    return ""


def _compare_costs(got: np.ndarray, example: BinnedExample, traversal_cost: float, what: str) -> None:
    """Fail where ``got`` are not the SAH costs of the binned ``example``
    (``_binned_example``) with ``traversal_cost`` (``what``: what the costs are, in words)."""
    want = _expected_costs(*example, traversal_cost=traversal_cost)
    finite = np.isfinite(want)
    with np.errstate(invalid="ignore"):
        bad = finite & ~(np.abs(got - want) < 1e-4 * np.abs(want))
    if bad.any():
        plane, node, axis = np.argwhere(bad)[0]
        hint = _cost_mistake(got, example, traversal_cost)
        ratio = got[plane, node, axis] / want[plane, node, axis]
        if not hint and abs(ratio - 1) < 0.6:
            hint = text("ch05.hint.union")
        hint = aside(hint)
        raise CheckFailed(
            text(
                "ch05.cost",
                what=what,
                plane=plane,
                axis="xyz"[axis],
                node=node,
                want=want[plane, node, axis],
                yours=got[plane, node, axis],
            )
            + hint
        )


def check_split_costs(module) -> str:
    split_costs = _pieces(module, "split_costs")["split_costs"]
    example = _binned_example(stream=1)
    got = split_costs(*example, traversal_cost=0.5)
    _compare_costs(got, example, 0.5, "0.5 + (N_L S_L + N_R S_R) / S")
    return text("ch05.costs_ok")


def check_empty_sides(module) -> str:
    (split_costs,) = require(module, "split_costs")
    example = _binned_example(stream=2, flat_node=True)
    want = _expected_costs(*example, traversal_cost=1.0)
    with np.errstate(all="ignore"):
        got = np.asarray(split_costs(*copy.deepcopy(example), traversal_cost=1.0), dtype=np.float64)
    if got.shape != want.shape:
        raise CheckFailed(text("ch05.costs_shape", expected=want.shape, shape=got.shape))
    for plane, node, axis in np.argwhere(np.isinf(want)):
        value = got[plane, node, axis]
        if value != np.inf:
            raise CheckFailed(
                text("ch05.empty_side", plane=plane, axis="xyz"[axis], node=node, value=value)
                + (aside(text("ch05.hint.zero_inf")) if np.isnan(value) else "")
            )
    _compare_costs(got, example, 1.0, text("ch05.dividing"))
    return text("ch05.empty_ok")


def check_best_split(module) -> str:
    best_split = _pieces(module, "best_split")["best_split"]
    rng = grading_rng(12)
    cost = rng.uniform(20, 60, (3, 5, 3))  # (every one dearer than the cheapest below)
    cost[2, 0, 1] = 7.5  # node 0: 10 triangles, must split, cheapest at plane 2 along y
    cost[0, 0, 2] = 7.6
    cost[1, 1, 0] = 3.5  # node 1: 3 triangles, cheapest split costs more than 3: a leaf
    cost[0, 2, 2] = 2.0  # node 2: 3 triangles, splitting is cheaper: split
    cost[1, 2, 0] = 2.5
    cost[:, 3] = np.inf  # node 3: 8 triangles, only one split divides it
    cost[0, 3, 2] = 9.0
    cost[:, 4] = np.inf  # node 4: 1 triangle, nothing divides it: a leaf
    size = np.array([10, 3, 3, 8, 1])
    want_leaf = np.array([False, True, False, False, True])
    wants = {0: (2, 1), 2: (0, 2), 3: (0, 2)}
    # The nodes in an order of the grading seed's: node k here is order[k] above.
    order = rng.permutation(5)
    cost, size, want_leaf = cost[:, order], size[order], want_leaf[order]
    wants = {int(np.flatnonzero(order == node)[0]): want for node, want in wants.items()}
    split_bin, split_axis, make_leaf = best_split(cost.copy(), size.copy(), 4)
    leaves = list(want_leaf)
    if list(make_leaf) != leaves:
        node = int(np.flatnonzero(make_leaf != leaves)[0])
        should = "ch05.should_be_leaf" if leaves[node] else "ch05.should_not_be_leaf"
        raise CheckFailed(text(should, node=node, size=size[node], cheapest=cost[:, node].min()))
    for node, want in sorted(wants.items()):
        if (split_bin[node], split_axis[node]) != want:
            raise CheckFailed(
                text(
                    "ch05.cheapest",
                    node=node,
                    plane=want[0],
                    axis="xyz"[want[1]],
                    yours=split_bin[node],
                    your_axis="xyz"[split_axis[node]] if 0 <= split_axis[node] < 3 else "?",
                )
                + aside(_layout_mistake(best_split) or text("ch05.hint.both"))
            )
    return text("ch05.best_ok")


def _layout_mistake(best_split) -> str:
    """The hint for costs flattened in one layout and the index decoded in the other, if
    ``best_split`` (``_checked_best_split``'s) picks so in a node whose cheapest split is
    plane 1 along z of 4 planes; else "". (With 4 planes, not 3, the two layouts' mix-ups
    differ from each other and from plane and axis swapped.)"""
    planes, plane, axis = 4, 1, 2
    cost = np.full((planes, 1, 3), 50.0)
    cost[plane, 0, axis] = 5.0
    split_bin, split_axis, _ = best_split(cost, np.array([10]), 4)
    yours = (int(split_bin[0]), int(split_axis[0]))
    if yours == divmod(axis * planes + plane, 3):  # axis-major index, decoded plane-major
        return text("ch05.hint.axis_major")
    if yours == tuple(reversed(divmod(plane * 3 + axis, planes))):  # and the other way round
        return text("ch05.hint.plane_major")
    return ""


def check_child_order(module) -> str:
    child_order = _pieces(module, "child_order")["child_order"]
    rng = grading_rng(13)
    first_child = 2 * rng.integers(0, 50, 32) + 1
    axis = np.tile([0, 1, 2], 11)[:32]
    # Both signs along every axis; no component near 0, where either child may come first.
    dirs = (rng.choice([-1, 1], (32, 3)) * rng.uniform(0.1, 2, (32, 3))).astype(np.float32)
    want = first_child + (dirs[np.arange(32), axis] < 0)
    near, _far = child_order(first_child.copy(), axis.copy(), dirs.copy())
    wrong = np.flatnonzero(near != want)
    if wrong.size:
        i = wrong[0]
        going = "ch05.going_up" if dirs[i, axis[i]] > 0 else "ch05.going_down"
        raise CheckFailed(text(going, d=dirs[i].tolist(), axis="xyz"[axis[i]], want=want[i], yours=near[i]))
    return text("ch05.order_ok")


# -- the pieces inside the BVH ------------------------------------------------------------


def check_closest_hits(module) -> str:
    tris = uneven_mesh()
    origins, dirs = _random_rays(3000)
    tmax = grading_rng(11).uniform(0, 600, len(dirs)).astype(np.float32)
    t_all = _brute_force(tris, origins, dirs)
    bvh = NumpyBVH(tris.copy(), pieces=BVHPieces(**_pieces(module, *PIECES)))
    hits = bvh.intersect(origins.copy(), dirs.copy())
    occluded = bvh.occluded(origins.copy(), dirs.copy(), tmax.copy())
    t_want = t_all.min(axis=1)
    # Equal up to float32 rounding: where two triangles meet, the one a box test lets
    # through first may be an ulp farther, whatever the order (pbrt-v4's slab test alike).
    with np.errstate(invalid="ignore"):
        wrong = ~(np.abs(hits.t - t_want) <= 1e-5 * t_want) & (hits.t != t_want)
    if wrong.any():
        i = np.flatnonzero(wrong)[0]
        what = (
            text("ch05.misses")
            if not hits.hit[i]
            else text("ch05.farther", t=hits.t[i])
            if hits.t[i] > t_want[i]
            else text("ch05.reports", t=hits.t[i])
        )
        raise CheckFailed(text("ch05.closest", wrong=wrong.sum(), n=len(dirs), t=t_want[i], what=what))
    hit_t = t_all[np.arange(len(dirs)), np.where(hits.hit, hits.prim, 0)]
    if not np.array_equal(hit_t[hits.hit], hits.t[hits.hit]):
        raise CheckFailed(text("ch05.wrong_triangle"))
    want_occluded = (t_all < tmax[:, None]).any(axis=1)
    if not np.array_equal(occluded, want_occluded):
        raise CheckFailed(text("ch05.shadow", wrong=np.count_nonzero(occluded != want_occluded), n=len(dirs)))
    return text("ch05.closest_ok", n=len(dirs), share=hits.hit.mean())


def check_tree_quality(module) -> str:
    tris = uneven_mesh()
    pieces = _pieces(module, "split_costs", "best_split")
    library = _tree_cost(tris)
    student = _tree_cost(tris, **pieces)
    if not student <= library * (1 + SAH_TOLERANCE):
        # Which piece makes the tree worse: each of the student's two with the library's other.
        with_costs = _tree_cost(tris, split_costs=pieces["split_costs"])
        with_choice = _tree_cost(tris, best_split=pieces["best_split"])
        costs_bad = with_costs > library * (1 + SAH_TOLERANCE)
        choice_bad = with_choice > library * (1 + SAH_TOLERANCE)
        causes = []
        if choice_bad or not costs_bad:
            layout = _layout_mistake(pieces["best_split"])
            choice = "ch05.choice_bad_because" if layout else "ch05.choice_bad"
            causes.append(text(choice, cost=with_choice, check=check_name(5, "best split"), hint=layout))
        if costs_bad:
            example = _binned_example(stream=1)
            mistake = _cost_mistake(pieces["split_costs"](*copy.deepcopy(example), 0.5), example, 0.5)
            costs = "ch05.costs_bad_because" if mistake else "ch05.costs_bad"
            causes.append(text(costs, cost=with_costs, hint=mistake))
        raise CheckFailed(
            text("ch05.tree", student=student, library=library, more=student / library - 1)
            + text("ch05.sentences").join(causes)
        )
    return text("ch05.tree_ok", student=student, library=library)


def _tree_cost(tris: np.ndarray, **pieces) -> float:
    """The SAH cost of the tree ``build_bvh`` makes of ``tris`` with ``pieces`` (by name) in
    the library's place."""
    return sah_cost(build_bvh(tris, pieces=BVHPieces(**pieces)))


def check_traversal_order(module) -> str:
    tris, origins, dirs = row_of_balls()
    library_slab_test = BVHPieces().slab_test
    entered = [0]

    def counting_slab_test(*args):
        hit, t_enter = library_slab_test(*args)
        entered[0] += int(np.count_nonzero(hit))
        return hit, t_enter

    # The same tree (the library's build) walked in the library's order, then the student's.
    NumpyBVH(tris, pieces=BVHPieces(slab_test=counting_slab_test)).intersect(origins, dirs)
    library, entered[0] = entered[0], 0
    student_order = BVHPieces(slab_test=counting_slab_test, **_pieces(module, "child_order"))
    NumpyBVH(tris, pieces=student_order).intersect(origins, dirs)
    student = entered[0]
    if not student <= library * (1 + VISIT_TOLERANCE):
        raise CheckFailed(text("ch05.order", student=student / len(dirs), library=library / len(dirs)))
    return text("ch05.traversal_ok", student=student / len(dirs), library=library / len(dirs))


def check_render(module) -> str:
    from ptlab.course.renders import check_render_through

    return check_render_through(text("ch05.yours"), Pieces(bvh=BVHPieces(**_pieces(module, *PIECES))))


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered through the student's BVH pieces (``ptlab exercise render``), on the
    NumPy BVH, which walks its tree through them whatever the scene's size."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, Pieces(bvh=BVHPieces(**_pieces(module, *PIECES))))


CHAPTER = Chapter(
    number=5,
    slug="bvh",
    title="The BVH: building with the SAH, and traversal",
    functions=PIECES,
    answers=(
        "ptlab.accel.numpy_bvh.split_costs",
        "ptlab.accel.numpy_bvh.best_split",
        "ptlab.accel.numpy_bvh.child_order",
    ),
    # The library's BVH builds and traverses a tree whole, and Embree is one.
    also_left_out=("ptlab.accel.numpy_bvh", "ptlab.accel.embree"),
    packages=("numpy", "scipy"),
    checks=(
        ChapterCheck("SAH costs", 2, check_split_costs, timeout=30),
        ChapterCheck("empty sides", 1, check_empty_sides, timeout=30),
        ChapterCheck("best split", 1, check_best_split, timeout=30),
        ChapterCheck("near child first", 1, check_child_order, timeout=30),
        # Any build the wrappers accept (any split that divides a node, the SAH's or not)
        # makes a valid tree, and any child order visits both children: the BVH then finds
        # the right hits with no work of the student's. What these two add of theirs is the
        # traversal piece inside the real BVH, so they score with its own check (a median
        # split with a right child_order earns them; the SAH's points it does not).
        ChapterCheck("closest hits", 2, check_closest_hits, timeout=60, requires=("near child first",)),
        ChapterCheck("tree quality", 1, check_tree_quality, timeout=60),
        ChapterCheck("traversal order", 1, check_traversal_order, timeout=60),
        ChapterCheck("render", 1, check_render, timeout=60, requires=("near child first",)),
    ),
    render=ChapterRender(render_yours, options=dict(backend="numpy")),
)
