"""The inspector (``ptlab.inspector``, ``ptlab inspect``): one pixel's paths as the renderer
traced them. Deterministic: the inspector re-runs the render's own jobs, so its value must be
the rendered pixel bit for bit, and its records must add up to each sample's contribution."""

from __future__ import annotations

import json

import numpy as np
import pytest

import ptlab
from ptlab.cli import main
from ptlab.errors import PtlabError
from ptlab.inspector import LightSample, inspect_pixel, parse_pixel

#: Small renders: 24 x 24, 6 spp in passes of 4 and 2 (two passes: the value adds them up).
OPTIONS = dict(res=24, spp=6, seed=3, workers=1, spp_per_pass=4)


def recorded_sum(sample) -> np.ndarray:
    """What the recorded steps of a sample added: emission, light samples, the sky."""
    total = np.zeros(3) + (sample.sky or 0)
    for v in sample.vertices:
        for added in (v.emission, v.light.contribution if v.light else None, v.sky):
            if added is not None:
                total += added
    return total


def pixels_to_test(image: np.ndarray) -> list[tuple[int, int]]:
    """The brightest pixel (in the Cornell box, one that sees the light), a middling one, a
    dark one, and the middle (in games101-hw5, the glass sphere: Whitted splits its rays)."""
    order = np.argsort(image.sum(axis=2), axis=None)
    picks = [order[-1], order[len(order) // 2], order[len(order) // 8]]
    return [(int(i % image.shape[1]), int(i // image.shape[1])) for i in picks] + [(12, 12)]


@pytest.mark.parametrize(
    ("scene", "options"),
    [
        ("cornell-box", dict(strategy="nee")),
        ("veach-mis", dict(strategy="mis")),
        ("games101-hw5", dict(integrator="whitted")),
    ],
)
def test_value_is_the_rendered_pixel(scene, options):
    options = dict(OPTIONS, **options)
    scene = ptlab.load_scene(scene)  # (once: games101-hw5's meshes take a while to read)
    image = ptlab.render(scene, **options)
    for x, y in pixels_to_test(image):
        found = inspect_pixel(scene, (x, y), **options)
        # The film's own sums, in its order: equal bit for bit, not only to rounding.
        assert np.array_equal(np.float32(found.value), image[y, x]), (x, y)
        contributions = np.array([s.contribution for s in found.samples])
        assert len(contributions) == options["spp"]
        np.testing.assert_allclose(contributions.mean(axis=0), found.value, rtol=1e-6, atol=1e-7)
        for sample in found.samples:  # nothing added that the records do not show
            np.testing.assert_allclose(recorded_sum(sample), sample.contribution, rtol=1e-5, atol=1e-7)
    if options.get("integrator") == "whitted":  # the glass: a reflected and a refracted ray
        assert any(len(v.split) == 2 and v.material == "glass" for s in found.samples for v in s.vertices)


def test_a_pixel_that_sees_the_light():
    options = dict(OPTIONS, res=32)
    found = inspect_pixel("cornell-box", (16, 4), **options)
    scene = ptlab.load_scene("cornell-box")
    le = scene.materials[scene.material_names.index("light")].emission
    first = [s.vertices[0] for s in found.samples]
    assert all(v.material == "light" and v.depth == 0 for v in first)
    # A camera ray that sees the light adds its Le (throughput 1), before any bounce.
    for v in first:
        np.testing.assert_allclose(v.emission, le, rtol=1e-6)
    image = ptlab.render("cornell-box", **options)
    assert np.array_equal(np.float32(found.value), image[4, 16])


def test_vertices_follow_the_path():
    """Each vertex's wo is minus the previous vertex's wi, the throughput after a bounce is
    the one before times the BSDF weight (over the roulette's survival), and the depths count
    up: the records are one path, in order."""
    found = inspect_pixel("cornell-box", (12, 14), **dict(OPTIONS, rr=0.8))
    checked = 0
    for sample in found.samples:
        throughput = np.ones(3)
        for k, v in enumerate(sample.vertices):
            assert v.depth == k
            if k:
                np.testing.assert_allclose(v.wo, -np.array(sample.vertices[k - 1].bsdf.wi), atol=1e-5)
            if v.bsdf is not None and v.roulette is not None and v.roulette.survived:
                expected = throughput / v.roulette.survival * np.array(v.bsdf.weight)
                np.testing.assert_allclose(v.throughput, expected, rtol=1e-5)
                f_cos_over_pdf = np.array(v.bsdf.f) * v.bsdf.cos_theta / v.bsdf.pdf
                np.testing.assert_allclose(v.bsdf.weight, f_cos_over_pdf, rtol=1e-4)
                throughput = np.array(v.throughput)
                checked += 1
    assert checked > 3


def test_the_api_is_at_the_top_and_plots(tmp_path):
    found = ptlab.inspect_pixel("cornell-box", (12, 14), res=24, spp=2, workers=1)
    assert isinstance(found.samples[0].vertices[0].light, LightSample)
    out = tmp_path / "paths.png"
    found.plot(out, image=ptlab.render("cornell-box", res=24, spp=1, workers=1))
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.stat().st_size > 10_000  # (three panels, not an empty figure)


def test_parse_pixel_and_bounds():
    assert parse_pixel("3, 14") == (3, 14)
    with pytest.raises(PtlabError, match="X,Y"):
        parse_pixel("3")
    with pytest.raises(PtlabError, match="outside the 24x24 image"):
        inspect_pixel("cornell-box", (24, 0), **OPTIONS)


def test_cli_prints_json_and_one_sample(tmp_path, capsys):
    out = tmp_path / "pixel.json"
    options = ["--res", "24", "--spp", "3", "--seed", "3", "--pixel", "12,14"]
    code = main(["inspect", "cornell-box", *options, "--sample", "1", "--json", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "sample 1" in printed
    assert "sample 0\n" not in printed
    assert "depth 0" in printed
    assert "pixel value" in printed
    data = json.loads(out.read_text())
    assert len(data["value"]) == 3
    assert len(data["samples"]) == 3
    vertex = data["samples"][0]["vertices"][0]
    for name in ("depth", "position", "triangle", "material", "normal", "front", "wo", "light", "throughput"):
        assert name in vertex
    assert set(vertex["light"]) >= {"point", "light", "pdf", "visible", "mis_weight", "contribution"}
    image = ptlab.render("cornell-box", res=24, spp=3, seed=3, workers=1)
    assert np.array_equal(np.float32(data["value"]), image[14, 12])


#: Cameras in the Cornell box: its own (looking along +z: the image's left is +x), and
#: others looking along -x, diagonally, and upside down. (position, target, up)
CAMERAS = {
    "the scene's": None,
    "along -x": ((500.0, 273.0, 278.0), (0.0, 273.0, 278.0), (0.0, 1.0, 0.0)),
    "diagonally": ((480.0, 300.0, 60.0), (100.0, 250.0, 500.0), (0.0, 1.0, 0.0)),
    "upside down": ((278.0, 273.0, -800.0), (278.0, 273.0, 0.0), (0.0, -1.0, 0.0)),
}


@pytest.mark.parametrize("camera", CAMERAS)
def test_the_plots_views_are_the_images_not_its_mirror(camera):
    # From above, what is left in the image is left in the panel; from the side, the camera
    # looks to the right and what is up in the image is up in the panel.
    from dataclasses import replace

    import matplotlib.pyplot as plt

    from ptlab.camera import Camera
    from ptlab.inspector.plot import draw, views

    scene = ptlab.load_scene("cornell-box")
    if CAMERAS[camera] is not None:
        position, target, up = CAMERAS[camera]
        scene = replace(scene, camera=Camera.look_at(position, target, up, fov_y=40.0))
    options = dict(res=24, spp=1, workers=1, max_depth=1)
    hits = {
        name: np.array(inspect_pixel(scene, pixel, **options).samples[0].vertices[0].position)
        for name, pixel in {"left": (2, 12), "right": (21, 12), "top": (12, 2), "bottom": (12, 21)}.items()
    }
    figure = draw(inspect_pixel(scene, (12, 12), **options), scene)
    try:
        above, side = figure.axes
        view_above, view_side = views(scene.camera)

        def shown_at(ax, view, point) -> np.ndarray:
            """Where ``point`` is drawn on the page (display coordinates, x right, y up)."""
            return ax.transData.transform((point[view.across], point[view.up]))

        assert shown_at(above, view_above, hits["left"])[0] < shown_at(above, view_above, hits["right"])[0]
        assert shown_at(side, view_side, hits["top"])[1] > shown_at(side, view_side, hits["bottom"])[1]
        camera_at = np.asarray(scene.camera.position)
        far = camera_at + 100 * np.asarray(scene.camera.forward)
        assert shown_at(side, view_side, camera_at)[0] < shown_at(side, view_side, far)[0]
        assert shown_at(above, view_above, camera_at)[1] < shown_at(above, view_above, far)[1]
    finally:
        plt.close(figure)
