"""Point lights and the sky in renders: known answers with every integrator and strategy.

* A point light over a diffuse plane: the irradiance is E = I cos(theta) / r^2, so a
  Lambertian plane of albedo a shows (a / pi) I cos(theta) / r^2 (pbrt-v4 section 12.2).
  One light is found without noise, so the render matches that per pixel.
* The sky furnace: a white (albedo 1) diffuse sphere under a constant sky of radiance L
  reflects L in every direction, so the whole image is L in expectation. The sphere is
  convex, so every path leaves it after one bounce and every estimate is bounded (finite
  variance): a z-test of the image's mean is then valid.

Statistical tests use fixed seeds and say their false-alarm rate.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import ptlab
from ptlab.camera import Camera
from ptlab.lights import PointLights, Sky
from ptlab.materials import Diffuse
from ptlab.samplers import SAMPLERS

ALBEDO = np.array([0.5, 0.4, 0.3])
HEIGHT = 2.0
RES = 32


def plane_scene(point_lights=None, sky=None) -> ptlab.Scene:
    """A big diffuse plane y = 0, seen from (0, 6, 0) looking straight down."""
    corners = np.array([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], dtype=float)
    triangles = corners[np.array([[0, 2, 1], [0, 3, 2]])]
    camera = Camera.look_at((0, 6, 0), (0, 0, 0), up=(0, 0, 1), fov_y=60)
    return ptlab.Scene(
        triangles,
        np.zeros(2, np.intp),
        [Diffuse(ALBEDO)],
        camera,
        name="plane",
        point_lights=point_lights,
        sky=sky,
    )


def analytic_plane(intensity, position=(0.0, HEIGHT, 0.0), sub: int = 8) -> np.ndarray:
    """(RES, RES, 3) the plane's radiance (a / pi) I cos(theta) / r^2, averaged over each
    pixel (a grid of sub x sub points in it), as a render's pixels are."""
    camera = plane_scene().camera
    scale = math.tan(math.radians(camera.fov_y) / 2)
    j, i = (np.mgrid[0 : RES * sub, 0 : RES * sub] + 0.5) / sub
    x, y = (2 * i / RES - 1) * scale, (1 - 2 * j / RES) * scale
    d = camera.forward + x[..., None] * camera.right + y[..., None] * camera.up
    p = camera.position + d * (camera.position[1] / -d[..., 1:2])  # where it meets y = 0
    to_light = np.asarray(position) - p
    r2 = np.sum(to_light**2, axis=-1, keepdims=True)
    cos_theta = to_light[..., 1:2] / np.sqrt(r2)
    radiance = ALBEDO / math.pi * np.asarray(intensity) * cos_theta / r2
    return radiance.reshape(RES, sub, RES, sub, 3).mean(axis=(1, 3))


ONE_LIGHT = ([[0.0, HEIGHT, 0.0]], [[10.0, 20.0, 30.0]])


@pytest.mark.parametrize(
    ("integrator", "strategy", "backend"),
    [
        ("path", "nee", "embree"),
        ("path", "mis", "embree"),
        ("path", "bsdf", "embree"),
        ("whitted", "nee", "embree"),
        ("path", "nee", "numpy"),
    ],
)
def test_a_point_light_over_a_diffuse_plane_gives_i_cos_over_r_squared(integrator, strategy, backend):
    # Direct light only (max_depth 1): the plane cannot light itself anyway. Even "bsdf"
    # samples the point light, which no sampled direction can hit. The light is found
    # without noise; only the pixel's average over its area differs between the render's
    # 64 camera samples and the analytic sub-grid (up to 0.2% where the light is close).
    image = ptlab.render(
        plane_scene(PointLights(*ONE_LIGHT)),
        spp=64,
        res=RES,
        max_depth=1,
        integrator=integrator,
        strategy=strategy,
        backend=backend,
        workers=1,
    )
    expected = analytic_plane(ONE_LIGHT[1][0])
    np.testing.assert_allclose(image, expected, rtol=4e-3)
    assert abs((image / expected - 1).mean()) < 1e-4


def z_score(image: np.ndarray, expected: np.ndarray) -> float:
    """The mean difference over pixels in standard errors (pixels are independent samples;
    the standard error is at least float32's rounding, 1e-6, for images without noise)."""
    difference = (image - expected).ravel()
    standard_error = difference.std(ddof=1) / math.sqrt(difference.size)
    return float(difference.mean() / max(standard_error, 1e-6))


@pytest.mark.parametrize(
    ("integrator", "strategy"), [("path", "nee"), ("path", "mis"), ("path", "bsdf"), ("whitted", "nee")]
)
def test_two_point_lights_and_a_sky_add_up(integrator, strategy):
    # Light sampling picks one of the two point lights (by power, 3 : 2) or the sky (1/2)
    # per sample; the expected image is the sum of each point light alone (rendered with the
    # same camera samples: no noise) and, for the path tracer, a L_sky from the sky (a plane
    # sees half the sky: E = pi L). Whitted's sky lights nothing. |z| < 4.5 for each of the
    # 4 cases: false-alarm rate 3e-5.
    lights = [([[0.0, HEIGHT, 0.0]], [[10.0, 20.0, 30.0]]), ([[1.5, 3.0, -1.0]], [[40.0, 0.0, 0.0]])]
    sky = np.array([0.3, 0.2, 0.1])
    options = dict(
        spp=16,
        res=RES,
        max_depth=1,
        integrator=integrator,
        strategy=strategy,
        workers=1,
        sampler="independent",
    )
    alone = sum(ptlab.render(plane_scene(PointLights(*light)), **options) for light in lights)
    both = PointLights(np.concatenate([p for p, _ in lights]), np.concatenate([i for _, i in lights]))
    image = ptlab.render(plane_scene(both, Sky(sky)), **options)
    expected = alone + (ALBEDO * sky if integrator == "path" else 0)
    for channel in range(3):
        assert abs(z_score(image[..., channel], expected[..., channel])) < 4.5, channel
    assert np.abs(image.mean(axis=(0, 1)) / expected.mean(axis=(0, 1)) - 1).max() < 0.03


