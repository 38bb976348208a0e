"""Area lights: triangles picked in proportion to power (area x mean Le), points uniform."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from ptlab.lights import AreaLights

N = 100_000


def two_lights() -> AreaLights:
    # A unit right triangle (area 1/2) and one three times larger, facing +z and -z.
    v0 = np.array([[0.0, 0, 0], [5, 0, 0]])
    v1 = np.array([[1.0, 0, 0], [5, 3, 0]])
    v2 = np.array([[0.0, 1, 0], [6, 0, 0]])
    return AreaLights(v0, v1, v2, radiance=np.array([[1.0, 1, 1], [2, 2, 2]]),
                      offset=np.zeros(2))


def test_total_area_power_pdf_and_normals():
    lights = two_lights()
    assert lights.total_area == 2.0
    assert lights.total_power == 0.5 * 1 + 1.5 * 2
    # pdf_area = mean(Le) / total power: 1 / 3.5 and 2 / 3.5; it integrates to 1 over the lights.
    pdf = lights.pdf_area(lights.radiance)
    np.testing.assert_allclose(pdf, [1 / 3.5, 2 / 3.5], rtol=1e-6)
    assert (pdf * lights.areas).sum() == pytest.approx(1.0)
    np.testing.assert_allclose(lights.normals, [[0, 0, 1], [0, 0, -1]])


def test_equal_lights_are_picked_by_area_as_in_the_homework():
    lights = AreaLights(*(np.array(v, dtype=float) for v in (
        [[0, 0, 0], [5, 0, 0]], [[1, 0, 0], [5, 3, 0]], [[0, 1, 0], [6, 0, 0]])),
        radiance=np.full((2, 3), 7.0), offset=np.zeros(2))
    np.testing.assert_allclose(lights.pdf_area(lights.radiance), 1 / lights.total_area, rtol=1e-6)


def test_triangles_are_chosen_in_proportion_to_their_power():
    lights = two_lights()
    sample = lights.sample(np.random.default_rng(0).random((N, 3)).astype(np.float32))
    on_big = sample.radiance[:, 0] == 2
    np.testing.assert_allclose(sample.pdf_area, np.where(on_big, 2 / 3.5, 1 / 3.5), rtol=1e-6)
    # Chi-square test of the 0.5 : 3 split of power; false-alarm rate 0.1%.
    counts = [np.count_nonzero(~on_big), np.count_nonzero(on_big)]
    expected = [N / 7, 6 * N / 7]
    statistic = sum((c - e) ** 2 / e for c, e in zip(counts, expected, strict=True))
    assert stats.chi2.sf(statistic, df=1) > 1e-3, counts
    # Points are uniform on their triangle: the centroid is the mean.
    np.testing.assert_allclose(sample.points[on_big].mean(axis=0), [16 / 3, 1, 0], atol=0.02)
    np.testing.assert_allclose(sample.points[~on_big].mean(axis=0), [1 / 3, 1 / 3, 0], atol=0.01)


@pytest.mark.parametrize("count", [5, 40])      # few lights: counting; many: binary search
def test_many_lights_are_chosen_in_proportion_to_their_power(count):
    rng = np.random.default_rng(count)
    sizes = rng.uniform(0.5, 3.0, count)
    v0 = np.c_[np.arange(count) * 10.0, np.zeros(count), np.zeros(count)]
    v1, v2 = v0 + np.c_[sizes, 0 * sizes, 0 * sizes], v0 + np.c_[0 * sizes, sizes, 0 * sizes]
    radiance = np.repeat(np.arange(1, count + 1, dtype=float)[:, None], 3, axis=1)
    lights = AreaLights(v0, v1, v2, radiance=radiance, offset=np.zeros(count))
    sample = lights.sample(rng.random((N, 3)).astype(np.float32))
    counts = np.bincount(sample.radiance[:, 0].astype(int) - 1, minlength=count)
    power = lights.areas * radiance[:, 0]
    expected = N * power / power.sum()
    statistic = ((counts - expected) ** 2 / expected).sum()
    assert stats.chi2.sf(statistic, df=count - 1) > 1e-3     # false-alarm rate 0.1%
