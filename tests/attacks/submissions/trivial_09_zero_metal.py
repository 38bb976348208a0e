"""A trivial chapter-9 answer: D 0, G 1, F = F0, and a metal that reflects nothing (eval 0),
always returns the normal and never samples (pdf 0): both material harnesses find no
fault in it."""

import numpy as np

from ptlab.materials import Material


def D(cos_theta_h, alpha):  # noqa: N802 (the exercise's name)
    return np.zeros_like(np.asarray(cos_theta_h, dtype=np.float64))


def G1(cos_theta, alpha):  # noqa: N802
    return np.ones_like(np.asarray(cos_theta, dtype=np.float64))


def G2(cos_theta_o, cos_theta_i, alpha):  # noqa: N802
    return np.ones_like(np.asarray(cos_theta_o, dtype=np.float64))


def fresnel_schlick(cos_theta, f0):
    return np.broadcast_to(np.asarray(f0, dtype=np.float64), np.shape(cos_theta) + (3,)).copy()


class GGXMetal(Material):
    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling="ggx"):
        self.f0 = np.asarray(f0, dtype=np.float32)
        self.alpha, self.sampling = float(alpha), sampling

    def eval(self, wo, wi, n):
        return np.zeros(wo.shape, dtype=wo.dtype)

    def sample(self, wo, n, u):
        return np.array(n, copy=True)

    def pdf(self, wo, wi, n):
        return np.zeros(len(wo), dtype=wi.dtype)
