"""A typical wrong chapter-6 answer: ``eval`` returns one number per row, an (N,) array,
instead of a colour per row, (N, 3). The graders must say so once, with both shapes, not
report a broadcasting error from inside the renderer or repeat the shape in every check of
the harness."""


import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import to_world
from ptlab.vectors import dot

EXPECTED_FAILURES = ("eval", "material harness", "render")
#: The shape said once, expected and returned; no broadcasting error from the renderer.
EXPECTED_HINTS = {"material harness": ("shape (5, 3)", "shape (5,)"), "render": ("shape (5, 3)",)}
MISLEADING_HINTS = {"render": ("broadcast", "outside your file"), "material harness": ("chi-square",)}


class Lambertian(Material):
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return above * float(self.albedo.mean()) / math.pi      # (the bug: (N,), not (N, 3))

    def sample(self, wo, n, u):
        cos_theta = u[:, 0]
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta * cos_theta))
        phi = 2 * math.pi * u[:, 1]
        local = np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1)
        return to_world(local, n)

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return (above / (2 * math.pi)).astype(wi.dtype)
