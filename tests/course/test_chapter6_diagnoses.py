"""Chapter 6's diagnosis of a sample flipped into n's hemisphere (``samples_flipped``), from
the values of small materials in this process (no grading subprocess)."""

import math

import numpy as np
import pytest

from ptlab.course.chapter import grading_seed
from ptlab.course.chapters.ch06_diffuse import known_mistake
from ptlab.sampling import to_world


def cosine_local(u: np.ndarray) -> np.ndarray:
    """Malley's method: a cosine-weighted direction around +z."""
    r, phi = np.sqrt(u[:, 0]), 2 * math.pi * u[:, 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u[:, 0])], axis=1)


class RightCosine:
    """The chapter's answer: the cosine sample turned to n, pdf cos(theta_i) / pi."""

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return above[:, None] * np.full(3, 0.8 / math.pi)

    def sample(self, wo, n, u):
        return to_world(cosine_local(u), n)

    def pdf(self, wo, wi, n):
        cos_i = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_i > 0), cos_i / math.pi, 0.0)


class FlippedCosine(RightCosine):
    """The cosine sample left around +z, negated where it is below n's surface (float32)."""

    def sample(self, wo, n, u):
        local = cosine_local(u).astype(np.float32)
        return local * np.sign(np.sum(local * n, axis=1))[:, None]


@pytest.mark.parametrize("seed", [1, 2])
def test_a_flipped_sample_is_named_and_a_right_one_is_not(seed):
    with grading_seed(seed):
        flipped = known_mistake(FlippedCosine())
        right = known_mistake(RightCosine())
    assert flipped is not None
    assert "for n = (0, 0, 1) but not for n =" in flipped
    assert "stays around +z whatever n is" in flipped
    assert "to_world(local, n)" in flipped
    assert right is None
