"""``--crop X,Y,W,H`` (``RenderOptions.crop``, pbrt's crop window): a W x H image whose pixels
are the whole image's render in that window, bit for bit, whatever the backend, workers,
sampler and passes; its file records where it sits; a checkpoint keeps it; bad windows are
one line."""

from __future__ import annotations

import functools
import importlib.util

import numpy as np
import pytest

import ptlab
from ptlab.cli import main
from ptlab.errors import PtlabError
from ptlab.image import Window, read_image_file
from ptlab.materials import Diffuse

#: The whole image (not square, so that x and y cannot be swapped unseen) and its window,
#: which starts inside a tile and spans several (tiles of ``TILE`` pixels).
RES = (24, 20)
CROP = (5, 3, 11, 9)
TILE = 8
#: Three passes of 4, 4 and 2 samples: each pixel's sums are made per pass.
SPP, SPP_PER_PASS = 10, 4


def window_of(image: np.ndarray, crop=CROP) -> np.ndarray:
    x, y, width, height = crop
    return np.ascontiguousarray(image[y : y + height, x : x + width])


def assert_same_bits(crop: np.ndarray, whole: np.ndarray) -> None:
    assert crop.dtype == whole.dtype
    assert crop.shape == whole.shape
    assert crop.tobytes() == whole.tobytes()


@functools.cache
def whole_image(backend: str, sampler: str, **options) -> np.ndarray:
    """The whole image's render (one worker: the image does not depend on it)."""
    return ptlab.render(
        "cornell-box",
        spp=SPP,
        res=RES,
        seed=3,
        workers=1,
        backend=backend,
        sampler=sampler,
        tile_size=TILE,
        spp_per_pass=SPP_PER_PASS,
        **options,
    )


def cropped(backend: str, sampler: str, workers: int, **options) -> ptlab.RenderResult:
    return ptlab.render_result(
        "cornell-box",
        spp=SPP,
        res=RES,
        seed=3,
        workers=workers,
        backend=backend,
        sampler=sampler,
        tile_size=TILE,
        spp_per_pass=SPP_PER_PASS,
        crop=CROP,
        **options,
    )


@pytest.mark.parametrize(
    ("backend", "sampler"),
    [("embree", "sobol"), ("numpy", "sobol"), ("embree", "stratified"), ("embree", "independent")],
)
def test_a_crop_is_the_whole_renders_window_bit_for_bit(backend, sampler):
    result = cropped(backend, sampler, workers=1)
    assert result.image.shape == (CROP[3], CROP[2], 3)
    assert result.complete
    assert result.spp == SPP
    assert_same_bits(result.image, window_of(whole_image(backend, sampler)))
    assert result.window == Window(CROP[0], CROP[1], *RES)


@pytest.mark.subprocess
@pytest.mark.parametrize("backend", ["embree", "numpy"])
def test_a_crop_on_two_workers_is_the_same(backend):
    result = cropped(backend, "sobol", workers=2)
    assert result.settings["workers"] == 2
    assert_same_bits(result.image, window_of(whole_image(backend, "sobol")))


def test_a_whitted_crop_is_the_same():
    result = cropped("embree", "sobol", workers=1, integrator="whitted")
    assert_same_bits(result.image, window_of(whole_image("embree", "sobol", integrator="whitted")))


def test_a_crop_to_a_noise_target_run_to_a_fixed_pass_is_the_same():
    # A noise target's passes depend on the estimate over the pixels rendered, the window's:
    # after the first pass (spp everywhere, each pixel's samples in two independent halves)
    # they differ. max_spp = spp stops it there, deterministically, for both.
    target = dict(target_error=1e-6, max_spp=8, spp=8, spp_per_pass=None)
    whole = ptlab.render_result("cornell-box", res=RES, seed=3, workers=1, tile_size=TILE, **target)
    crop = ptlab.render_result("cornell-box", res=RES, seed=3, workers=1, tile_size=TILE, crop=CROP, **target)
    assert whole.settings["target_end"] == crop.settings["target_end"] == "max spp"
    assert crop.relmse_estimate is not None
    assert_same_bits(crop.image, window_of(whole.image))


@pytest.mark.skipif(importlib.util.find_spec("pyoidn") is None, reason="the denoise extra")
def test_a_denoised_crop_denoises_the_windows_same_noisy_pixels():
    crop = (4, 2, 16, 16)  # (the denoiser's least size)
    options = dict(spp=4, res=RES, seed=3, workers=1, tile_size=TILE, denoise=True)
    whole = ptlab.render_result("cornell-box", **options)
    part = ptlab.render_result("cornell-box", crop=crop, **options)
    assert part.noisy is not None
    assert whole.noisy is not None
    assert_same_bits(part.noisy, window_of(whole.noisy, crop))
    assert part.image.shape == (16, 16, 3)
    # (The denoiser sees only the window: its pixels are its own, near the edges above all.)
    assert (
        np.abs(part.image - window_of(whole.image, crop)).mean() < 0.1 * window_of(whole.image, crop).mean()
    )


def test_a_checkpoint_keeps_the_crop_and_resumes_to_the_same_bits(tmp_path):
    checkpoint = tmp_path / "crop.npz"
    passes = []
    stopped = cropped(
        "embree",
        "sobol",
        workers=1,
        checkpoint=checkpoint,
        on_pass=lambda film: passes.append(film.spp),
        stop=lambda: bool(passes),
    )
    assert not stopped.complete
    assert stopped.spp == SPP_PER_PASS
    resumed = cropped("embree", "sobol", workers=1, resume=checkpoint)
    assert resumed.complete
    assert_same_bits(resumed.image, window_of(whole_image("embree", "sobol")))
    with pytest.raises(PtlabError, match="crop = '5,3,11,9', this render has None"):
        ptlab.render_result(
            "cornell-box",
            spp=SPP,
            res=RES,
            seed=3,
            workers=1,
            tile_size=TILE,
            spp_per_pass=4,
            resume=checkpoint,
        )


