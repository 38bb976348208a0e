"""A right chapter-6 answer, written into the exercise file as a student would: uniform
hemisphere sampling (the homework's), not the library's cosine sampling. It must get full
marks, and ``ptlab grade`` must find nothing to warn about in it (float32 in, float32 out,
with the exercise file's own ``__init__``)."""

import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import to_world
from ptlab.vectors import dot


class Lambertian(Material):
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return above[:, None] * self.albedo / math.pi

    def sample(self, wo, n, u):
        cos_theta = u[:, 0]
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta * cos_theta))
        phi = 2 * math.pi * u[:, 1]
        local = np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1)
        return to_world(local, n)

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return (above / (2 * math.pi)).astype(wi.dtype)
