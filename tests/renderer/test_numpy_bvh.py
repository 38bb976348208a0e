"""Tests of the NumPy BVH backend (``ptlab.accel.numpy_bvh``) and of Möller-Trumbore
(``ptlab.accel.triangle``): known answers for the small pieces, and agreement with the
Embree backend on random rays (fixed seeds) for the whole accelerator.

Agreement with Embree means: the same rays hit; the same triangle, except where two
triangles are hit at the same ``t`` (a shared edge, coplanar faces); ``t`` equal to a
relative 1e-5, or to the float32 resolution of the hit point, whichever is larger (a
ray that starts a hair away from a surface has a tiny ``t`` that no float32 tracer,
Embree included, knows to 1e-5 relative, and a grazing ray turns a small error across
the surface into a large one along the ray); ``u, v`` equal to 1e-4 on the same
triangle.
"""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest
import trimesh

from ptlab.accel import numpy_bvh
from ptlab.accel.base import Hits
from ptlab.accel.embree import EmbreeAccelerator
from ptlab.accel.numpy_bvh import SMALL_SCENE, NumpyBVH, build_bvh, slab_test
from ptlab.accel.triangle import ray_triangle

F32_EPS = float(np.finfo(np.float32).eps)


# --- scenes and rays --------------------------------------------------------------------


def box_triangles(lo, hi, angle_deg: float = 0.0, bottom: bool = True) -> np.ndarray:
    """(12, 3, 3) triangles of the box [lo, hi] turned by ``angle_deg`` about its
    vertical (y) axis; (10, 3, 3) without the two facing -y when ``bottom`` is False."""
    mesh = trimesh.creation.box(extents=np.subtract(hi, lo))
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.radians(angle_deg), [0, 1, 0]))
    mesh.apply_translation(np.add(lo, hi) / 2)
    tris = mesh.vertices[mesh.faces]
    if not bottom:
        tris = tris[mesh.face_normals[:, 1] > -0.5]
    return tris


def quad(corner, edge1, edge2) -> np.ndarray:
    """(2, 3, 3) triangles of the parallelogram corner + a * edge1 + b * edge2."""
    c, e1, e2 = (np.asarray(a, dtype=float) for a in (corner, edge1, edge2))
    return np.array([[c, c + e1, c + e1 + e2], [c, c + e1 + e2, c + e2]])


def cornell_like() -> np.ndarray:
    """(34, 3, 3): the room 0..556 (12), a short and a tall box turned by -17 and +17
    degrees standing on the floor, without their bottoms (10 + 10), and a ceiling
    light just below the ceiling (2); about the GAMES101 Cornell box."""
    return np.concatenate(
        [
            box_triangles([0, 0, 0], [556, 556, 556]),
            box_triangles([130, 0, 65], [295, 165, 230], -17, bottom=False),
            box_triangles([265, 0, 295], [430, 330, 460], 17, bottom=False),
            quad([213, 548.7, 227], [130, 0, 0], [0, 0, 105]),
        ]
    )


def big_mesh() -> np.ndarray:
    """(102400, 3, 3): two overlapping icospheres (81920 and 20480 triangles)."""
    a = trimesh.creation.icosphere(subdivisions=6)
    b = trimesh.creation.icosphere(subdivisions=5, radius=0.5)
    b.apply_translation([0.9, 0.3, 0.0])
    return np.concatenate([a.vertices[a.faces], b.vertices[b.faces]])


