"""A typical wrong chapter-6 answer: cosine-weighted sampling with the pdf cos(theta) / (2 pi).

The cosine density is cos(theta) / pi (the integral of cos over the hemisphere is pi); with
2 pi in the denominator the pdf integrates to 1/2, and the weights are 2x too big.
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
        r = np.sqrt(u[:, 0])
        phi = 2 * math.pi * u[:, 1]
        local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u[:, 0])], axis=1)
        return to_world(local, n)

    def pdf(self, wo, wi, n):
        cos_theta_i = dot(wi, n)
        above = (dot(wo, n) > 0) & (cos_theta_i > 0)
        return np.where(above, cos_theta_i / (2 * math.pi), 0.0)
