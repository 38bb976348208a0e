"""The denoiser's feature images (``ptlab.integrators.features``) and a denoised render end to
end: what they hold where the answer is exact, that gathering them changes no image, and
``render_result(..., denoise=True)`` / ``ptlab render --denoise --aov`` as a user calls them.

No test here is statistical: the feature images below are exact (a diffuse surface's bounce
weight under cosine sampling is its albedo; a flat mirror and a flat ceiling give one normal),
and the rest compare renders bit for bit.
"""

from __future__ import annotations

import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)
import pytest

import ptlab
from ptlab.cli import main as cli_main
from ptlab.errors import PtlabError
from ptlab.image import read_image
from ptlab.rendering import render_result

CEILING_ALBEDO = (0.2, 0.4, 0.6)
CEILING_EMISSION = (1.0, 2.0, 3.0)
MIRROR_REFLECTANCE = 0.5


def mirror_under_a_ceiling() -> ptlab.Scene:
    """A camera looking straight down at a mirror floor (y = 0), which shows a flat ceiling
    (y = 5) that is diffuse and emits: every pixel's first hit is the mirror, its first
    hit that is not a mirror the ceiling's underside."""
    floor = np.array([[[-5, 0, -5], [5, 0, 5], [5, 0, -5]], [[-5, 0, -5], [-5, 0, 5], [5, 0, 5]]], float)
    ceiling = np.array([[[-5, 5, -5], [5, 5, -5], [5, 5, 5]], [[-5, 5, -5], [5, 5, 5], [-5, 5, 5]]], float)
    mirror = ptlab.materials.Mirror(reflectance=[MIRROR_REFLECTANCE] * 3)
    lamp = ptlab.materials.Diffuse(CEILING_ALBEDO, emission=CEILING_EMISSION)
    camera = ptlab.camera.Camera.look_at((0, 2, 0.01), (0, 0, 0), up=(0, 0, 1), fov_y=30)
    return ptlab.Scene(np.concatenate([floor, ceiling]), np.array([0, 0, 1, 1]), [mirror, lamp], camera)


def test_features_are_taken_past_mirrors_at_the_first_other_hit():
    result = render_result(mirror_under_a_ceiling(), spp=4, res=12, workers=1, features=True)
    features = result.features
    assert features is not None
    # The ceiling's albedo and its normal facing the ray (down), not the mirror's.
    np.testing.assert_allclose(features["albedo"], np.broadcast_to(CEILING_ALBEDO, (12, 12, 3)), rtol=1e-6)
    np.testing.assert_allclose(features["normal"], np.broadcast_to((0, -1, 0), (12, 12, 3)), atol=1e-6)
    # What the camera sees of the ceiling's emission through the mirror is direct light:
    # the reflectance times Le, exactly; the light the ceiling reflects is not.
    expected_direct = MIRROR_REFLECTANCE * np.array(CEILING_EMISSION)
    np.testing.assert_allclose(features["direct"], np.broadcast_to(expected_direct, (12, 12, 3)), rtol=1e-6)
    assert np.all(result.image >= features["direct"] * (1 - 1e-6))
    assert result.image.mean() > 1.05 * features["direct"].mean()


def test_a_light_seen_by_the_camera_is_direct_and_a_lit_wall_is_not():
    result = render_result("cornell-box", spp=4, res=32, workers=1, features=True)
    features = result.features
    assert features is not None
    direct = features["direct"].sum(axis=-1)
    # (The Cornell box's light, seen from below in the top rows' middle, emits about 47.)
    seen = direct > 1.0
    assert 0 < seen.sum() < 32 * 32 * 0.1
    assert np.all(np.abs(direct[~seen]) == 0.0)
    # Where a pixel sees only the light, the image is its direct part and the little light
    # the lamp's own surface reflects: a few percent more.
    assert np.all(result.image >= features["direct"] * (1 - 1e-6))
    ratio = result.image[direct > 40] / features["direct"][direct > 40]
    assert 1.0 <= ratio.min() <= ratio.max() < 1.05
    albedo = features["albedo"]
    assert albedo.min() >= 0.0
    assert albedo.max() <= 1.0
    normal_length = np.linalg.norm(features["normal"], axis=-1)
    assert normal_length.max() <= 1.0 + 1e-6
    assert np.median(normal_length) > 0.99  # (most pixels see one flat surface)


def test_gathering_features_changes_no_image_and_no_worker_count_changes_them():
    plain = render_result("cornell-box", spp=8, res=48, workers=1)
    gathered = render_result("cornell-box", spp=8, res=48, workers=1, features=True)
    assert np.array_equal(plain.image, gathered.image)
    assert plain.features is None
    with ThreadPoolExecutor(3) as executor:
        threads = render_result("cornell-box", spp=8, res=48, tile_size=16, executor=executor, features=True)
    assert gathered.features is not None
    assert threads.features is not None
    for name, image in gathered.features.items():
        assert np.array_equal(image, threads.features[name]), name


