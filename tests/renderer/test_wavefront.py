"""The wavefront toolkit (``ptlab.integrators.wavefront``): the film's sums per pixel (NaN and
infinite samples left out and counted) and new rays leaving a surface. (Its use by the
integrators: ``renderer/test_path.py``, ``renderer/test_whitted.py``.)
"""

from __future__ import annotations

import numpy as np
import pytest

from ptlab.integrators.wavefront import Paths, add_to_film, counting_nonfinite, leave_surface

# -- new paths -----------------------------------------------------------------------------


def test_camera_paths_start_at_depth_0_with_throughput_1_and_see_emission():
    origins = np.zeros((5, 3), np.float32)
    dirs = np.tile(np.array([[0, 0, 1]], np.float32), (5, 1))
    pixel, keys = np.arange(10, 15), np.arange(5, dtype=np.uint64) * 7
    paths = Paths.camera(origins, dirs, pixel, keys)
    assert paths.origins is origins
    assert paths.dirs is dirs
    assert paths.pixel is pixel
    assert paths.sample is keys
    assert paths.throughput.shape == (5, 3)
    assert paths.throughput.dtype == np.float32
    assert (paths.throughput == 1).all()
    assert paths.sees_emission.all()
    assert paths.depths().tolist() == [0] * 5
    assert paths.pdf is None


# -- the film ------------------------------------------------------------------------------


def test_the_film_adds_every_contribution_to_its_pixel_in_float64():
    rng = np.random.default_rng(1)
    pixel = rng.integers(0, 7, size=1000)
    radiance = rng.random((1000, 3)).astype(np.float32)
    film = np.full((7, 3), 0.5)
    add_to_film(film, pixel, radiance)
    expected = np.full((7, 3), 0.5)
    np.add.at(expected, pixel, radiance.astype(np.float64))
    assert film.dtype == np.float64
    np.testing.assert_allclose(film, expected, rtol=1e-12)


@pytest.mark.parametrize(
    "rows",
    [
        np.arange(0, 3000, 2),  # a batch's paths, each its own row, in order: added in place
        np.arange(1500)[::-1] * 2,  # the same rows in another order
        np.arange(1500) % 700,  # repeated rows, many of them: bincount
        np.array([5, 5, 3, 5]),  # repeated rows, few of them in a large film: add.at
    ],
)
def test_the_film_adds_each_row_whatever_their_order_and_repeats(rows):
    radiance = np.asfortranarray(np.random.default_rng(3).random((len(rows), 3)).astype(np.float32))
    for order in ("F", "C"):  # (a render's per-path film, and a student's np.zeros)
        film = np.zeros((3000, 3), order=order)
        add_to_film(film, rows, radiance)
        expected = np.zeros((3000, 3))
        np.add.at(expected, rows, radiance.astype(np.float64))
        np.testing.assert_allclose(film, expected, rtol=1e-12)


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")
def test_a_nan_or_infinite_sample_is_left_out_and_counted_and_the_rest_of_its_pixel_kept():
    film = np.zeros((3, 3))
    radiance = np.array([[1, 1, 1], [np.nan, 0, 0], [2, 2, 2], [np.inf, 1, 1], [3, 3, 3]], np.float32)
    with counting_nonfinite() as nonfinite:
        add_to_film(film, np.array([0, 0, 1, 1, 2]), radiance)
        add_to_film(film, np.array([2]), np.array([[0, -np.inf, 0]], np.float32))
    np.testing.assert_array_equal(film, [[1, 1, 1], [2, 2, 2], [3, 3, 3]])
    assert (nonfinite.count, nonfinite.first_row, nonfinite.first_depth) == (3, 0, 0)
    # The depth where the caller says it, one for all or per row.
    with counting_nonfinite() as nonfinite:
        add_to_film(np.zeros((3, 3)), np.array([0, 1, 2]), radiance[2:], depth=np.array([4, 7, 5]))
    assert (nonfinite.count, nonfinite.first_row, nonfinite.first_depth) == (1, 1, 7)
    # Outside a count, a warning says so: never silently.
    with pytest.warns(RuntimeWarning, match="1 samples were NaN or infinite"):
        add_to_film(film, np.array([1]), np.array([[np.nan, 0, 0]], np.float32))
    np.testing.assert_array_equal(film, [[1, 1, 1], [2, 2, 2], [3, 3, 3]])


# -- leaving a surface -----------------------------------------------------------------------


def test_a_new_ray_starts_offset_along_the_normal_on_the_side_it_goes_to():
    rng = np.random.default_rng(2)
    n = rng.normal(size=(1000, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    wi = rng.normal(size=(1000, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wi[:10] -= (wi[:10] * n[:10]).sum(axis=1, keepdims=True) * n[:10]  # tangent: counts as above
    p = rng.normal(size=(1000, 3))
    offset = rng.uniform(1e-4, 1e-2, size=1000)
    moved = leave_surface(p, n, offset, wi) - p
    side = np.where((wi * n).sum(axis=1) >= 0, 1.0, -1.0)
    np.testing.assert_allclose(moved, (side * offset)[:, None] * n, rtol=1e-12, atol=1e-15)
