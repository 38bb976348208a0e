"""A trivial chapter-6 answer: a material that reflects nothing (eval 0), always returns
the normal, and never samples (pdf 0). Nothing it says contradicts itself, so the material
harness (chi-square, normalisation, energy, reciprocity, consistency) finds no fault."""

import numpy as np

from ptlab.materials import Material


class Lambertian(Material):
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        return np.zeros(wo.shape, dtype=wo.dtype)

    def sample(self, wo, n, u):
        return np.array(n, copy=True)

    def pdf(self, wo, wi, n):
        return np.zeros(len(wo), dtype=wi.dtype)