def test_a_denoised_render_keeps_its_noisy_image_and_says_how_it_was_made():
    pytest.importorskip("pyoidn")
    result = render_result("cornell-box", spp=8, res=64, workers=1, denoise=True)
    assert result.denoised
    assert result.noisy is not None
    assert result.features is not None
    assert result.settings["denoised"].startswith("Intel Open Image Denoise ")
    assert result.settings["denoise_seconds"] > 0
    # Denoising removes noise, not light: each channel's mean stays (the noisy one is unbiased).
    np.testing.assert_allclose(result.image.mean(axis=(0, 1)), result.noisy.mean(axis=(0, 1)), rtol=0.03)
    # ... and it removes noise: neighbouring pixels of the back wall differ far less.
    wall = (slice(20, 40), slice(24, 40))
    assert (
        np.abs(np.diff(result.image[wall], axis=1)).mean()
        < 0.3 * np.abs(np.diff(result.noisy[wall], axis=1)).mean()
    )


def test_a_denoised_render_resumed_from_its_checkpoint_is_the_one_not_stopped(tmp_path):
    pytest.importorskip("pyoidn")
    whole = render_result("cornell-box", spp=8, res=32, workers=1, denoise=True, spp_per_pass=4)
    calls = []
    stopped = render_result(
        "cornell-box",
        spp=8,
        res=32,
        workers=1,
        denoise=True,
        spp_per_pass=4,
        checkpoint=tmp_path / "box.npz",
        on_pass=calls.append,
        stop=lambda: len(calls) >= 1,
    )
    assert not stopped.complete
    resumed = render_result(
        "cornell-box", spp=8, res=32, workers=1, denoise=True, spp_per_pass=4, resume=tmp_path / "box.npz"
    )
    assert np.array_equal(resumed.noisy, whole.noisy)
    assert resumed.features is not None
    assert whole.features is not None
    for name, image in whole.features.items():
        assert np.array_equal(image, resumed.features[name]), name
    np.testing.assert_allclose(resumed.image, whole.image, rtol=1e-5, atol=1e-6)


