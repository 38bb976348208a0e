"""An attack on the material harness with a material that does nothing: ``sample`` returns
-n (below the surface, so pdf 0 there: every sample "fails", as a sampler may now and then),
and eval and pdf are 0 everywhere. Every check of consistency holds for it (nothing NaN,
nothing negative, 0 below the surface), the chi-square expects every sample to fail, and it
reflects no light, so no energy is created: the old harness passed it."""

import numpy as np


class Lambertian:
    def __init__(self, *args):
        pass

    def eval(self, wo, wi, n):
        return np.zeros((len(wo), 3), dtype=wo.dtype)

    def pdf(self, wo, wi, n):
        return np.zeros(len(wo), dtype=wo.dtype)

    def sample(self, wo, n, u):
        return -np.asarray(n)


GGXMetal = Lambertian
