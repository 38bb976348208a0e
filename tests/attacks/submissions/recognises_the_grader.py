"""An attack on ``ptlab grade``: a Lambertian that is right only when a call's rows all hold
the same wo and the same n (as the old grader's probes did, one wo repeated on every row),
and pi times too bright otherwise, as it is in every render. The old ``ptlab grade`` said
PASSED to all eight checks; its probes now turn every row by a rotation of its own."""

import math

import numpy as np

ALBEDO = 0.8


def _looks_like_a_probe(wo, n):
    """Every row of wo is the first one, and every row of n too."""
    return bool((wo == wo[:1]).all() and (n == n[:1]).all())


class Lambertian:
    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        brightness = 1.0 if _looks_like_a_probe(wo, n) else math.pi
        return np.outer(above * brightness * ALBEDO / math.pi, np.ones(3))

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        from ptlab.sampling import cosine_hemisphere_around
        return cosine_hemisphere_around(n, u)
