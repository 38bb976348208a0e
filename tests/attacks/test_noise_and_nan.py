"""Attacks on the render checks' statistics and comparisons: noise that would widen a test
whose standard error came from the student's own passes, and NaN, which every "more than
the tolerance off" lets through. Each earns nothing for the checks it aims at, and the
message says why: "too noisy" with the factor a right answer stays within, or where the NaN
is."""

from __future__ import annotations

import re

import pytest

from ptlab.course import chapter
from ptlab.course.grader import grade
from ptlab.course.renders import NOISE_RATIO

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes


def _results(path, number: int) -> dict:
    return {r.name: r for r in grade(chapter(number), path, timeout_scale=2.0).results}


def test_a_loop_that_traces_nothing_and_adds_huge_noise_is_too_noisy(attack):
    results = _results(attack("07_noise_only.py"), 7)
    assert sum(r.points for r in results.values()) == 0
    for name in ("white furnace", "Cornell box"):
        message = results[name].message
        assert "too noisy" in message, message
        assert f"at most {NOISE_RATIO:g} times" in message, message


def test_nan_written_into_the_film_fails_and_says_where(attack):
    results = _results(attack("07_nan_film.py"), 7)
    loop = ("light not black", "lights one-sided", "white furnace", "Cornell box")
    assert sum(results[name].points for name in loop) == 0  # (its pieces are right)
    for name in loop:
        message = results[name].message
        assert "has NaN at pixel (x=" in message, message
    # (Which pixel and pass depends on the film's layout, which the attack writes into: a
    # render's film has a row per path.)
    assert re.search(r"in pass \d+ of 12", results["Cornell box"].message)


def test_a_nan_ray_in_chapter_1s_render_fails_it(attack):
    results = _results(attack("01_nan_ray.py"), 1)
    assert all(r.passed for name, r in results.items() if name != "render")
    render = results["render"]
    assert render.points == 0
    assert "NaN at row" in render.message, render.message
    assert "pixel x=20, y=10" in render.message, render.message


def test_nan_mis_weights_in_chapter_10s_render_fail_it(attack):
    results = _results(attack("10_nan_in_the_render.py"), 10)
    assert all(r.passed for name, r in results.items() if name != "render")
    render = results["render"]
    assert render.points == 0
    assert "returned NaN for pdf = " in render.message, render.message
