"""A right chapter-9 answer, written into the exercise file as a student would: Walter's
sampling of D(h) cos(theta_h) (the exercise file's hint), not the library's visible normals.
It must get full marks, and ``ptlab grade`` must find nothing to warn about in it.
"""

import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import cosine_hemisphere, to_world
from ptlab.scattering import reflect
from ptlab.vectors import dot, normalize


def D(cos_theta_h, alpha):  # noqa: N802
    alpha2 = alpha * alpha
    denominator = cos_theta_h * cos_theta_h * (alpha2 - 1) + 1
    return alpha2 / (math.pi * denominator * denominator)


def Lambda(cos_theta, alpha):  # noqa: N802
    cos2 = cos_theta * cos_theta
    return (np.sqrt(1 + alpha * alpha * (1 - cos2) / cos2) - 1) / 2


def G1(cos_theta, alpha):  # noqa: N802
    return 1 / (1 + Lambda(cos_theta, alpha))


def G2(cos_theta_o, cos_theta_i, alpha):  # noqa: N802
    return 1 / (1 + Lambda(cos_theta_o, alpha) + Lambda(cos_theta_i, alpha))


def fresnel_schlick(cos_theta, f0):
    return f0 + (1 - f0) * (1 - np.clip(cos_theta, 0, 1))[:, None] ** 5


class GGXMetal(Material):
    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling="ggx"):
        self.f0 = np.asarray(f0, dtype=np.float32)
        self.alpha = float(alpha)
        self.sampling = sampling

    def eval(self, wo, wi, n):
        cos_o, cos_i = dot(wo, n), dot(wi, n)
        above = (cos_o > 0) & (cos_i > 0)
        cos_o, cos_i = np.maximum(cos_o, 1e-7), np.maximum(cos_i, 1e-7)
        h = normalize(wo + wi)
        specular = D(dot(h, n), self.alpha) * G2(cos_o, cos_i, self.alpha) / (4 * cos_o * cos_i)
        return fresnel_schlick(dot(wo, h), self.f0) * (specular * above)[:, None]

    def sample(self, wo, n, u):
        if self.sampling == "hemisphere":
            return to_world(cosine_hemisphere(u), n)
        tan2_theta = self.alpha**2 * u[:, 0] / (1 - u[:, 0])
        cos_theta = 1 / np.sqrt(1 + tan2_theta)
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta**2))
        phi = 2 * math.pi * u[:, 1]
        local = np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta], axis=1)
        return reflect(wo, to_world(local, n))

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        if self.sampling == "hemisphere":
            return np.where(above, dot(wi, n) / math.pi, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):    # wi = -wo has no half vector
            h = normalize(wo + wi)
            density = D(dot(h, n), self.alpha) * dot(h, n) / (4 * np.abs(dot(wo, h)))
        return np.where(above, density, 0.0)
