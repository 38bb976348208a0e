"""A material that is consistent but reflects nothing: cosine sampling with its right pdf,
and eval 0 everywhere (a black surface). Every statistical check holds for it. ``ptlab grade``
passes it but says so ("reflects nothing"); the exercises give its harness no points: the
chapter asks for a material that reflects its albedo."""

import math

import numpy as np

from ptlab.sampling import to_world


def cosine_hemisphere_around(n, u):
    """Cosine-weighted directions around n (Malley's method), written as a student would."""
    r, phi = np.sqrt(u[:, 0]), 2 * math.pi * u[:, 1]
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - u[:, 0]))], axis=1)
    return to_world(local, n)


class Lambertian:
    def __init__(self, *args):
        pass

    def eval(self, wo, wi, n):
        return np.zeros((len(wo), 3), dtype=wo.dtype)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        above = (np.sum(wo * n, axis=1) > 0) & (cos_theta > 0)
        return np.where(above, cos_theta / math.pi, 0.0).astype(wi.dtype)

    def sample(self, wo, n, u):
        return cosine_hemisphere_around(n, u).astype(wo.dtype)


GGXMetal = Lambertian