def sky_furnace(radiance: float) -> ptlab.Scene:
    """A white diffuse sphere, seen whole from outside, under a constant sky."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    triangles = sphere.vertices[sphere.faces]
    camera = Camera.look_at((0.3, 0.5, -3.0), (0, 0, 0), fov_y=50)
    return ptlab.Scene(
        triangles,
        np.zeros(len(triangles), np.intp),
        [Diffuse([1.0, 1.0, 1.0])],
        camera,
        name="sky-furnace",
        sky=Sky([radiance] * 3),
    )


@pytest.mark.parametrize("sampler", SAMPLERS)
@pytest.mark.parametrize("strategy", ["nee", "mis", "bsdf"])
def test_sky_furnace_a_white_sphere_under_the_sky_is_the_sky(strategy, sampler):
    # The sphere fills about 40% of the image; the other pixels see the sky itself. The mean
    # over the sphere's pixels is a z-test at |z| < 4.5 (9 cases: false-alarm rate 6e-5),
    # and within 2% of L (a wrong pdf or weight is off by far more).
    radiance = 0.7
    options = dict(spp=16, res=RES, sampler=sampler, workers=1)
    image = ptlab.render(sky_furnace(radiance), strategy=strategy, **options)
    # The same camera samples, in the depth view: pixels none of whose samples hit are 0.
    on_sphere = ptlab.render(sky_furnace(radiance), integrator="depth", **options)[..., 0] > 0
    assert 0.3 < on_sphere.mean() < 0.6
    assert abs(z_score(image[on_sphere], radiance)) < 4.5
    assert abs(image[on_sphere].mean() / radiance - 1) < 0.02
    np.testing.assert_allclose(image[~on_sphere], radiance, rtol=1e-6)


def test_sky_furnace_is_exact_with_cosine_bsdf_sampling():
    # Cosine sampling weighs each bounce by the albedo (1), and every path escapes to the
    # sky after one bounce: every sample is L, no noise at all.
    image = ptlab.render(sky_furnace(0.7), spp=4, res=RES, strategy="bsdf", workers=1)
    np.testing.assert_allclose(image, 0.7, rtol=1e-5)


def test_whitted_sees_the_sky_but_is_not_lit_by_it():
    # Camera rays that miss the sphere see the sky; the diffuse sphere, which Whitted lights
    # by light sampling only and whose light here is all the sky's, stays black. The albedo
    # view (1 per sample on the white sphere, 0 off it) has the same camera samples, so each
    # pixel is L times the share of its samples that miss.
    options = dict(spp=4, res=RES, workers=1)
    image = ptlab.render(sky_furnace(0.7), integrator="whitted", **options)
    covered = ptlab.render(sky_furnace(0.7), integrator="albedo", **options)
    np.testing.assert_allclose(image, 0.7 * (1 - covered), atol=1e-6)
    assert (covered == 1).any()
    assert (covered == 0).any()


def test_every_strategy_agrees_under_an_area_light_a_point_light_and_the_sky():
    # A square lamp facing down over the plane, a point light and the sky: light sampling
    # picks among all three (the lamp's MIS pdf then carries its share), BSDF sampling finds
    # the lamp and the sky, MIS both. Direct light only. Each pair of strategies must agree
    # on the image's mean, per channel, |z| < 4.5 (9 tests: false-alarm rate 6e-5).
    lamp = np.array([[-0.5, 1.5, -0.5], [0.5, 1.5, -0.5], [0.5, 1.5, 0.5], [-0.5, 1.5, 0.5]])
    plane = plane_scene()
    triangles = np.concatenate([plane.triangles, lamp[np.array([[0, 1, 2], [0, 2, 3]])]])
    point_lights, sky = PointLights([[1.5, 2.0, 0.0]], [[10.0, 20.0, 30.0]]), Sky([0.3, 0.2, 0.1])
    scene = ptlab.Scene(
        triangles,
        np.array([0, 0, 1, 1]),
        [Diffuse(ALBEDO), Diffuse([0, 0, 0], emission=[5.0, 4.0, 3.0])],
        plane.camera,
        name="lamp-point-sky",
        point_lights=point_lights,
        sky=sky,
    )
    assert scene.area_lights.normals[0, 1] == -1  # the lamp shines down
    # The scene keeps the lights it was given; the light sampler picks the sky half the time.
    assert scene.point_lights is point_lights
    assert scene.sky is sky
    assert scene.light_sampler.pmf[scene.light_sampler.kinds.index(scene.light_sampler.sky)] == 0.5
    images = {
        strategy: ptlab.render(
            scene, spp=64, res=RES, max_depth=1, strategy=strategy, sampler="independent", seed=3, workers=1
        )
        for strategy in ("nee", "bsdf", "mis")
    }
    for a, b in (("nee", "bsdf"), ("nee", "mis"), ("bsdf", "mis")):
        for channel in range(3):
            z = z_score(images[a][..., channel], images[b][..., channel])
            assert abs(z) < 4.5, (a, b, channel, z)
