"""Samplers (ptlab/samplers.py): the patterns they promise, their independence, and images that
do not depend on how a render is cut up.

Statistical tests here use fixed seeds; each states its bound and false-alarm rate.
"""

from __future__ import annotations

import numpy as np
import pytest

import ptlab
from ptlab.rendering import render_result
from ptlab.samplers import (
    ONE_MINUS_EPSILON,
    SAMPLERS,
    BounceUniforms,
    largest_below_one,
    make_sampler,
)


def pixel_points(
    name: str, count: int, dim: int, pixel: int = 12345, seed: int = 7, spp: int | None = None
) -> np.ndarray:
    """(count, 2) the first ``count`` samples of one pixel in the pair starting at ``dim``."""
    sampler = make_sampler(name, seed, spp or count)
    keys = sampler.keys(np.full(count, pixel), np.arange(count))
    return sampler.get(keys, dim, 2)


@pytest.mark.parametrize("dim", [0, 2, 5, 10])
@pytest.mark.parametrize("pixel", [0, 12345, 999_999])
def test_sobol_prefixes_are_nets(dim, pixel):
    # A (0, 2)-sequence: the first 2^k points put exactly one point in every elementary
    # interval of area 2^-k, [i / 2^a, (i + 1) / 2^a) x [j / 2^b, (j + 1) / 2^b), a + b = k.
    points = pixel_points("sobol", 256, dim, pixel)
    for k in range(2, 9):
        first = points[: 1 << k]
        for a in range(k + 1):
            b = k - a
            cells = (np.floor(first[:, 0] * (1 << a)) * (1 << b) + np.floor(first[:, 1] * (1 << b))).astype(
                int
            )
            assert np.bincount(cells, minlength=1 << k).tolist() == [1] * (1 << k), (k, a, b)


@pytest.mark.parametrize("name", ["sobol", "stratified"])
def test_dimensions_after_the_second_bounce_are_independent(name):
    # Only the camera's and the first two bounces' dimensions are spread evenly
    # (PATTERNED_DIMENSIONS); from there on every sampler draws independent numbers.
    from ptlab.samplers import PATTERNED_DIMENSIONS, independent_one, independent_pair

    assert BounceUniforms(make_sampler("sobol"), None, 2).first == PATTERNED_DIMENSIONS
    sampler = make_sampler(name, 3, 16)
    keys = sampler.keys(np.full(16, 9), np.arange(16))
    assert np.array_equal(
        sampler.get(keys, PATTERNED_DIMENSIONS, 2), np.stack(independent_pair(keys, PATTERNED_DIMENSIONS)).T
    )
    assert np.array_equal(
        sampler.get(keys, PATTERNED_DIMENSIONS + 2, 1)[:, 0], independent_one(keys, PATTERNED_DIMENSIONS + 2)
    )
    # while the last pair before them is still stratified: one point per 1/16 strip
    last = sampler.get(keys, PATTERNED_DIMENSIONS - 2, 2)
    assert np.bincount((last[:, 0] * 16).astype(int), minlength=16).max() == 1


def test_sobol_one_dimension_is_stratified():
    sampler = make_sampler("sobol", 3)
    keys = sampler.keys(np.full(64, 77), np.arange(64))
    u = sampler.get(keys, 4, 1)[:, 0]
    for k in range(1, 7):
        assert np.bincount((u[: 1 << k] * (1 << k)).astype(int), minlength=1 << k).max() == 1


def test_sobol_needs_no_spp_and_prefixes_stay_the_same():
    # The values of a sample do not depend on how many samples the render takes.
    sampler = make_sampler("sobol", 5)
    keys = sampler.keys(np.full(40, 3), np.arange(40))
    assert np.array_equal(sampler.get(keys, 9, 2)[:24], sampler.get(keys[:24], 9, 2))


