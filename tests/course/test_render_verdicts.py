"""What the checks say of pictures and numbers that are wrong in the ways issue 36 named: a
render less noisy than the library's is accused of not being a render only when it is the
library's picture in the mean (``ptlab.course.renders.NoiseTest.verdict``); chapter 7's
patterned furnace ties the picture to the samples; chapter 10's densities reach float32's
overflow; chapter 11's films hold pixels whose samples are all alike.

Seeds are fixed. The made-up passes are normal, so the render verdicts' false-alarm rates
hold (``FALSE_ALARM`` + 2 ``NOISE_FALSE_ALARM``, 1.2e-3 a comparison), and the seeds below
are ones where a right answer passes; the chapters' own checks are deterministic.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import uniform_filter

from ptlab.course.chapter import CheckFailed, grading_rng, grading_seed, grading_seed_for
from ptlab.course.chapters import ch07_path_tracing as ch07
from ptlab.course.chapters import ch10_mis as ch10
from ptlab.course.chapters import ch11_noise as ch11
from ptlab.course.renders import compare_renders
from ptlab.rendering import adaptive

ANSWERS = Path(__file__).parents[1] / "exercises"
PASSES, SIZE = 12, 16
#: A pass size of the range the render checks draw (24 to 40): the messages must say it.
SPP = 31


def _passes(rng, mean: np.ndarray, noise: float) -> np.ndarray:
    return mean + noise * rng.normal(size=(PASSES, *mean.shape))


def _answer(name: str):
    """tests/exercises/``name``.py as a module of this process (trusted files only)."""
    spec = importlib.util.spec_from_file_location(name, ANSWERS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# -- the noise verdict's words -------------------------------------------------------------


def test_a_wrong_picture_that_is_less_noisy_is_told_its_difference_not_accused():
    """A wrong D makes a wider highlight, darker and less noisy: the message leads with how
    the picture differs and says the noise as a fact."""
    rng = np.random.default_rng(1)
    mean = 0.2 + rng.random((SIZE, SIZE, 3))
    library = _passes(rng, mean, 0.1)
    student = _passes(rng, 0.7 * mean, 0.01)
    with pytest.raises(CheckFailed) as failure:
        compare_renders(student, library, "the box", "(a hint)", SPP)
    message = str(failure.value)
    assert message.startswith("the box: 48 of 48 regions and colours differ from the library's picture")
    assert f"less noisy than the library's at the same {SPP} samples per pixel" in message
    assert "(a hint)" in message
    assert "not a render" not in message


def test_the_librarys_picture_without_its_noise_is_not_a_render_of_these_samples():
    rng = np.random.default_rng(2)
    mean = 0.2 + rng.random((SIZE, SIZE, 3))
    library = _passes(rng, mean, 0.1)
    converged = np.broadcast_to(library.mean(axis=0), library.shape).copy()
    with pytest.raises(CheckFailed) as failure:
        compare_renders(converged, library, "the box", "(a hint)", SPP)
    message = str(failure.value)
    assert message.startswith(
        f"the box: too clean for {SPP} samples per pixel: this is not a render of these samples"
    )
    assert "(a hint)" not in message  # (the hint says what a brighter or darker picture means)


def test_a_furnace_too_dark_and_too_clean_says_too_dark_first():
    rng = np.random.default_rng(3)
    expected = ch07.furnace_radiance(ch07.FURNACE_DEPTH)
    library = np.repeat(expected[0] + 0.02 * rng.normal(size=(8, 16, 16, 1)), 3, axis=-1)
    student = np.repeat(0.8 * expected[0] + 0.001 * rng.normal(size=(8, 16, 16, 1)), 3, axis=-1)
    with pytest.raises(CheckFailed) as failure:
        ch07.furnace_verdict(student, library, expected, "the furnace")
    message = str(failure.value)
    assert message.startswith("the furnace: your furnace image averages")
    assert "too dark" in message
    assert "less noisy than the library's at the same 8 samples per pixel" in message
    assert "not a render" not in message


# -- chapter 7: the patterned furnace ------------------------------------------------------


def test_the_patterned_furnace_differs_from_patch_to_patch_and_from_grading_to_grading():
    import ptlab

    with grading_seed(5):
        scene = ch07.patterned_furnace_scene(grading_rng(ch07.PATTERN_STREAM))
        again = ch07.patterned_furnace_scene(grading_rng(ch07.PATTERN_STREAM))
    with grading_seed(6):
        other = ch07.patterned_furnace_scene(grading_rng(ch07.PATTERN_STREAM))
    assert scene.name == "scene"  # (nothing that tells it is a furnace)
    assert len(scene.materials) == ch07.PATCHES + 1
    assert np.array_equal(scene.material_ids, again.material_ids)
    assert not np.array_equal(scene.material_ids, other.material_ids)
    # Emission only: each pixel is the Le of what its camera rays hit. The camera sees the
    # inner sphere and several patches of the wall.
    seen = ptlab.render(scene, spp=1, res=32, max_depth=0, seed=1, workers=1).reshape(-1, 3)
    emissions = np.array([m.emission for m in scene.materials], np.float32)
    shown = {k for k, le in enumerate(emissions) if np.isclose(seen, le, rtol=1e-5).all(axis=1).any()}
    assert ch07.PATCHES in shown  # (the inner sphere)
    assert len(shown) >= 4, shown


def test_the_furnace_fake_fails_the_patterned_furnace_and_a_right_loop_passes():
    """tests/exercises/07_wrong_furnace_fake.py's loop adds the furnace's analytic value with
    a render's noise: right in the furnace of one material, not in the patterned one. A
    right loop with random numbers of its own passes (false alarm at most 1.2e-3)."""
    with grading_seed(25):
        seed = grading_seed_for(ch07.PATTERNED_SEED)
        library = ch07.patterned_furnace_passes(seed=seed)
        right = ch07.patterned_furnace_passes(_answer("07_right_own_random").trace_paths, seed)
        fake = ch07.patterned_furnace_passes(_answer("07_wrong_furnace_fake").trace_paths, seed)
    assert "no noisier than a right answer" in compare_renders(right, library, "the furnace")
    with pytest.raises(CheckFailed, match="regions and colours differ from the library's picture"):
        compare_renders(fake, library, "the furnace")


# -- chapter 10: densities past float32's squares ------------------------------------------


def _naive_power(pdf, other):
    total = pdf * pdf + other * other
    return np.where(total > 0, pdf * pdf / np.where(total > 0, total, 1), 0.0)


def test_a_power_heuristic_that_squares_large_float32_densities_fails_naming_the_overflow():
    assert 1.8e19 < ch10.SQUARE_OVERFLOW < 1.9e19
    pdf, other = np.array([3e20, 2.0]), np.array([1e20, 1.0])
    with pytest.raises(CheckFailed, match=r"returned NaN for pdf = 3e\+20.*float32.*overflow"):
        ch10._weights(_naive_power, pdf, other)
    # In float64 the same squares are finite, and the weights right.
    assert np.allclose(ch10._weights(_naive_power, pdf, other, dtype=np.float64), [0.9, 0.8])


def test_a_power_heuristic_that_divides_by_the_larger_density_first_passes_up_to_1e30():
    right = _answer("10_right_own_code")
    rng = np.random.default_rng(4)
    pdf = 10.0 ** rng.uniform(4, 30, 500)
    other = pdf * 10.0 ** rng.uniform(-3, 3, 500)
    for heuristic in ("power", "balance"):
        for dtype in ch10.DTYPES:
            ch10._sum_to_one(right.mis_weight, heuristic, pdf, other, dtype)
    with pytest.raises(CheckFailed, match="overflow"):
        ch10._sum_to_one(lambda p, q, heuristic: _naive_power(p, q), "power", pdf, other, np.float32)


# -- chapter 11: samples all alike ---------------------------------------------------------


def test_a_variance_of_mean_not_clipped_goes_below_0_on_pixels_of_samples_all_alike():
    samples = np.full((1, 1, 5, 3), 0.3)  # (the example: -5.5e-17)
    film = ch11._film(samples, np.array([[5]]))
    sums, squares, _ = film
    unclipped = (squares - sums * sums / 5) / (4 * 5)
    assert (unclipped < 0).any()
    with pytest.raises(CheckFailed) as failure:
        ch11._require_not_negative(unclipped, film, lambda y, x, c: f"pixel ({x}, {y})")
    message = str(failure.value)
    assert "for pixel (0, 0), of 5 samples: a variance is never below 0" in message
    assert "its samples are all 0.3" in message
    assert '"Cancellation"' in message
    ch11._require_not_negative(adaptive.variance_of_mean(*film), film, lambda y, x, c: "")


def test_the_weights_film_makes_an_unclipped_square_root_nan_and_says_why():
    with grading_seed(25):
        sums, squares, counts = ch11._weights_film(grading_rng(113))
    variance = adaptive.variance_of_mean(sums, squares, counts)
    v = adaptive.relative_variance(variance, sums, counts)
    with np.errstate(invalid="ignore"):
        unclipped = np.sqrt(uniform_filter(v, size=7))
    assert np.isnan(unclipped).any()
    assert "clip the pooled values at 0" in ch11._nan_hint(unclipped, variance, sums, counts)
    # The library's weights (clipped) are finite, and 0 in the windows without noise.
    weights = adaptive.allocation_weights(variance, sums, counts)
    assert np.isfinite(weights).all()
    band = ch11.QUIET_BAND
    assert (weights[-band + 3 : -band + 4, : -band - 3] <= 1e-6 * np.median(weights)).all()


# -- chapter 9, graded: a wrong D is not a fake --------------------------------------------


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_wrong_d_is_told_its_picture_differs_not_that_it_is_not_a_render(tmp_path):
    """GGX's D with alpha where alpha^2 belongs (a wider, dimmer lobe) renders a picture much
    less noisy than the library's: an honest mistake, told as a difference."""
    from ptlab.course import chapter
    from ptlab.course.grader import grade

    right = (ANSWERS / "09_right_walter.py").read_text(encoding="utf-8")
    wrong = right.replace("(alpha2 - 1) + 1", "(alpha - 1) + 1").replace(
        "return alpha2 / (math.pi", "return alpha / (math.pi"
    )
    assert wrong.count("alpha / (math.pi") == 1
    path = tmp_path / "09_microfacet.py"
    path.write_text(wrong, encoding="utf-8")
    results = {r.name: r for r in grade(chapter(9), path, seed=25).results}
    message = results["render (importance)"].message
    assert not results["render (importance)"].passed
    assert "differ from the library's picture" in message
    assert "not a render of these samples" not in message
