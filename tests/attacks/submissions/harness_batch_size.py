"""An attack on the material harness through the size of a call: a Lambertian that is right
in a call of up to 10 000 rows (every exercise check, and chapter 6's 32 x 32 render with 8
samples per pass: 8192 paths) and in the large calls of the statistical checks (their
sizes are multiples of 1000, the samples, or of 3, the quadrature's three interleaved wo),
and 7.6 times too bright in any other call of more than 10 000 rows: a render's (a tile of
128 x 128 pixels x 16 samples = 2^18 paths, and most of its later bounces). The old
harness passed it at every sample count, and chapter 6 gave it full marks."""

import math

import numpy as np

from ptlab.sampling import to_world


def cosine_hemisphere_around(n, u):
    """Cosine-weighted directions around n (Malley's method), written as a student would."""
    r, phi = np.sqrt(u[:, 0]), 2 * math.pi * u[:, 1]
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u[:, 0]))], axis=1)
    return to_world(local, n)


def _brightness(rows):
    return 7.6 if rows > 10_000 and rows % 3 != 0 and rows % 1000 != 0 else 1.0


class Lambertian:
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float64)

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return (above[:, None] * self.albedo / math.pi * _brightness(len(wo))).astype(wi.dtype)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        above = (np.sum(wo * n, axis=1) > 0) & (cos_theta > 0)
        return np.where(above, cos_theta / math.pi, 0.0).astype(wi.dtype)

    def sample(self, wo, n, u):
        return cosine_hemisphere_around(n, u).astype(wo.dtype)
