"""What the checks hand to the student's code that the library does not have.

The student's process rebuilds whatever a check sends it from the classes of its kit
(``ptlab.course.sandbox.kit``), which holds no exercise but this module: a check's own object
of a class defined here reaches the student's code as it is. Chapters whose answer one of
these computes leave it out of their kit like the rest of their answers.
"""

from __future__ import annotations

import math

import numpy as np


class FlakyDiffuse:
    """A Lambertian material whose ``sample`` fails for a quarter of the u (u[:, 0] >= 0.75):
    it returns -n there, below the surface, where eval and pdf are 0 (the material contract
    allows this; microfacet sampling does it at grazing angles)."""

    emission = None
    is_delta = False

    def eval(self, wo, wi, n):
        from ptlab.vectors import dot

        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return np.outer(above * (0.7 / math.pi), np.ones(3)).astype(wi.dtype)

    def pdf(self, wo, wi, n):
        from ptlab.vectors import dot

        cos_theta = dot(wi, n)
        return np.where((dot(wo, n) > 0) & (cos_theta > 0), cos_theta / math.pi, 0).astype(wi.dtype)

    def sample(self, wo, n, u):
        from ptlab.sampling import cosine_hemisphere_around

        wi = cosine_hemisphere_around(n, u.astype(n.dtype))
        return np.where((u[:, 0] >= 0.75)[:, None], -n, wi)

    def sample_weight(self, wo, n, u, front=None):
        from ptlab.materials.base import Material

        return Material.sample_weight(self, wo, n, u)
