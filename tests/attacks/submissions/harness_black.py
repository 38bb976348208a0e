"""A material that is consistent but reflects nothing: cosine sampling with its right pdf,
and eval 0 everywhere (a black surface). Every statistical check holds for it. ``ptlab grade``
passes it but says so ("reflects nothing"); the exercises give its harness no points: the
chapter asks for a material that reflects its albedo."""

import math

import numpy as np

from ptlab.sampling import cosine_hemisphere_around


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
