"""Warps: each produces what its pdf claims (fixed seeds, 200k samples)."""

from __future__ import annotations

import numpy as np
import pytest

from ptlab.samplers import ONE_MINUS_EPSILON
from ptlab.sampling import (
    cosine_hemisphere,
    discrete_cdf,
    pick_from_cdf,
    to_world,
    uniform_hemisphere,
    uniform_triangle,
)

N = 200_000


@pytest.fixture
def u():
    return np.random.default_rng(0).random((N, 2))


def test_uniform_hemisphere_moments(u):
    w = uniform_hemisphere(u)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-12)
    assert (w[:, 2] >= 0).all()
    # Uniform on the hemisphere: cos(theta) is uniform on [0, 1]: mean 1/2, E[cos^2] = 1/3.
    # Tolerances are 5 standard errors (sd <= 0.3 / sqrt(N)): false alarm < 1e-6.
    assert w[:, 2].mean() == pytest.approx(1 / 2, abs=5 * 0.29 / np.sqrt(N))
    assert (w[:, 2] ** 2).mean() == pytest.approx(1 / 3, abs=5 * 0.3 / np.sqrt(N))
    assert abs(w[:, 0].mean()) < 5 * 0.5 / np.sqrt(N)


def test_cosine_hemisphere_moments(u):
    w = cosine_hemisphere(u)
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-12)
    # pdf cos/pi: E[cos] = 2/3, E[cos^2] = 1/2 (a uniform sampler would give 1/2 and 1/3).
    assert w[:, 2].mean() == pytest.approx(2 / 3, abs=5 * 0.24 / np.sqrt(N))
    assert (w[:, 2] ** 2).mean() == pytest.approx(1 / 2, abs=5 * 0.29 / np.sqrt(N))


def test_to_world_maps_z_to_the_normal_and_keeps_lengths_and_angles():
    rng = np.random.default_rng(1)
    n = rng.normal(size=(1000, 3))
    n[:3] = [[0, 0, 1], [0, 0, -1], [1, 0, 0]]  # the frame's special cases
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    local = cosine_hemisphere(rng.random((1000, 2)))
    world = to_world(local, n)
    np.testing.assert_allclose(to_world(np.tile([0.0, 0, 1], (1000, 1)), n), n, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(world, axis=1), 1, atol=1e-12)
    np.testing.assert_allclose((world * n).sum(axis=1), local[:, 2], atol=1e-12)


def test_uniform_triangle_is_uniform(u):
    b1, b2 = uniform_triangle(u)
    assert (b1 >= 0).all()
    assert (b2 >= 0).all()
    assert (b1 + b2 <= 1).all()
    # Uniform on the triangle: each barycentric has mean 1/3; the sub-triangle
    # b1 + b2 < 1/2 (the corner at v0 cut at half height) holds 1/4 of the area.
    for b in (b1, b2, 1 - b1 - b2):
        assert b.mean() == pytest.approx(1 / 3, abs=5 * 0.24 / np.sqrt(N))
    assert ((b1 + b2) < 0.5).mean() == pytest.approx(0.25, abs=5 * 0.44 / np.sqrt(N))


@pytest.mark.parametrize("name", ["uniform_hemisphere_around", "cosine_hemisphere_around"])
def test_hemisphere_warps_are_one_to_one(name):
    # Stratified uniforms must stay spread out after the warp: no two strata may land on
    # the same directions. Folding the lower half of the sphere onto the upper (as a
    # mirror would) maps the centres of cell (i, j) and of its antipodal cell onto the
    # same direction: their distance is 0.
    from scipy.spatial import cKDTree

    import ptlab.sampling as sampling

    k = (np.arange(64) + 0.5) / 64
    u = np.stack(np.meshgrid(k, k), axis=-1).reshape(-1, 2)
    n = np.tile(np.array([[0.36, -0.48, 0.8]]), (len(u), 1))
    w = getattr(sampling, name)(n, u)
    distances, _ = cKDTree(w).query(w, k=2)
    # 4096 directions on a hemisphere (2 pi sr) are about sqrt(2 pi / 4096) = 0.04 apart.
    assert distances[:, 1].min() > 1e-4


def test_sampling_around_a_normal_matches_the_local_frame_warps(u):
    from ptlab.sampling import cosine_hemisphere_around, uniform_hemisphere_around

    rng = np.random.default_rng(3)
    n = rng.normal(size=(N, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    for around, expected_mean in ((uniform_hemisphere_around, 1 / 2), (cosine_hemisphere_around, 2 / 3)):
        w = around(n, u)
        np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1, atol=1e-12)
        cos = (w * n).sum(axis=1)
        assert (cos >= 0).all()
        assert cos.mean() == pytest.approx(expected_mean, abs=5 * 0.3 / np.sqrt(N))
        # The distribution of cos(theta) itself: CDF P(cos < c) = c (uniform), c^2 (cosine).
        for c in (0.25, 0.5, 0.75):
            cdf = c if around is uniform_hemisphere_around else c * c
            assert (cos < c).mean() == pytest.approx(cdf, abs=5 * 0.5 / np.sqrt(N))
        # Around the normal, the azimuth is uniform: no preferred tangent direction.
        tangent = np.cross(n, [0.0, 0.0, 1.0])
        assert abs((w * tangent).sum(axis=1).mean()) < 5 * 0.5 / np.sqrt(N)


@pytest.mark.parametrize("items", [5, 40])  # (counted pass by pass; found by binary search)
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_pick_from_cdf_picks_by_weight_and_stretches_u_back_evenly(items, dtype):
    # Evenly spaced u: each item gets exactly its share of them (weight 0: none), and the u
    # that picked an item, stretched, are evenly spaced in [0, 1) again. Deterministic.
    weights = np.zeros(items)
    weights[0], weights[2], weights[items - 2] = 1, 3, 4  # (the last item: weight 0)
    cdf = discrete_cdf(weights).astype(dtype)
    count = 8000
    u = ((np.arange(count) + 0.5) / count).astype(np.float32)
    index, stretched = pick_from_cdf(cdf, u)
    expected = {0: 1000, 2: 3000, items - 2: 4000}
    assert np.bincount(index, minlength=items).tolist() == [expected.get(i, 0) for i in range(items)]
    assert stretched.dtype == np.float32
    for item, picked in expected.items():
        np.testing.assert_allclose(
            np.sort(stretched[index == item]), (np.arange(picked) + 0.5) / picked, atol=1e-4
        )


def test_pick_from_cdf_keeps_u_below_one_where_the_cdf_falls_short_of_it():
    # A float32 cdf may end just below 1: a u above its last entry still picks the last item,
    # and no stretched u reaches 1 (a uniform of 1 would put a light point off its triangle).
    cdf = np.array([0.5, 1 - 2**-23], dtype=np.float32)
    u = np.array([0.0, 0.5, 1 - 2**-23, ONE_MINUS_EPSILON], dtype=np.float32)
    index, stretched = pick_from_cdf(cdf, u)
    assert index.tolist() == [0, 1, 1, 1]
    assert stretched[:2].tolist() == [0, 0]
    assert (stretched < 1).all()
    assert stretched[3] == ONE_MINUS_EPSILON