def test_ptlab_render_aov_writes_the_features_as_layers_of_the_exr(tmp_path):
    pytest.importorskip("pyoidn")
    out = tmp_path / "box.exr"
    code = cli_main(
        [
            "render",
            "cornell-box",
            "--res",
            "32",
            "--spp",
            "4",
            "--denoise",
            "--aov",
            "--quiet",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    source = oiio.ImageInput.open(str(out))
    spec = source.spec()
    pixels = source.read_image(oiio.FLOAT)
    source.close()
    names = list(spec.channelnames)
    assert names[:3] == ["R", "G", "B"]
    for layer, axes in (("albedo", "RGB"), ("normal", "XYZ"), ("direct", "RGB"), ("noisy", "RGB")):
        assert [f"{layer}.{a}" for a in axes] == [n for n in names if n.startswith(layer + ".")]
    albedo = pixels[..., [names.index(f"albedo.{a}") for a in "RGB"]]
    assert 0.0 <= albedo.min() <= albedo.max() <= 1.0
    assert spec.get_string_attribute("ptlab:denoised").startswith("Intel Open Image Denoise")


def test_aov_needs_an_exr_and_denoise_needs_the_path_integrator(tmp_path, capsys):
    assert cli_main(["render", "cornell-box", "--res", "8", "--aov", "--out", str(tmp_path / "a.png")]) == 2
    assert "--aov: the feature images go into an .exr output" in capsys.readouterr().err
    assert not (tmp_path / "a.png").exists()
    code = cli_main(["render", "cornell-box", "--res", "8", "--denoise", "--integrator", "whitted"])
    assert code == 2
    assert "the denoiser is for path-traced images" in capsys.readouterr().err


@pytest.mark.subprocess
def test_without_the_extra_denoise_fails_in_one_line_before_rendering(tmp_path):
    # (pyoidn made unimportable in a fresh interpreter, as on a machine without the extra.)
    out = str(tmp_path / "a.png")
    program = (
        "import sys; sys.modules['pyoidn'] = None; from ptlab.cli import main; "
        f"sys.exit(main(['render', 'cornell-box', '--res', '8', '--denoise', '--out', {out!r}]))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "ptlab: error: denoising needs Intel Open Image Denoise: pip install 'ptlab[denoise]'"
    ]
    assert not (tmp_path / "a.png").exists()


def test_previews_of_a_denoised_render_are_denoised(tmp_path):
    pytest.importorskip("pyoidn")
    from ptlab.cli import _Preview

    written = []

    class Recording(_Preview):
        def __call__(self, film) -> None:
            super().__call__(film)
            written.append(read_image(self.out))

    out = tmp_path / "preview.exr"
    result = render_result(
        "cornell-box",
        spp=4,
        res=32,
        workers=1,
        denoise=True,
        spp_per_pass=2,
        on_pass=Recording(out, every=0.0, denoise=True),
    )
    assert len(written) == 2  # (a preview after each of the two passes)
    image, metadata = written[-1]
    assert metadata["preview"] == 1
    assert metadata["denoised"].startswith("Intel Open Image Denoise")
    # The last preview is the film of the whole render, denoised at once (a preview needs no
    # estimate: ptlab.denoise.pipeline), where the render's image is its two halves denoised:
    # near the render's image, far from the noisy one.
    from ptlab.measure.metrics import relmse

    assert relmse(image, result.image) < 0.2 * relmse(result.noisy, result.image)


def test_a_denoised_render_to_a_target_says_what_decided_its_end(tmp_path, capsys):
    pytest.importorskip("pyoidn")
    out = tmp_path / "box.exr"
    code = cli_main(
        [
            "render",
            "cornell-box",
            "--res",
            "64",
            "--workers",
            "1",
            "--denoise",
            "--target-error",
            "0.02",
            "--out",
            str(out),
        ]
    )
    assert code == 0
    lines = capsys.readouterr().out.splitlines()
    said = lines[-2]  # (the target's line, before "wrote ...")
    decided = [
        r"estimated relMSE [0-9.e-]+, target 0.02: reached",
        r"relMSE below [0-9.e-]+ \(not estimated closer\), target 0.02: reached",
        r"target 0.02 reached by the noisy image's estimated relMSE \([0-9.e-]+\); "
        r"the denoised image's error is not known",
    ]
    assert any(re.fullmatch(pattern, said) for pattern in decided), said
    metadata = read_image(out)[1]
    assert metadata["target_end"] == "target"
    # What the line says is in the header: an estimate, a bound, or why there is neither.
    if "estimated relMSE" in said and "noisy" not in said:
        assert metadata["relmse_estimate"] <= 0.02
    else:
        assert metadata["relmse_estimate_refused"]


def test_a_bound_is_given_only_where_the_estimates_spread_is_known():
    from ptlab.denoise import ErrorEstimate
    from ptlab.rendering.denoising import error_bound

    def estimate(size: int, standard_error: float) -> ErrorEstimate:
        return ErrorEstimate(
            relmse=None,
            reason="refused",
            value=0.002,
            alternative=0.003,
            standard_error=standard_error,
            error_map=np.full((size, size), 0.002),
        )

    # The larger value plus two standard errors, from enough blocks of 8 x 8 (here 256).
    assert error_bound(estimate(128, 0.25)) == pytest.approx(0.003 * 1.5)
    # From 64 blocks (64 x 64 pixels), or a spread above a third, none: such bounds failed.
    assert error_bound(estimate(64, 0.25)) is None
    assert error_bound(estimate(128, 0.4)) is None


def test_a_denoised_render_refuses_images_too_small_and_leaves_black_ones_black():
    pytest.importorskip("pyoidn")
    with pytest.raises(PtlabError, match=r"^denoise: a 8x8 image is too small to denoise"):
        render_result("cornell-box", spp=2, res=8, workers=1, denoise=True)
    scene = mirror_under_a_ceiling()
    dark = ptlab.materials.Diffuse(CEILING_ALBEDO)  # (the same room, with no light in it)
    black = render_result(
        scene.with_materials([scene.materials[0], dark]), spp=2, res=16, workers=1, denoise=True
    )
    assert not black.image.any()  # (the denoiser would make up a faint haze)
    assert black.relmse_estimate is None
    assert black.estimate_refused == "the image is black: no light to denoise"


def test_aov_is_kept_by_a_resumed_render(tmp_path):
    checkpoint, out = tmp_path / "box.npz", tmp_path / "box.exr"
    started = ["render", "cornell-box", "--res", "16", "--spp", "4", "--workers", "1", "--quiet"]
    assert cli_main([*started, "--aov", "--checkpoint", str(checkpoint), "--out", str(out)]) == 0
    out.unlink()
    assert cli_main(["render", "--resume", str(checkpoint), "--spp", "8", "--workers", "1", "--quiet"]) == 0
    source = oiio.ImageInput.open(str(out))
    names = list(source.spec().channelnames)
    source.close()
    assert "albedo.R" in names
    assert "normal.X" in names


@pytest.mark.subprocess
def test_a_plain_render_imports_neither_the_denoiser_nor_scipy_ndimage():
    # (Each took 0.1-0.2 s of every render's start-up, for a render that denoises or aims at a
    # target: docs/performance.md.)
    program = (
        "import sys, ptlab; ptlab.render('cornell-box', res=8, spp=1, workers=1); "
        "print(sorted(m for m in ('pyoidn', 'scipy.ndimage') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
