"""The path tracer's pieces (``ptlab.integrators.path``): MIS weights, Russian roulette,
leaving a surface, next-event estimation against a closed form, and whole paths in a
furnace. (The integrator end to end, through ``ptlab.render``: ``renderer/test_render.py`` and
``renderer/test_strategies.py``.)

The statistical tests have fixed seeds, so each always passes or always fails. Each compares
a mean of 2^14 or more independent samples of finite variance with its exact value within
5 standard errors: over the choice of seeds, a correct estimator fails one with probability
about 6e-7 (the normal tail beyond 5 sigma).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import closed_sphere_scene

from ptlab.accel import make_accelerator
from ptlab.camera import Camera
from ptlab.integrators.path import PathSettings, direct_light, mis_weight, russian_roulette, trace_paths
from ptlab.integrators.wavefront import Paths, leave_surface, surface_hit
from ptlab.materials import Diffuse
from ptlab.samplers import make_sampler
from ptlab.scene import Scene

#: 5 standard errors: a two-sided false-alarm rate of 5.7e-7 for a mean of many samples.
Z = 5.0


def camera_paths(origins, dirs, seed: int = 0) -> Paths:
    """Paths leaving ``origins`` along ``dirs`` (N, 3) as camera rays do: throughput 1, each
    path a film row of its own, sampler keys of sample 0 of pixels 0..N-1."""
    pixel = np.arange(len(origins))
    keys = make_sampler("independent", seed).keys(pixel, np.zeros(len(pixel), np.intp))
    return Paths.camera(np.asarray(origins, np.float32), np.asarray(dirs, np.float32), pixel, keys)


def floor_under_a_light(light: np.ndarray, radiance: float, albedo: float = 0.5) -> Scene:
    """A grey floor, the square [-5, 5]^2 at y = 0 (normal +y), under one emitting triangle
    ``light`` (3, 3) whose front faces the floor."""
    floor = np.array(
        [[[-5, 0, -5], [5, 0, 5], [5, 0, -5]], [[-5, 0, -5], [-5, 0, 5], [5, 0, 5]]], dtype=float
    )
    materials = [Diffuse([albedo] * 3), Diffuse([0.0] * 3, emission=[radiance] * 3)]
    return Scene(
        triangles=np.concatenate([floor, light[None]]),
        material_ids=[0, 0, 1],
        materials=materials,
        camera=Camera.look_at((0, 3, -3), (0, 0, 0)),
        name="floor",
    )


def vertices_below(scene: Scene, accel, points: np.ndarray, seed: int = 0):
    """The ``SurfaceHit`` of rays shot straight down onto the floor at ``points`` (N, 3)."""
    origins = points + np.array([0.0, 0.5, 0.0])
    dirs = np.tile([0.0, -1.0, 0.0], (len(points), 1))
    paths = camera_paths(origins, dirs, seed)
    return surface_hit(scene, paths, accel.intersect(paths.origins, paths.dirs))


# -- MIS weights -------------------------------------------------------------------------


def test_mis_weights_are_the_power_and_balance_heuristics():
    rng = np.random.default_rng(0)
    p, q = rng.exponential(size=(2, 1000))
    np.testing.assert_allclose(mis_weight(p, q), p**2 / (p**2 + q**2), rtol=1e-12)
    np.testing.assert_allclose(mis_weight(p, q, "balance"), p / (p + q), rtol=1e-12)


@pytest.mark.parametrize("heuristic", ["power", "balance"])
def test_the_two_strategies_weights_add_up_to_one_even_for_extreme_pdfs(heuristic):
    # A sharp lobe's peak and a far, small light give pdfs far apart; float32 as in a render.
    pdfs = np.array([1e-30, 1e-8, 0.5, 1.0, 3.0, 1e8, 1e30], dtype=np.float32)
    p, q = (a.ravel() for a in np.meshgrid(pdfs, pdfs))
    total = mis_weight(p, q, heuristic) + mis_weight(q, p, heuristic)
    np.testing.assert_allclose(total, 1.0, rtol=1e-6)


@pytest.mark.parametrize("heuristic", ["power", "balance"])
def test_a_zero_pdf_weighs_nothing_and_the_other_strategys_zero_pdf_weighs_all(heuristic):
    p = np.array([0.0, 2.0, 0.0, np.inf, 2.0])
    q = np.array([2.0, 0.0, 0.0, 2.0, np.inf])
    weight = mis_weight(p, q, heuristic)
    assert not np.isnan(weight).any()
    np.testing.assert_array_equal(weight, [0.0, 1.0, 0.0, 1.0, 0.0])


# -- Russian roulette ----------------------------------------------------------------------

#: A triangle light over the floor, its front (the order of its vertices) facing down.
LIGHT = np.array([[-0.3, 1.0, -0.2], [0.4, 1.0, -0.3], [0.1, 1.0, 0.5]])


@pytest.fixture(scope="module")
def floor():
    scene = floor_under_a_light(LIGHT, radiance=2.0)
    return scene, make_accelerator(scene.triangles, "embree")


def carrying(floor, throughput):
    """Vertices on the floor, one per row of ``throughput`` (N, 3), that their paths reach
    carrying it."""
    scene, accel = floor
    count = len(throughput)
    points = np.column_stack([np.linspace(-2, 2, count), np.zeros(count), np.full(count, 2.0)])
    hit = vertices_below(scene, accel, points)
    hit.throughput = np.array(throughput, np.float32)
    return hit


@pytest.mark.parametrize("rr", [0.8, 0.3])
def test_fixed_roulette_keeps_a_fraction_p_and_divides_their_throughput_by_p(floor, rr):
    count, colour = 10_000, np.array([0.2, 0.5, 1.0])
    u = ((np.arange(count) + 0.5) / count).astype(np.float32)  # stratified: exact fractions
    hit = carrying(floor, np.tile(colour, (count, 1)))
    survive = russian_roulette(hit, PathSettings(rr=rr), u)
    assert survive.mean() == pytest.approx(rr, abs=1 / count)
    np.testing.assert_allclose(hit.throughput[survive], np.tile(colour / rr, (survive.sum(), 1)), rtol=1e-6)
    # Unbiased: the survivors carry, on average over all the paths, what all of them carried.
    kept = np.where(survive[:, None], hit.throughput, 0).mean(axis=0)
    np.testing.assert_allclose(kept, colour, rtol=2 / count / rr)


def test_throughput_roulette_survives_with_the_largest_channel_at_most_one(floor):
    throughput = np.array([[0.1, 0.25, 0.05], [2.0, 0.1, 0.1], [0.5, 0.5, 0.5]], np.float32)
    hit = carrying(floor, throughput)
    u = np.array([0.24, 0.999, 0.51], np.float32)
    survive = russian_roulette(at_depth(hit, 5), PathSettings(rr="throughput"), u)
    np.testing.assert_array_equal(survive, [True, True, False])
    np.testing.assert_allclose(hit.throughput[0], throughput[0] / 0.25, rtol=1e-6)
    np.testing.assert_array_equal(hit.throughput[1], throughput[1])  # bright: never dies


@pytest.mark.parametrize(("rr", "start"), [(0.1, 3), ("throughput", None)])
def test_roulette_never_ends_a_path_before_its_start_depth(floor, rr, start):
    settings = PathSettings(rr=rr, rr_depth=start)
    dim = np.full((100, 3), 0.01, np.float32)  # would die almost surely
    u = np.full(100, 0.999, np.float32)
    for depth in range(settings.rr_depth):
        hit = at_depth(carrying(floor, dim), depth)
        assert russian_roulette(hit, settings, u).all()
        np.testing.assert_array_equal(hit.throughput, dim)
    assert not russian_roulette(at_depth(carrying(floor, dim), settings.rr_depth), settings, u).any()
    # A batch of paths at several depths (path regeneration): each row by its own depth.
    depth = np.arange(100) % (settings.rr_depth + 1)
    survive = russian_roulette(at_depth(carrying(floor, dim), depth), settings, u)
    np.testing.assert_array_equal(survive, depth < settings.rr_depth)


def at_depth(hit, depth):
    """``hit`` with its paths at ``depth``: one for all, or (N,) one per path."""
    hit.paths.depth = depth
    return hit


# -- leaving a surface -----------------------------------------------------------------------


def test_rays_leaving_a_floor_up_or_down_never_hit_it(floor):
    # Down is a ray through the surface (glass): it must start below it, up one above it.
    scene, accel = floor
    points = np.column_stack([np.linspace(-2, 2, 50), np.zeros(50), np.linspace(-3, 3, 50)])
    hit = vertices_below(scene, accel, points)
    up = np.tile(np.array([0.3, 1.0, 0.0], np.float32) / np.float32(math.hypot(0.3, 1.0)), (50, 1))
    for wi in (up, -up):
        origins = leave_surface(hit.p, hit.n, hit.offset, wi)
        assert not np.isin(accel.intersect(origins, wi).prim, [0, 1]).any()


# -- next-event estimation -------------------------------------------------------------------


def polygon_irradiance(x: np.ndarray, n: np.ndarray, polygon: np.ndarray) -> float:
    """The integral over the flat ``polygon`` (K, 3) of cos(theta) cos(theta') / r^2 dA, as
    seen from the point ``x`` with normal ``n``: the irradiance a polygon of unit radiance
    gives (Lambert's formula: (1/2) sum over edges of the edge's angle times n . the unit
    normal of the plane through x and the edge; Arvo 1994, "The irradiance Jacobian")."""
    u = polygon - x
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    total = 0.0
    for a, b in zip(u, np.roll(u, -1, axis=0), strict=True):
        gamma = np.cross(a, b)
        total += math.acos(np.clip(a @ b, -1, 1)) * (gamma / np.linalg.norm(gamma)) @ n
    return abs(total) / 2


def test_direct_light_from_one_triangle_is_lamberts_closed_form(floor):
    scene, accel = floor
    light = scene.triangles[2]
    count = 1 << 16
    x = np.array([0.05, 0.0, 0.02])
    hit = vertices_below(scene, accel, np.tile(x, (count, 1)))
    film = np.zeros((count, 3))
    u = np.random.default_rng(3).random((count, 2)).astype(np.float32)
    rays = direct_light(film, scene, accel, hit, u, PathSettings(strategy="nee"))
    assert rays == count  # every light point faces x: one shadow ray each
    samples = film[:, 0]
    # L = f_r Le E = (albedo / pi) Le E, E the integral of cos cos' / r^2 over the light.
    expected = 0.5 / math.pi * 2.0 * polygon_irradiance(x, np.array([0.0, 1.0, 0.0]), light)
    standard_error = samples.std(ddof=1) / math.sqrt(count)
    assert abs(samples.mean() - expected) < Z * standard_error, (samples.mean(), expected)
    assert Z * standard_error < 0.01 * expected  # sharp enough to see a 1% error


def test_direct_light_behind_a_blocker_is_black(floor):
    scene, _ = floor
    blocker = np.array(
        [[[-1, 0.5, -1], [1, 0.5, 1], [1, 0.5, -1]], [[-1, 0.5, -1], [-1, 0.5, 1], [1, 0.5, 1]]], dtype=float
    )
    blocked = Scene(
        triangles=np.concatenate([scene.triangles, blocker]),
        material_ids=[0, 0, 1, 0, 0],
        materials=scene.materials,
        camera=scene.camera,
    )
    accel = make_accelerator(blocked.triangles, "embree")
    # Rays from below the blocker, down to the floor under the light.
    points = np.tile([0.05, 0.0, 0.02], (256, 1))
    paths = camera_paths(points + np.array([0, 0.25, 0]), np.tile([0.0, -1.0, 0.0], (256, 1)))
    hit = surface_hit(blocked, paths, accel.intersect(paths.origins, paths.dirs))
    film = np.zeros((256, 3))
    u = np.random.default_rng(4).random((256, 2)).astype(np.float32)
    direct_light(film, blocked, accel, hit, u, PathSettings())
    assert (film == 0).all()


# -- whole paths ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("strategy", "rr"), [("nee", "throughput"), ("bsdf", "throughput"), ("mis", "throughput"), ("nee", 0.8)]
)
def test_paths_in_a_furnace_see_emission_over_one_minus_albedo(strategy, rr):
    # Every surface of a closed sphere emits Le and reflects albedo a: every ray sees
    # Le (1 + a + a^2 + ...) = Le / (1 - a), whichever way it looks.
    albedo, emission, count = 0.5, 0.3, 1 << 14
    scene = closed_sphere_scene(albedo, emission)
    accel = make_accelerator(scene.triangles, "embree")
    dirs = np.random.default_rng(5).normal(size=(count, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    paths = camera_paths(np.tile(scene.camera.position, (count, 1)), dirs, seed=6)
    film = np.zeros((count, 3))
    trace_paths(
        film, scene, accel, paths, make_sampler("independent", 6), PathSettings(strategy=strategy, rr=rr)
    )
    samples = film[:, 0]
    standard_error = samples.std(ddof=1) / math.sqrt(count)
    expected = emission / (1 - albedo)
    assert abs(samples.mean() - expected) < Z * standard_error, (samples.mean(), expected)
    # Sharp enough to see the third bounce's light missing (or doubled).
    assert Z * standard_error < emission * albedo**3