def random_rays(
    rng: np.random.Generator, n: int, inner: tuple[float, float], outer: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) float32 origins, half in the cube ``inner`` and half in ``outer``, and
    directions of random lengths; a fifth of them have one or two components exactly 0."""
    origins = np.concatenate([rng.uniform(*inner, (n // 2, 3)), rng.uniform(*outer, (n - n // 2, 3))])
    dirs = rng.normal(size=(n, 3)) * rng.uniform(0.1, 10.0, (n, 1))
    axis_aligned = rng.random(n) < 0.2
    zeros = rng.random((n, 3)) < 0.5
    zeros[np.arange(n), rng.integers(0, 3, n)] = False  # never all three
    dirs[axis_aligned[:, None] & zeros] = 0.0
    return origins.astype(np.float32), dirs.astype(np.float32)


def assert_hits_match(ref: Hits, hits: Hits, origins: np.ndarray, dirs: np.ndarray, tris: np.ndarray):
    """The agreement with Embree described in the module docstring."""
    np.testing.assert_array_equal(hits.hit, ref.hit)
    assert hits.t.dtype == np.float32
    assert hits.prim.dtype == np.intp
    assert hits.u.dtype == np.float32
    assert hits.v.dtype == np.float32
    assert np.all(hits.prim[~hits.hit] == -1)
    assert np.all(np.isinf(hits.t[~hits.hit]))
    hit = ref.hit
    t, t_ref = hits.t[hit].astype(float), ref.t[hit].astype(float)
    # A float32 hit point is known to a few ulps of the coordinates' size; along a ray
    # at grazing angle theta to the surface that is 1/cos(theta) times more in t.
    d = dirs[hit].astype(float)
    tri = tris[ref.prim[hit]]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    d_cos = np.abs(np.sum(normal * d, axis=1)) / np.linalg.norm(normal, axis=1)
    size = np.abs(origins[hit]).max(axis=1) + t_ref * np.linalg.norm(d, axis=1)
    tol = np.maximum(1e-5 * t_ref, 8 * F32_EPS * size / d_cos)
    bad = np.abs(t - t_ref) > tol
    assert not bad.any(), f"{bad.sum()} rays with t off, e.g. {t[bad][:3]} vs {t_ref[bad][:3]}"
    same = hits.prim[hit] == ref.prim[hit]
    assert same.mean() > 0.99  # a different triangle only at ties (t agrees)
    for name in ("u", "v"):
        err = np.abs(getattr(hits, name)[hit] - getattr(ref, name)[hit])[same]
        assert err.max() < 1e-4, f"{name} off by {err.max()}"


def check_against_embree(
    tris: np.ndarray,
    origins: np.ndarray,
    dirs: np.ndarray,
    rng: np.random.Generator,
    every_triangle: bool | None = None,
):
    embree, bvh = EmbreeAccelerator(tris), NumpyBVH(tris, every_triangle=every_triangle)
    ref = embree.intersect(origins, dirs)
    assert_hits_match(ref, bvh.intersect(origins, dirs), origins, dirs, tris)

    # Per-ray tmin: Embree moves the origin instead, so compare with its tolerance.
    tmin = (rng.uniform(0, 0.8, len(dirs)) * np.where(ref.hit, ref.t, 1)).astype(np.float32)
    assert_hits_match(
        embree.intersect(origins, dirs, tmin=tmin),
        bvh.intersect(origins, dirs, tmin=tmin),
        origins,
        dirs,
        tris,
    )

    # Shadow rays with finite tmax, leaving out those with a hit within 1e-4 of tmax.
    tmax = np.where(ref.hit, ref.t, 1.0) * rng.uniform(0.5, 1.5, len(dirs))
    clear = ~ref.hit | (np.abs(tmax - ref.t) > 1e-4 * ref.t)
    tmax = tmax.astype(np.float32)
    expected = embree.occluded(origins, dirs, tmax)
    got = bvh.occluded(origins, dirs, tmax)
    assert 0.1 < expected.mean() < 0.9  # both answers well represented
    np.testing.assert_array_equal(got[clear], expected[clear])


# --- Möller-Trumbore ------------------------------------------------------------------

V0, V1, V2 = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])


def mt(origin, direction):
    """ray_triangle for one ray against the triangle V0, V1, V2, as Python floats."""
    t, u, v = ray_triangle(
        np.array([origin], float), np.array([direction], float), V0[None], (V1 - V0)[None], (V2 - V0)[None]
    )
    return float(t[0]), float(u[0]), float(v[0])


def test_ray_triangle_known_answer():
    t, u, v = mt([0.25, 0.5, 1.0], [0, 0, -1])
    assert (t, u, v) == pytest.approx((1.0, 0.25, 0.5))
    hit_point = (1 - u - v) * V0 + u * V1 + v * V2
    np.testing.assert_allclose(hit_point, [0.25, 0.5, 0.0])
    assert mt([0.25, 0.5, 1.0], [0, 0, -2]) == pytest.approx((0.5, 0.25, 0.5))  # t in |d|s


def test_ray_triangle_broadcasts_one_triangle():
    origins = np.array([[0.25, 0.5, 1.0], [0.5, 0.25, 2.0], [2.0, 2.0, 1.0]])
    t, u, v = ray_triangle(origins, np.array([0.0, 0, -1]), V0, V1 - V0, V2 - V0)
    np.testing.assert_allclose(t, [1, 2, np.inf])
    np.testing.assert_allclose([u[:2], v[:2]], [[0.25, 0.5], [0.5, 0.25]])


def test_ray_triangle_back_face_hits():
    assert mt([0.25, 0.5, -1.0], [0, 0, 1]) == pytest.approx((1.0, 0.25, 0.5))


def test_ray_triangle_misses():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero warnings either
        assert mt([0.25, 0.5, 1.0], [1, 0, 0])[0] == np.inf  # parallel to the plane
        assert mt([0.25, 0.5, 0.0], [1, 1, 0])[0] == np.inf  # parallel, in the plane
        assert mt([0.8, 0.8, 1.0], [0, 0, -1])[0] == np.inf  # outside, u + v > 1
        assert mt([-0.1, 0.5, 1.0], [0, 0, -1])[0] == np.inf  # outside, u < 0
    # Behind the origin is a hit at negative t: keeping t > tmin is the caller's job.
    assert mt([0.25, 0.5, 1.0], [0, 0, 1])[0] == pytest.approx(-1.0)


def test_ray_triangle_matches_a_linear_solve():
    """Random rays and triangles against o + t d = v0 + u e1 + v e2 solved directly."""
    rng = np.random.default_rng(1)
    n = 2000
    o, d, v0, e1, e2 = (rng.normal(size=(n, 3)) for _ in range(5))
    t, u, v = ray_triangle(o, d, v0, e1, e2)
    tuv = np.linalg.solve(np.stack([d, -e1, -e2], axis=-1), (v0 - o)[..., None])[..., 0]
    inside = (tuv[:, 1] >= 0) & (tuv[:, 2] >= 0) & (tuv[:, 1] + tuv[:, 2] <= 1)
    clear = np.min(np.abs([tuv[:, 1], tuv[:, 2], 1 - tuv[:, 1] - tuv[:, 2]]), axis=0) > 1e-9
    np.testing.assert_array_equal(np.isfinite(t)[clear], inside[clear])
    for got, want in zip((t, u, v), tuv.T, strict=True):
        np.testing.assert_allclose(got[inside], want[inside], rtol=1e-6, atol=1e-9)


# --- slab test ------------------------------------------------------------------------


def slab(origin, direction, lo, hi, tmin=0.0, tmax=np.inf):
    """slab_test for one ray and one box, as (bool, float)."""
    with np.errstate(divide="ignore"):
        inv = 1 / np.array([direction], np.float32)
    hit, t_enter = slab_test(
        np.array([origin], np.float32),
        inv,
        np.array([lo], np.float32),
        np.array([hi], np.float32),
        tmin,
        tmax,
    )
    return bool(hit[0]), float(t_enter[0])


def test_slab_test_box():
    assert slab([-1, 0.5, 0.5], [2, 0, 0], [0, 0, 0], [1, 1, 1]) == (True, 0.5)
    assert slab([0.5, 0.5, 0.5], [1, 1, 1], [0, 0, 0], [1, 1, 1]) == (True, 0.0)  # inside
    assert not slab([-1, 0.5, 0.5], [-1, 0, 0], [0, 0, 0], [1, 1, 1])[0]  # box behind
    assert not slab([-1, 0.5, 0.5], [1, 0, 0], [0, 0, 0], [1, 1, 1], tmax=0.9)[0]
    assert not slab([-1, 0.5, 0.5], [1, 1, 0], [0, 0, 0], [1, 1, 1])[0]  # passes by


def test_slab_test_flat_box():
    flat = ([0, 0, 1], [1, 1, 1])  # the square z = 1, 0 <= x, y <= 1
    assert slab([0.5, 0.5, 0], [0, 0, 1], *flat) == (True, 1.0)  # perpendicular
    assert slab([0.5, 0.5, 3], [0, 0, -2], *flat) == (True, 1.0)
    assert slab([0, 0, 0], [1, 1, 1], *flat) == (True, 1.0)  # through a corner
    assert not slab([2, 0.5, 0], [0, 0, 1], *flat)[0]  # beside it
    assert slab([-1, 0.5, 1], [1, 0, 0], *flat) == (True, 1.0)  # in its plane


def test_slab_test_ray_parallel_to_a_slab():
    box = ([0, 0, 0], [1, 1, 1])
    assert not slab([-1, 2, 0.5], [1, 0, 0], *box)[0]  # outside the y slab: miss
    assert slab([-1, 0.5, 0.5], [1, 0, 0], *box)[0]  # inside it: hit
    assert slab([-1, 1, 0.5], [1, 0, 0], *box)[0]  # on its boundary plane: hit
    assert slab([-1, 0, 0], [1, 0, 0], *box)[0]  # along an edge: hit


# --- the BVH ------------------------------------------------------------------------------


@pytest.mark.parametrize("max_leaf_size", [1, 4, 8])
def test_build_invariants(max_leaf_size):
    rng = np.random.default_rng(2)
    tris = np.concatenate(
        [
            cornell_like(),
            rng.uniform(0, 556, (200, 3, 3)),
            np.repeat(rng.uniform(0, 556, (1, 3, 3)), 20, axis=0),
        ]
    )  # 20 alike
    bvh = build_bvh(tris, max_leaf_size=max_leaf_size)
    leaf = np.flatnonzero(bvh.count > 0)
    assert bvh.count.max() <= max_leaf_size
    np.testing.assert_array_equal(np.sort(bvh.order), np.arange(len(tris)))
    covered = np.concatenate(
        [np.arange(f, f + c) for f, c in zip(bvh.first[leaf], bvh.count[leaf], strict=True)]
    )
    np.testing.assert_array_equal(np.sort(covered), np.arange(len(tris)))
    for i in leaf:
        leaf_tris = tris[bvh.order[bvh.first[i] : bvh.first[i] + bvh.count[i]]]
        np.testing.assert_array_equal(bvh.box_min[i], leaf_tris.min(axis=(0, 1)))
        np.testing.assert_array_equal(bvh.box_max[i], leaf_tris.max(axis=(0, 1)))
    inner = np.flatnonzero(bvh.count == 0)
    for c in (bvh.child[inner], bvh.child[inner] + 1):
        assert np.all(bvh.box_min[c] >= bvh.box_min[inner])
        assert np.all(bvh.box_max[c] <= bvh.box_max[inner])


def test_the_tree_is_the_same_however_many_nodes_are_binned_at_once(monkeypatch):
    # A deep level's nodes are binned a group at a time (to bound memory); the groups must not
    # change a single split.
    rng = np.random.default_rng(7)
    tris = np.concatenate([cornell_like(), rng.uniform(0, 556, (3000, 3, 3))])
    trees = []
    for cells in (1e-9, 0.25, 1e9):
        monkeypatch.setattr(numpy_bvh, "CELLS_PER_TRIANGLE", cells)
        trees.append(build_bvh(tris))
    for tree in trees[1:]:
        for name in ("box_min", "box_max", "child", "axis", "first", "count", "order"):
            np.testing.assert_array_equal(getattr(tree, name), getattr(trees[0], name))


def test_a_big_mesh_builds_within_a_bounded_memory_per_triangle():
    # tracemalloc counts NumPy's arrays, so the peak is the same on any machine. It was 1.1-1.4
    # KB a triangle when a deep level binned all its nodes at once (docs/performance.md).
    sphere = trimesh.creation.icosphere(subdivisions=6)  # 81 920 triangles
    tris = sphere.vertices[sphere.faces]
    tracemalloc.start()
    try:
        NumpyBVH(tris)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak / len(tris) < 450, f"{peak / len(tris):.0f} bytes a triangle"


# Both ways of answering a query: walking the tree, and (the default for a scene this small)
# testing every triangle, plane first.
BOTH_WAYS = pytest.mark.parametrize("every_triangle", [False, True], ids=["tree", "every"])


@BOTH_WAYS
def test_cornell_like_matches_embree(every_triangle):
    rng = np.random.default_rng(3)
    origins, dirs = random_rays(rng, 20000, (1, 555), (-300, 856))
    check_against_embree(cornell_like(), origins, dirs, rng, every_triangle)


def test_a_small_scene_tests_every_triangle_and_a_large_one_walks_the_tree():
    assert NumpyBVH(cornell_like()).every_triangle
    assert not NumpyBVH(cornell_like()[:1].repeat(SMALL_SCENE + 1, axis=0)).every_triangle


def test_both_ways_find_the_same_hits_ray_by_ray():
    rng = np.random.default_rng(6)
    origins, dirs = random_rays(rng, 20000, (1, 555), (-300, 856))
    tris = cornell_like()
    tree, every = NumpyBVH(tris, every_triangle=False), NumpyBVH(tris, every_triangle=True)
    a, b = tree.intersect(origins, dirs), every.intersect(origins, dirs)
    np.testing.assert_array_equal(a.hit, b.hit)
    assert np.mean(a.prim == b.prim) > 0.999  # another triangle only where two meet
    assert_hits_match(a, b, origins, dirs, tris)  # t, u, v up to float32 rounding
    tmax = rng.uniform(0, 1000, len(dirs)).astype(np.float32)
    clear = ~a.hit | (np.abs(tmax - a.t) > 1e-4 * a.t)
    np.testing.assert_array_equal(
        tree.occluded(origins, dirs, tmax)[clear], every.occluded(origins, dirs, tmax)[clear]
    )


def test_big_mesh_matches_embree():
    rng = np.random.default_rng(4)
    origins, dirs = random_rays(rng, 10000, (-1, 1), (-3, 3))
    check_against_embree(big_mesh(), origins, dirs, rng)


@BOTH_WAYS
def test_float64_rays_give_the_same_hits(every_triangle):
    rng = np.random.default_rng(5)
    origins, dirs = random_rays(rng, 2000, (1, 555), (1, 555))
    bvh = NumpyBVH(cornell_like(), every_triangle=every_triangle)
    h32 = bvh.intersect(origins, dirs)
    h64 = bvh.intersect(origins.astype(np.float64), dirs.astype(np.float64))
    for name in ("t", "prim", "u", "v"):
        np.testing.assert_array_equal(getattr(h64, name), getattr(h32, name))


@pytest.mark.parametrize(("max_leaf_size", "every_triangle"), [(1, False), (4, False), (4, True)])
def test_single_axis_aligned_quad(max_leaf_size, every_triangle):
    """A flat tree: the quad z = 1, 0 <= x, y <= 1 (with max_leaf_size 1, a flat root
    over two flat leaves), hit by rays along z and rays with zero components."""
    bvh = NumpyBVH(
        quad([0, 0, 1], [1, 0, 0], [0, 1, 0]), max_leaf_size=max_leaf_size, every_triangle=every_triangle
    )
    assert bvh.bvh.box_min[0, 2] == bvh.bvh.box_max[0, 2] == 1.0
    xy = np.stack(np.meshgrid(np.linspace(0.05, 0.95, 7), np.linspace(0.05, 0.95, 7)), axis=-1).reshape(-1, 2)
    n = len(xy)
    origins = np.column_stack([xy, np.zeros(n)])
    for dirs, t in [((0, 0, 1), 1.0), ((0, 0, 4), 0.25)]:
        hits = bvh.intersect(origins, np.tile(dirs, (n, 1)))
        assert hits.hit.all()
        assert np.all(hits.t == t)
        np.testing.assert_allclose(
            origins + hits.t[:, None] * np.array(dirs), np.column_stack([xy, np.ones(n)]), atol=1e-6
        )
    from_above = bvh.intersect(origins + np.array([0, 0, 2]), np.tile([0, 0, -1], (n, 1)))
    assert from_above.hit.all()
    assert np.all(from_above.t == 1.0)
    # One zero component, and rays in the quad's plane (a miss, as for Embree).
    slanted = bvh.intersect([[0.5, -0.5, 0], [-0.5, 0.5, 0]], [[0, 1, 1], [1, 0, 1]])
    np.testing.assert_allclose(slanted.t, [1, 1])
    in_plane = bvh.intersect([[-1, 0.5, 1], [0.5, -1, 1]], [[1, 0, 0], [0, 1, 0]])
    assert not in_plane.hit.any()


@BOTH_WAYS
def test_tmin_and_tmax(every_triangle):
    """Two quads, at z = 1 and z = 2, and rays along +z from z = 0."""
    tris = np.concatenate([quad([0, 0, 1], [1, 0, 0], [0, 1, 0]), quad([0, 0, 2], [1, 0, 0], [0, 1, 0])])
    bvh = NumpyBVH(tris, every_triangle=every_triangle)
    o = np.tile([0.3, 0.6, 0.0], (5, 1))
    d = np.tile([0.0, 0.0, 1.0], (5, 1))
    assert np.all(bvh.intersect(o, d).t == 1)
    assert not bvh.intersect(o, d, tmax=0.5).hit.any()  # scalars
    assert np.all(bvh.intersect(o, d, tmin=1.5).t == 2)
    assert np.all(bvh.intersect(o, d, tmin=1.5).prim >= 2)
    hits = bvh.intersect(
        o,
        d,
        tmin=np.array([0, 1.5, 0, 2.5, 1.5]),  # per-ray arrays
        tmax=np.array([np.inf, np.inf, 0.5, np.inf, 1.9]),
    )
    np.testing.assert_array_equal(hits.t, [1, 2, np.inf, np.inf, np.inf])
    np.testing.assert_array_equal(hits.hit, [True, True, False, False, False])
    np.testing.assert_array_equal(
        bvh.occluded(o, d, np.array([0.5, 1.5, 3, 1.0, 2.0])), [False, True, True, False, True]
    )
    assert not bvh.occluded(o, d, 1.0).any()  # 0 < t < tmax, strictly
    assert np.all(bvh.intersect(o, 2 * d).t == 0.5)  # t in units of |d|


@BOTH_WAYS
def test_no_rays(every_triangle):
    hits = NumpyBVH(cornell_like(), every_triangle=every_triangle).intersect(
        np.zeros((0, 3)), np.zeros((0, 3))
    )
    assert hits.t.shape == hits.prim.shape == (0,)
