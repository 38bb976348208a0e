"""The render comparisons of the exercises (``ptlab.course.renders``) and chapter 7's furnace
verdict, on made-up passes: normal region values around a picture, so that each test's
verdict is known. Seeds are fixed; with these sizes a right answer fails a comparison with
probability at most 1.1e-3 (``FALSE_ALARM`` + ``NOISE_FALSE_ALARM``), and the seeds below
are ones where it does not."""

from __future__ import annotations

import numpy as np
import pytest

from ptlab.course.chapter import CheckFailed
from ptlab.course.chapters.ch07_path_tracing import furnace_radiance, furnace_verdict
from ptlab.course.renders import NOISE_RATIO, compare_renders

PASSES, SIZE = 12, 16


def picture(rng) -> np.ndarray:
    """(SIZE, SIZE, 3) positive values: a picture that is not flat."""
    return 0.2 + rng.random((SIZE, SIZE, 3))


def passes_of(rng, mean: np.ndarray, noise: float, count: int = PASSES) -> np.ndarray:
    """(count, SIZE, SIZE, 3): independent passes of ``mean`` with normal noise per pixel."""
    return mean + noise * rng.normal(size=(count, *mean.shape))


def test_a_right_answer_with_noise_of_its_own_passes():
    rng = np.random.default_rng(1)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.1)
    note = compare_renders(passes_of(rng, mean, 0.1 * np.sqrt(2)), library, "the box")
    assert note.startswith("the box: every region within")
    assert "no noisier" in note


def test_the_same_random_numbers_make_a_sharp_test():
    rng = np.random.default_rng(2)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.1)
    compare_renders(library * (1 + 1e-4), library, "the box")  # rounding passes
    with pytest.raises(CheckFailed, match=r"brighter .1.05x"):
        compare_renders(library * 1.05, library, "the box")  # 5% too bright fails


def test_library_plus_big_zero_mean_noise_is_too_noisy_and_names_the_factor():
    rng = np.random.default_rng(3)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.1)
    student = library + rng.normal(scale=30.0, size=library.shape)
    with pytest.raises(CheckFailed) as failure:
        compare_renders(student, library, "the box")
    assert "the box: too noisy" in str(failure.value)
    assert f"a right answer's is at most {NOISE_RATIO:g} times" in str(failure.value)


def test_nothing_but_noise_is_too_noisy_and_differs():
    rng = np.random.default_rng(4)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.1)
    with pytest.raises(CheckFailed, match=r"too noisy.*; and .* differ from the library's"):
        compare_renders(rng.normal(scale=100.0, size=library.shape), library, "the box")


def test_noise_cannot_widen_the_test_below_the_noise_verdict():
    """A wrong picture (10% too dark) with as much added noise as the noise test lets through
    still fails: the standard error never exceeds what the library's variance allows."""
    rng = np.random.default_rng(5)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.05)
    student = passes_of(rng, 0.9 * mean, 0.05 * np.sqrt(NOISE_RATIO))
    with pytest.raises(CheckFailed, match="darker"):
        compare_renders(student, library, "the box")


def test_nan_fails_and_says_where():
    rng = np.random.default_rng(6)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.1)
    student = library.copy()
    student[2, 5, 3, 1] = np.nan
    with pytest.raises(
        CheckFailed,
        match=r"the box: your render has NaN at pixel \(x=3, y=5\) "
        r"\(green; .*\) in pass 3 of 12",
    ):
        compare_renders(student, library, "the box")
    student[4, 0, 0, 0] = np.inf
    with pytest.raises(CheckFailed, match="and 1 more NaN or infinite values"):
        compare_renders(student, library, "the box")


def test_a_firefly_in_one_pass_fails_neither_test():
    """A right answer's rare firefly makes one pass of a region many standard deviations too
    bright (here 80, a variance 500 times the library's in that region): the noise test
    looks at half the regions and the mean test at the passes without the most extreme, so
    neither takes it for a mistake."""
    rng = np.random.default_rng(7)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.2)
    student = passes_of(rng, mean, 0.2)
    student[3, :4, :4] += 4.0  # one bright pass of the top left region
    assert "no noisier" in compare_renders(student, library, "the box")


def test_a_spike_in_one_pass_of_every_region_does_not_hide_a_mistake():
    """Big spikes, one pass of each region, widen the student's own spread of the
    differences, not the standard error, and do not move the mean of the other passes."""
    rng = np.random.default_rng(12)
    mean = picture(rng)
    library = passes_of(rng, mean, 0.05)
    student = passes_of(rng, 0.9 * mean, 0.05)
    spikes = 50.0 * rng.choice([-1, 1], size=(4, 4))
    for row in range(4):
        for column in range(4):
            student[rng.integers(PASSES), 4 * row : 4 * row + 4, 4 * column : 4 * column + 4] += spikes[
                row, column
            ]
    with pytest.raises(CheckFailed, match="differ from the library's picture"):
        compare_renders(student, library, "the box")


# -- chapter 7's white furnace -------------------------------------------------------------


def furnace(rng, value: float, noise: float) -> np.ndarray:
    """(8, 16, 16, 3) grey furnace passes around ``value``."""
    grey = value + noise * rng.normal(size=(8, 16, 16, 1))
    return np.repeat(grey, 3, axis=-1)


def test_the_furnace_verdict_passes_a_right_answer():
    rng = np.random.default_rng(8)
    expected = furnace_radiance(10)
    mean, error = furnace_verdict(
        furnace(rng, expected[0], 0.02), furnace(rng, expected[0], 0.02), expected, "the furnace"
    )
    assert abs(mean - expected[0]) < 0.01
    assert error > 0


def test_the_furnace_verdict_fails_big_zero_mean_noise_as_too_noisy():
    rng = np.random.default_rng(9)
    expected = furnace_radiance(10)
    library = furnace(rng, expected[0], 0.02)
    with pytest.raises(CheckFailed, match=r"the furnace: too noisy: .* at most 4 times"):
        furnace_verdict(rng.normal(scale=50.0, size=library.shape), library, expected, "the furnace")


def test_the_furnace_verdict_fails_nan_and_says_where():
    rng = np.random.default_rng(10)
    expected = furnace_radiance(10)
    library = furnace(rng, expected[0], 0.02)
    student = library.copy()
    student[7, 15, 0, 2] = np.nan
    with pytest.raises(
        CheckFailed,
        match=r"your furnace image has NaN at pixel \(x=0, y=15\) "
        r"\(blue; .*\) in pass 8 of 8",
    ):
        furnace_verdict(student, library, expected, "the furnace")


def test_the_furnace_tolerance_comes_from_the_library():
    """A furnace 10% too dark fails however noisy the student's own passes are (within the
    noise test): its standard error is not the tolerance."""
    rng = np.random.default_rng(11)
    expected = furnace_radiance(10)
    library = furnace(rng, expected[0], 0.005)
    student = furnace(rng, 0.9 * expected[0], 0.005 * np.sqrt(NOISE_RATIO))
    with pytest.raises(CheckFailed, match="too dark"):
        furnace_verdict(student, library, expected, "the furnace")