def test_the_command_writes_the_window_and_resumes_it(tmp_path, capsys):
    out, checkpoint = tmp_path / "crop.exr", tmp_path / "crop.npz"
    x, y, width, height = CROP
    args = ["render", "cornell-box", "--res", "24x20", "--seed", "3", "--workers", "1", "--out", str(out)]
    assert main([*args, "--spp", "4", "--crop", "5,3,11,9", "--checkpoint", str(checkpoint)]) == 0
    assert "11x9 window at (5, 3) of 24x20, 4 spp" in capsys.readouterr().out
    # Resumed with more samples, the crop given by the checkpoint alone.
    assert main(["render", "--resume", str(checkpoint), "--spp", "8", "--workers", "1"]) == 0
    found = read_image_file(out)
    assert found.window == Window(x, y, *RES)
    assert found.metadata["crop"] == "5,3,11,9"
    assert found.metadata["spp"] == 8
    whole = ptlab.render("cornell-box", spp=8, res=RES, seed=3, workers=1)
    assert_same_bits(found.pixels, window_of(whole))
    tif = tmp_path / "crop.tif"
    assert main([*args[:-1], str(tif), "--spp", "1", "--crop", "5,3,11,9", "--quiet"]) == 0
    assert read_image_file(tif).window == Window(x, y, *RES)
    png = tmp_path / "crop.png"
    assert main([*args[:-1], str(png), "--spp", "1", "--crop", "5,3,11,9", "--quiet"]) == 0
    assert read_image_file(png).pixels.shape == (height, width, 3)


def test_the_first_nan_is_named_by_the_images_pixel(monkeypatch):
    original = Diffuse.eval

    def broken(self, wo, wi, n):
        f = np.array(original(self, wo, wi, n))
        f[(wi * n).sum(axis=1) < 0.3] = np.nan
        return f

    monkeypatch.setattr(Diffuse, "eval", broken)
    crop = (13, 11, 11, 9)  # (the window's pixels and the film's share no coordinates)
    result = ptlab.render_result("cornell-box", spp=2, res=RES, workers=1, crop=crop)
    assert result.nonfinite > 0
    assert result.first_nonfinite is not None
    x, y, _ = result.first_nonfinite
    assert 13 <= x < 24
    assert 11 <= y < 20


@pytest.mark.parametrize(
    ("crop", "said"),
    [
        ("20,0,5,5", "crop 20,0,5,5: the window (columns 20-24, rows 0-4) is not inside the 24x20 image"),
        ("0,16,4,5", "is not inside the 24x20 image"),
        ("0,0,0,5", "crop 0,0,0,5: the window is empty"),
        ("0,0,5", "crop '0,0,5': expected X,Y,W,H, four whole numbers"),
        ("0,0,5,2.5", "expected X,Y,W,H, four whole numbers"),
        ("a,b,c,d", "expected X,Y,W,H, four whole numbers"),
        ("-1,0,5,5", "crop -1,0,5,5: X and Y must be 0 or more"),
    ],
)
def test_a_bad_crop_is_one_line_and_exit_2(crop, said, capsys, tmp_path):
    args = ["render", "cornell-box", "--res", "24x20", "--spp", "1", f"--crop={crop}"]
    assert main([*args, "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert said in err
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("crop", [(0, 0, 5), (0, 0, 5.0, 5), (0, 0, True, 5), "0,0,5", None])
def test_render_takes_a_crop_of_four_whole_numbers(crop):
    if crop is None:  # (None: the whole image)
        assert ptlab.render("cornell-box", spp=1, res=(6, 4), workers=1, crop=crop).shape == (4, 6, 3)
        return
    with pytest.raises(PtlabError, match="four whole numbers"):
        ptlab.render("cornell-box", spp=1, res=(6, 4), workers=1, crop=crop)


def test_a_crops_spp_map_records_its_window_and_a_black_window_blames_no_light(tmp_path, capsys):
    out, spp_map = tmp_path / "crop.exr", tmp_path / "spp.exr"
    args = ["render", "cornell-box", "--res", "24x20", "--workers", "1", "--spp", "2", "--quiet"]
    assert main([*args, "--crop", "5,3,11,9", "--out", str(out), "--spp-map", str(spp_map)]) == 0
    assert read_image_file(spp_map).window == read_image_file(out).window == Window(5, 3, *RES)
    # The floor's corner, with direct light only: black, in a lit image.
    assert main([*args, "--max-depth", "0", "--crop", "0,16,4,4", "--out", str(out)]) == 0
    said = capsys.readouterr().err
    assert "ptlab: warning: the window is black" in said
    assert "do the lights face the scene" not in said


def test_a_crop_in_a_file_that_cannot_say_where_says_so(tmp_path, capsys):
    for name, said in (("crop.png", True), ("crop.exr", False)):
        out = tmp_path / name
        assert (
            main(
                [
                    "render",
                    "cornell-box",
                    "--res",
                    "24x20",
                    "--workers",
                    "1",
                    "--spp",
                    "1",
                    "--crop",
                    "5,3,11,9",
                    "--out",
                    str(out),
                ]
            )
            == 0
        )
        assert ("does not record the window's place" in capsys.readouterr().out) is said
