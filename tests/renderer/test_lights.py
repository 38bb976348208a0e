"""Lights: triangles picked in proportion to power (area x mean Le), points uniform on them;
point lights picked by power; the sky's directions; the choice between kinds of light."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from ptlab.lights import (
    SKY_SHARE,
    AreaLights,
    LightPoint,
    LightSampler,
    PointLights,
    Sky,
    build_lights,
    light_shares,
    triangle_areas,
    triangle_normals,
)

N = 100_000


def two_lights() -> AreaLights:
    # A unit right triangle (area 1/2) and one three times larger, facing +z and -z.
    v0 = np.array([[0.0, 0, 0], [5, 0, 0]])
    v1 = np.array([[1.0, 0, 0], [5, 3, 0]])
    v2 = np.array([[0.0, 1, 0], [6, 0, 0]])
    return AreaLights(v0, v1, v2, radiance=np.array([[1.0, 1, 1], [2, 2, 2]]), offset=np.zeros(2))


def test_triangle_areas_and_normals():
    triangles = np.array(
        [
            [[0.0, 0, 0], [1, 0, 0], [0, 1, 0]],  # area 1/2, facing +z
            [[5.0, 0, 0], [5, 3, 0], [6, 0, 0]],  # area 3/2, facing -z
            [[0.0, 0, 0], [1, 1, 1], [2, 2, 2]],
        ]
    )  # on a line: area 0
    np.testing.assert_array_equal(triangle_areas(triangles), [0.5, 1.5, 0.0])
    with np.errstate(invalid="ignore"):
        normals = triangle_normals(triangles)
    np.testing.assert_array_equal(normals[:2], [[0, 0, 1], [0, 0, -1]])
    assert np.isnan(normals[2]).all()


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
    lights = AreaLights(
        *(
            np.array(v, dtype=float)
            for v in ([[0, 0, 0], [5, 0, 0]], [[1, 0, 0], [5, 3, 0]], [[0, 1, 0], [6, 0, 0]])
        ),
        radiance=np.full((2, 3), 7.0),
        offset=np.zeros(2),
    )
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


@pytest.mark.parametrize("count", [5, 40])  # few lights: counting; many: binary search
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
    assert stats.chi2.sf(statistic, df=count - 1) > 1e-3  # false-alarm rate 0.1%


# -- point lights, the sky, and the choice between kinds of light ----------------------------


def test_point_lights_are_picked_by_power_and_fall_off_as_the_square_of_distance():
    positions = np.array([[0.0, 2, 0], [3, 4, 0]])
    intensity = np.array([[10.0, 20, 30], [40, 0, 0]])  # mean 20 and 13.3: power 3 : 2
    lights = PointLights(positions, intensity)
    assert lights.power == pytest.approx(4 * np.pi * (20 + 40 / 3))
    np.testing.assert_allclose(lights.probability, [0.6, 0.4], rtol=1e-6)
    p = np.zeros((N, 3), np.float32)
    sample = lights.sample_li(p, np.random.default_rng(1).random((N, 2)).astype(np.float32))
    first = sample.target[:, 1] == 2
    counts = [np.count_nonzero(first), np.count_nonzero(~first)]
    statistic = sum((c - e) ** 2 / e for c, e in zip(counts, [0.6 * N, 0.4 * N], strict=True))
    assert stats.chi2.sf(statistic, df=1) > 1e-3, counts  # false-alarm rate 0.1%
    np.testing.assert_allclose(sample.radiance[first][0], np.array([10, 20, 30]) / 4, rtol=1e-6)
    np.testing.assert_allclose(sample.radiance[~first][0], np.array([40, 0, 0]) / 25, rtol=1e-6)
    np.testing.assert_allclose(sample.wi[~first][0], [0.6, 0.8, 0], rtol=1e-6)
    np.testing.assert_allclose(sample.pdf, np.where(first, 0.6, 0.4), rtol=1e-6)
    # No ray finds a point light: to MIS, its density is 0 (a delta light).
    assert lights.is_delta
    assert not lights.pdf_li(LightPoint(sample.radiance)).any()


@pytest.mark.parametrize("intensity", [[[-1.0, 1, 1]], [[0.0, 0, 0]]])
def test_a_point_light_needs_an_intensity_that_shines(intensity):
    with pytest.raises(ValueError, match="intensity"):
        PointLights([[0.0, 0, 0]], intensity)


def test_the_sky_is_sampled_uniformly_on_the_sphere():
    sky = Sky([0.2, 0.4, 0.6], distance=10.0)
    p = np.ones((N, 3), np.float32)
    sample = sky.sample_li(p, np.random.default_rng(2).random((N, 2)).astype(np.float32))
    np.testing.assert_allclose(np.linalg.norm(sample.wi, axis=1), 1, rtol=1e-5)
    # Uniform on the sphere: each coordinate has mean 0 and variance 1/3 (sd of the mean
    # 0.0018 with 1e5 samples; 5 sd: false-alarm rate below 1e-5).
    np.testing.assert_allclose(sample.wi.mean(axis=0), 0, atol=0.01)
    np.testing.assert_allclose((sample.wi**2).mean(axis=0), 1 / 3, atol=0.01)
    np.testing.assert_allclose(sample.pdf, 1 / (4 * np.pi), rtol=1e-6)
    np.testing.assert_array_equal(sky.pdf_li(LightPoint(sample.radiance)), sample.pdf)
    np.testing.assert_allclose(sample.radiance, np.broadcast_to([0.2, 0.4, 0.6], (N, 3)), rtol=1e-6)
    np.testing.assert_allclose(sample.target, p + 10 * sample.wi, rtol=1e-5)


def test_light_shares_by_power_with_half_for_the_sky():
    assert light_shares(5.0, 0.0, sky=False) == (1.0, 0.0, 0.0)  # exactly: same numbers
    assert light_shares(0.0, 0.0, sky=True) == (0.0, 0.0, 1.0)
    assert light_shares(0.0, 7.0, sky=False) == (0.0, 1.0, 0.0)
    area, points, sky = light_shares(1.0, 3.0, sky=True)
    assert (area, points, sky) == pytest.approx((SKY_SHARE * 0.25, SKY_SHARE * 0.75, SKY_SHARE))


def test_area_power_is_pi_area_radiance_and_pdf_li_is_sample_lis_density():
    lights = two_lights()
    assert lights.power == pytest.approx(np.pi * 3.5)
    np.testing.assert_allclose(lights.pdf_area(lights.radiance), [1 / 3.5, 2 / 3.5], rtol=1e-6)
    # pdf_li of the points that sample_li picked, seen from where they were picked, is the
    # density sample_li gave them (the MIS weights of emission rely on it).
    rng = np.random.default_rng(4)
    p = rng.uniform(-2, 8, size=(1000, 3)).astype(np.float32)
    sample = lights.sample_li(p, rng.random((1000, 2)).astype(np.float32))
    front = sample.pdf > 0
    assert 0 < front.mean() < 1  # some points see a light from behind: pdf 0
    # two_lights' offsets are 0, so the targets are the points; the first light (Le 1) faces +z,
    # the second (Le 2) -z.
    normal_z = np.where(sample.radiance[:, 0] == 2, -1.0, 1.0)
    lit = sample.radiance[front]
    to_light = (sample.target - p)[front]
    found = LightPoint(
        radiance=lit,
        dist2=(to_light**2).sum(axis=1),
        cos_theta_light=-normal_z[front] * sample.wi[front, 2],
    )
    np.testing.assert_allclose(lights.pdf_li(found), sample.pdf[front], rtol=1e-5)


def test_the_light_sampler_picks_only_the_sampled_kinds_and_keeps_u_stratified():
    kinds = [two_lights(), PointLights([[0.0, 1, 0]], [[1.0, 1, 1]]), Sky([1.0, 1, 1])]
    sampler = LightSampler(kinds, shares=(0.2, 0.3, 0.5))
    u = np.stack([(np.arange(1000) + 0.5) / 1000, np.full(1000, 0.25)]).T.astype(np.float32)
    kind, stretched = sampler.pick(u, np.array([True, True, True]))
    assert np.bincount(kind).tolist() == [200, 300, 500]
    # Each kind's part of an evenly spaced u is stretched back to evenly spaced in [0, 1).
    for k, count in enumerate((200, 300, 500)):
        np.testing.assert_allclose(
            np.sort(stretched[kind == k, 0]), (np.arange(count) + 0.5) / count, atol=1e-4
        )
    np.testing.assert_array_equal(stretched[:, 1], u[:, 1])
    kind, stretched = sampler.pick(u, np.array([True, True, False]))
    assert np.bincount(kind).tolist() == [400, 600]
    np.testing.assert_allclose(sampler.pmf_among(np.array([True, True, False])), [0.4, 0.6, 0])
    assert (stretched[:, 0] < 1).all()
    assert (stretched[:, 0] >= 0).all()
    # One kind to pick: u is left as it was.
    kind, stretched = sampler.pick(u, np.array([False, True, False]))
    assert (kind == 1).all()
    assert stretched is u


def test_the_light_sampler_takes_one_share_per_light_and_finds_each_kind():
    area, sky = two_lights(), Sky([1.0, 1, 1])
    sampler = LightSampler([sky, area], shares=(0.25, 0.75))
    assert sampler.kinds == [sky, area]
    assert (sampler.area_lights, sampler.point_lights, sampler.sky) == (area, None, sky)
    np.testing.assert_array_equal(sampler.is_delta, [False, False])
    assert LightSampler([area]).pmf.tolist() == [1.0]  # one light: always picked
    with pytest.raises(ValueError, match="2 shares for 3 kinds"):
        LightSampler([area, PointLights([[0.0, 1, 0]], [[1.0, 1, 1]]), sky], shares=(0.5, 0.5))
    with pytest.raises(TypeError):  # the shares are named, never taken for a light
        LightSampler([area], (1.0,))


def test_a_light_samples_density_is_the_kinds_probability_times_its_own():
    kinds = [two_lights(), PointLights([[0.0, 1, 0]], [[1.0, 1, 1]]), Sky([1.0, 1, 1])]
    sampler = LightSampler(kinds, shares=(0.2, 0.3, 0.5))
    rng = np.random.default_rng(5)
    p = rng.uniform(-1, 1, size=(3000, 3)).astype(np.float32)
    u = rng.random((3000, 2)).astype(np.float32)
    sampled = np.array([True, True, False])  # (the sky left to BSDF sampling)
    sample, kind = sampler.sample_li(p, u, sampled)
    assert set(kind.tolist()) == {0, 1}
    point = kind == 1
    np.testing.assert_allclose(sample.pdf[point], 0.6, rtol=1e-6)  # one point light: 0.6 x 1
    area = (kind == 0) & (sample.pdf > 0)
    own = kinds[0].sample_li(p, sampler.pick(u, sampled)[1]).pdf
    np.testing.assert_allclose(sample.pdf[area], 0.4 * own[area], rtol=1e-6)
    found = LightPoint(sample.radiance[:5])
    np.testing.assert_array_equal(sampler.pdf_li(kinds[2], found, sampled), 0)  # not sampled
    np.testing.assert_allclose(sampler.pdf_li(kinds[2], found, np.ones(3, bool)), 0.5 / (4 * np.pi))


def test_build_lights_shares_the_samples_and_leaves_the_given_lights_as_they_are():
    # Two emissive triangles (power pi x 3.5, as two_lights) and one of zero area, which is no
    # light; a point light and the sky.
    area = two_lights()
    triangles = np.stack([area.v0, area.v0 + area.e1, area.v0 + area.e2], axis=1).astype(float)
    triangles = np.concatenate([triangles, [[[0.0, 0, 0], [1, 1, 1], [2, 2, 2]]]])
    radiance = np.array([[1, 1, 1], [2, 2, 2], [9, 9, 9]], dtype=np.float32)
    points, sky = PointLights([[0.0, 1, 0]], [[1.0, 2, 3]]), Sky([1.0, 1, 1])
    sampler = build_lights(triangles, radiance, np.zeros(3), points, sky, sky_distance=7.0)
    assert sampler.kinds == [sampler.area_lights, sampler.point_lights, sampler.sky]
    assert len(sampler.area_lights) == 2
    shares = light_shares(np.pi * 3.5, points.power, sky=True)
    np.testing.assert_allclose(sampler.pmf, shares)
    assert sampler.sky.distance == 7.0
    # The sky given is left as it is: shadow rays toward the one sampled go out of the scene.
    assert sky.distance == 1.0
    assert sampler.sky is not sky
    np.testing.assert_array_equal(sampler.sky.radiance, sky.radiance)
    assert build_lights(triangles[2:], radiance[2:], np.zeros(1)) is None  # no light at all