@pytest.mark.parametrize("spp", [16, 24, 25, 7])
def test_stratified_puts_one_point_per_cell(spp):
    # m x n cells (m = floor(sqrt(spp)), n = ceil(spp / m)) hold at most one sample each,
    # all of them when spp = m n; and x (or y) alone has one sample per 1 / (m n).
    m = int(np.sqrt(spp))
    n = -(-spp // m)
    for dim in (0, 6):
        points = pixel_points("stratified", spp, dim, spp=spp)
        cells = (np.floor(points[:, 0] * m) + m * np.floor(points[:, 1] * n)).astype(int)
        assert np.bincount(cells, minlength=m * n).max() == 1
        for axis in (0, 1):
            assert np.bincount((points[:, axis] * m * n).astype(int), minlength=m * n).max() == 1


def test_stratified_one_dimension_is_stratified():
    sampler = make_sampler("stratified", 1, 24)
    keys = sampler.keys(np.full(24, 5), np.arange(24))
    u = sampler.get(keys, 4, 1)[:, 0]
    assert np.bincount((u * 24).astype(int), minlength=24).tolist() == [1] * 24


@pytest.mark.parametrize("name", SAMPLERS)
def test_values_are_uniform_floats_in_the_unit_interval(name):
    sampler = make_sampler(name, 0, 16)
    pixel = np.repeat(np.arange(4096), 16)
    keys = sampler.keys(pixel, np.tile(np.arange(16), 4096))
    for dim, count in ((0, 2), (3, 1), (17, 2)):
        u = sampler.get(keys, dim, count)
        assert u.dtype == np.float32
        assert u.shape == (len(keys), count)
        assert (u >= 0).all()
        assert (u < 1).all()
        # 65536 values: the mean of U(0, 1) has standard error 0.0011; 5 SE is a false
        # alarm once in 1.7 million.
        assert abs(u.mean() - 0.5) < 5 * np.sqrt(1 / 12 / u.size)


@pytest.mark.parametrize("name", SAMPLERS)
def test_no_correlation_between_pixels_or_dimensions(name):
    # 10^5 pixels, sample 3 of each: the correlation of a pair's first coordinate between
    # neighbouring pixels, and between dimensions of one pixel, has standard deviation
    # 1 / sqrt(10^5) = 0.0032 if there is none; the bound 5 / sqrt(N) is a false alarm once
    # in 1.7 million per coefficient (14 coefficients here).
    count = 100_000
    sampler = make_sampler(name, 11, 16)
    pixel = np.arange(count + 1)
    keys = sampler.keys(pixel, np.full(count + 1, 3))
    bound = 5 / np.sqrt(count)
    for dim in (0, 2, 7):
        u = sampler.get(keys, dim, 2)
        assert abs(np.corrcoef(u[:-1, 0], u[1:, 0])[0, 1]) < bound  # pixel p vs p + 1
        assert abs(np.corrcoef(u[:-1, 0], u[:-1, 1])[0, 1]) < bound  # within a pair
    dims = [BounceUniforms(sampler, keys, depth) for depth in range(3)]
    first = [d.light()[:, 0] for d in dims] + [d.roulette() for d in dims] + [d.bsdf()[:, 0] for d in dims]
    for i, j in [(0, 3), (0, 6), (3, 6), (1, 4), (2, 8), (4, 7), (6, 7), (0, 1)]:
        assert abs(np.corrcoef(first[i], first[j])[0, 1]) < bound, (i, j)


@pytest.mark.parametrize("name", SAMPLERS)
def test_dimensions_of_a_sample_are_independent(name):
    # Not only uncorrelated: P(u_a < 0.3, u_b < 0.6, u_c < 0.2) = 0.036 for dimensions of three
    # different pairs (camera, light, BSDF) of one sample. Over 4 x 10^5 samples the estimate
    # has standard error 0.0003; 5 SE is a false alarm once in 1.7 million.
    sampler = make_sampler(name, 2, 16)
    pixel = np.repeat(np.arange(25_000), 16)
    keys = sampler.keys(pixel, np.tile(np.arange(16), 25_000))
    bounce = BounceUniforms(sampler, keys, 1)
    camera = sampler.get(keys, BounceUniforms.PIXEL, 2)
    hits = (camera[:, 1] < 0.3) & (bounce.light()[:, 0] < 0.6) & (bounce.bsdf()[:, 1] < 0.2)
    assert abs(hits.mean() - 0.036) < 5 * np.sqrt(0.036 * 0.964 / len(keys))


@pytest.mark.parametrize("name", SAMPLERS)
def test_seeds_give_other_patterns(name):
    a = pixel_points(name, 16, 2, seed=0)
    b = pixel_points(name, 16, 2, seed=1)
    assert not np.allclose(a, b)


def test_the_largest_uniform_is_the_float_just_below_one():
    assert ONE_MINUS_EPSILON.dtype == np.float32
    assert ONE_MINUS_EPSILON == 1 - 2**-24
    assert np.nextafter(ONE_MINUS_EPSILON, np.float32(2)) == 1  # nothing in between
    assert largest_below_one(np.float64) == 1 - 2**-53


def test_unknown_sampler_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown sampler 'halton'"):
        make_sampler("halton")
    from ptlab.errors import PtlabError

    with pytest.raises(PtlabError, match="sampler 'halton'"):
        ptlab.render("cornell-box", spp=1, res=8, sampler="halton")


def _image(sampler: str, **options) -> np.ndarray:
    defaults = dict(spp=24, res=(40, 24), seed=3, workers=1, sampler=sampler)
    return render_result("cornell-box", **dict(defaults, **options)).image


@pytest.mark.subprocess
@pytest.mark.parametrize("name", SAMPLERS)
def test_image_does_not_depend_on_workers_tiles_or_pass_size(name):
    reference = _image(name)
    assert np.array_equal(reference, _image(name, workers=2))
    assert np.array_equal(reference, _image(name, tile_size=16))
    assert np.array_equal(reference, _image(name, tile_size=32, workers=2))


@pytest.mark.parametrize("name", SAMPLERS)
def test_resume_gives_the_straight_image(name, tmp_path):
    checkpoint = tmp_path / "render.npz"
    stopped = iter([False, False, True])
    first = render_result(
        "cornell-box",
        spp=48,
        res=(40, 24),
        seed=2,
        workers=1,
        sampler=name,
        tile_size=16,
        spp_per_pass=8,
        checkpoint=checkpoint,
        stop=lambda: next(stopped, True),
    )
    assert not first.complete
    resumed = render_result(
        "cornell-box",
        spp=48,
        res=(40, 24),
        seed=2,
        workers=1,
        sampler=name,
        tile_size=16,
        spp_per_pass=8,
        resume=checkpoint,
    )
    straight = render_result(
        "cornell-box", spp=48, res=(40, 24), seed=2, workers=1, sampler=name, tile_size=16, spp_per_pass=8
    )
    assert resumed.complete
    assert np.array_equal(resumed.image, straight.image)


def test_a_sobol_render_resumes_to_more_samples(tmp_path):
    checkpoint = tmp_path / "render.npz"
    options = dict(res=(24, 16), seed=4, workers=1, sampler="sobol", spp_per_pass=8)
    render_result("cornell-box", spp=16, checkpoint=checkpoint, **options)
    more = render_result("cornell-box", spp=32, resume=checkpoint, **options)
    assert np.array_equal(more.image, render_result("cornell-box", spp=32, **options).image)


def test_a_stratified_render_cannot_resume_to_more_samples(tmp_path):
    from ptlab.errors import PtlabError

    checkpoint = tmp_path / "render.npz"
    options = dict(res=(24, 16), seed=4, workers=1, sampler="stratified", spp_per_pass=8)
    render_result("cornell-box", spp=16, checkpoint=checkpoint, **options)
    with pytest.raises(PtlabError, match="sampler"):
        render_result("cornell-box", spp=32, resume=checkpoint, **options)


@pytest.mark.parametrize("name", ["sobol", "stratified"])
def test_every_sampler_gives_the_cornell_image(name):
    # The same expected image as independent sampling, at 24 spp (not a power of two). Each
    # pixel has its own pattern, so the per-pixel differences of the two renders are
    # independent, with mean 0 if both are unbiased: their mean over the 4096 pixels is off by
    # more than 5 standard errors once in 1.7 million per channel.
    options = dict(spp=24, res=64, seed=3, workers=1)
    difference = (
        ptlab.render("cornell-box", sampler=name, **options).astype(np.float64)
        - ptlab.render("cornell-box", sampler="independent", **options)
    ).reshape(-1, 3)
    standard_error = difference.std(axis=0, ddof=1) / np.sqrt(len(difference))
    assert (np.abs(difference.mean(axis=0)) < 5 * standard_error).all(), (
        difference.mean(axis=0),
        standard_error,
    )


@pytest.mark.parametrize("name", SAMPLERS)
@pytest.mark.parametrize("layout", ["runs", "shuffled"])
def test_a_dimension_per_row_gives_each_row_what_its_own_dimension_would(name, layout):
    # A batch kept full holds paths at several depths, each asking for its own dimension:
    # in runs (paths that entered together stay together) or, in general, in any order.
    sampler = make_sampler(name, seed=5, spp=16)
    rows = 3000
    keys = sampler.keys(np.arange(rows) % 97, np.arange(rows) // 97)
    depth = np.repeat([9, 4, 2, 1, 0], rows // 5)
    if layout == "shuffled":
        depth = np.random.default_rng(0).permutation(depth)
    for count, offset in ((2, 0), (1, 2), (2, 3)):  # light, roulette, bsdf
        dims = 2 + BounceUniforms.PER_BOUNCE * depth + offset
        got = sampler.get(keys, dims, count)
        for d in np.unique(depth):
            mine = depth == d
            expected = sampler.get(keys[mine], int(2 + BounceUniforms.PER_BOUNCE * d + offset), count)
            np.testing.assert_array_equal(got[mine], expected)
