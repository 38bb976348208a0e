"""A typical wrong chapter-6 answer: uniform hemisphere sampling with the pdf 1 / (4 pi).

1 / (4 pi) is the uniform density over the whole *sphere*; ``sample`` only draws from the
hemisphere, whose uniform density is 1 / (2 pi). The pdf is 2x too small, so every bounce's
weight f cos / pdf is 2x too big: the indirect light grows at every bounce.
"""

import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import to_world
from ptlab.vectors import dot

EXPECTED_FAILURES = ("pdf integrates to 1", "material harness", "render")


class Lambertian(Material):
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float64)

    def eval(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return above[:, None] * self.albedo / math.pi

    def sample(self, wo, n, u):
        cos_theta = u[:, 0]
        sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
        phi = 2 * math.pi * u[:, 1]
        local = np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1)
        return to_world(local, n)

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return np.where(above, 1 / (4 * math.pi), 0.0)
