"""The scenes of GAMES101 Homeworks 5 and 6 (``scenes/games101-hw5``, ``scenes/games101-hw6``):
the homework's numbers, and a render without NaN by every integrator on both backends."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from helpers import grazing_cameras

import ptlab
from ptlab.accel import make_accelerator
from ptlab.integrators.path import PathSettings
from ptlab.rendering import resolution
from ptlab.rendering.jobs import Job, RenderSetup, Tile, run_job
from ptlab.samplers import make_sampler
from ptlab.scene_file import builtin_scene_names, builtin_scenes_dir

BACKGROUND = (0.235294, 0.67451, 0.843137)  # the homework's backgroundColor, 8-bit sRGB


def srgb_to_linear(c) -> np.ndarray:
    c = np.asarray(c, dtype=float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def material(scene, name):
    return scene.materials[scene.material_names.index(name)]


def bounds(scene, name) -> np.ndarray:
    """(2, 3) the box around the triangles of one material."""
    corners = scene.triangles[scene.material_ids == scene.material_names.index(name)].reshape(-1, 3)
    return np.array([corners.min(axis=0), corners.max(axis=0)])


def test_both_scenes_are_built_in():
    assert {"games101-hw5", "games101-hw6"} <= set(builtin_scene_names())


def test_homework_5_scene_has_the_homeworks_geometry_lights_and_colours():
    scene = ptlab.load_scene("games101-hw5")
    np.testing.assert_allclose(scene.camera.position, [0, 0, 0])
    np.testing.assert_allclose(scene.camera.forward, [0, 0, -1])
    assert scene.camera.fov_y == 90
    assert resolution(scene) == (1280, 960)
    assert scene.defaults.max_depth == 5
    np.testing.assert_allclose(scene.point_lights.positions, [[-20, 70, 20], [30, 50, -12]])
    np.testing.assert_allclose(scene.sky.radiance, srgb_to_linear(BACKGROUND), atol=1e-4)
    np.testing.assert_allclose(bounds(scene, "checkerboard"), [[-5, -3, -16], [5, -3, -6]])
    board = material(scene, "checkerboard").albedo
    np.testing.assert_allclose(
        board.colours, srgb_to_linear([(0.815, 0.235, 0.031), (0.937, 0.937, 0.231)]), atol=1e-4
    )
    assert board.scale == 5
    np.testing.assert_allclose(
        material(scene, "diffuse_and_glossy").kd, srgb_to_linear((0.6, 0.7, 0.8)), atol=1e-4
    )
    for name, center, radius in (("diffuse_and_glossy", (-1, 0, -12), 2.0), ("glass", (0.5, -0.5, -8), 1.5)):
        np.testing.assert_allclose(
            bounds(scene, name), [np.subtract(center, radius), np.add(center, radius)], atol=1e-9
        )
    assert material(scene, "glass").eta == 1.5


def test_homework_6_scene_is_the_bunny_scaled_by_60():
    from ptlab.meshes import read_mesh_triangles

    scene = ptlab.load_scene("games101-hw6")
    bunny = read_mesh_triangles(builtin_scenes_dir() / "games101-hw6" / "meshes" / "bunny.obj")
    assert scene.triangle_count == len(bunny) == 4968
    np.testing.assert_allclose(scene.triangles, 60 * bunny)
    np.testing.assert_allclose(scene.camera.position, [-1, 5, 10])
    np.testing.assert_allclose(scene.camera.forward, [0, 0, -1])
    assert scene.camera.fov_y == 90
    assert resolution(scene) == (1280, 960)
    np.testing.assert_allclose(scene.point_lights.positions, [[-20, 70, 20], [20, 70, 20]])
    np.testing.assert_allclose(scene.sky.radiance, srgb_to_linear(BACKGROUND), atol=1e-4)


RUNS = [
    ("path", "nee"),
    ("path", "bsdf"),
    ("path", "mis"),
    ("whitted", "nee"),
    ("normals", "nee"),
    ("albedo", "nee"),
    ("depth", "nee"),
]


def render_job(
    scene, accel, backend: str, integrator: str, strategy: str, width: int, height: int
) -> tuple[np.ndarray, int]:
    """(height, width, 3) one job's image, 2 spp, through a ray-query structure built once,
    and its samples that were NaN or infinite (left out of the image)."""
    job = Job(Tile(0, 0, 0, width, height), pass_index=0, spp=2)
    setup = RenderSetup(
        scene=scene,
        backend=backend,
        width=width,
        height=height,
        seed=5,
        settings=PathSettings(strategy=strategy, max_depth=8),
        integrator=integrator,
        sampler=make_sampler("sobol", 5, 2),
    )
    result = run_job(setup, job, accel)
    return result.sums / job.spp, result.nonfinite


@pytest.mark.parametrize("backend", ["embree", pytest.param("numpy", marks=pytest.mark.slow)])
@pytest.mark.parametrize("name", ["games101-hw5", "games101-hw6"])
def test_every_integrator_renders_the_scene_without_nan(name, backend):
    # Every integrator, from the scene's camera and from two that graze its floor
    # (tests/renderer/test_strategies.py's check of the other scenes), through one ray-query
    # structure per scene and backend. No path contribution may be NaN or infinite, even
    # one the film would drop.
    scene = ptlab.load_scene(name)
    accel = make_accelerator(scene.triangles, backend)
    views = {"scene camera": scene}
    views.update(
        {view: dataclasses.replace(scene, camera=camera) for view, camera in grazing_cameras(scene).items()}
    )
    width, height = 24, 18
    for view, viewed in views.items():
        images = {}
        for integrator, strategy in RUNS:
            image, nonfinite = render_job(viewed, accel, backend, integrator, strategy, width, height)
            assert np.isfinite(image).all(), (view, integrator, strategy)
            assert (image >= 0).all(), (view, integrator, strategy)
            assert nonfinite == 0, (view, integrator, strategy, nonfinite)
            images[integrator, strategy] = image
        if view == "scene camera":
            # The sky fills the top row; the path tracer and Whitted see it there alike.
            sky = np.broadcast_to(scene.sky.radiance, (width, 3))
            for key in RUNS[:4]:
                np.testing.assert_allclose(images[key][0], sky, rtol=1e-5)
            assert (images["depth", "nee"] > 0).any()
            assert (images["normals", "nee"] > 0).any()
