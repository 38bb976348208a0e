"""Deliberately wrong materials: each makes one classic mistake the grader must name.

Used by ``tests/test_grading.py`` (and handy for ``ptlab grade tests/wrong_materials.py:NAME``).
Each class says its mistake in its docstring; ``WalterSampling`` is the one correct material
here, the reference for ``HalfVectorPdfWithoutJacobian``.
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.materials import Dielectric, Diffuse, Microfacet, Mirror
from ptlab.materials.base import Material
from ptlab.materials.microfacet import G1, D
from ptlab.sampling import cosine_hemisphere, to_world, uniform_hemisphere
from ptlab.scattering import F_schlick, fresnel_dielectric, reflect, refract
from ptlab.vectors import dot, normalize, vec3

ALBEDO = (0.8, 0.6, 0.4)


class _Lambertian(Material):
    """A plain Lambertian material written the way a student would, to break one piece at a time."""

    albedo = np.array(ALBEDO)

    def eval(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return above[:, None] * self.albedo / math.pi

    def pdf(self, wo, wi, n):
        cos_theta_i = dot(wi, n)
        return np.where((dot(wo, n) > 0) & (cos_theta_i > 0), cos_theta_i / math.pi, 0.0)

    def sample(self, wo, n, u):
        return to_world(cosine_hemisphere(u), n)


class MissingCosineInPdf(_Lambertian):
    """Cosine sampling, but pdf = 1/pi: the cosine of cos(theta)/pi forgotten."""

    def pdf(self, wo, wi, n):
        return np.where((dot(wo, n) > 0) & (dot(wi, n) > 0), 1 / math.pi, 0.0)


class MissingCosineInWeight(_Lambertian):
    """sample_weight returns f / pdf: the cosine of the rendering equation forgotten."""

    def sample_weight(self, wo, n, u, front=None):
        wi = self.sample(wo, n, u)
        pdf = self.pdf(wo, wi, n)
        return wi, self.eval(wo, wi, n) / np.where(pdf > 0, pdf, 1)[:, None]


class CosineTwice(_Lambertian):
    """eval includes cos(theta_i), which the renderer multiplies by again."""

    def eval(self, wo, wi, n):
        return super().eval(wo, wi, n) * np.maximum(dot(wi, n), 0)[:, None]


class PdfOffByConstant(_Lambertian):
    """pdf = cos(theta) / (2 pi): half of what cosine sampling gives."""

    def pdf(self, wo, wi, n):
        return super().pdf(wo, wi, n) / 2


class UniformSamplingCosinePdf(_Lambertian):
    """Uniform hemisphere sampling, but the pdf of cosine sampling."""

    def sample(self, wo, n, u):
        return to_world(uniform_hemisphere(u), n)


class CosineSamplingUniformPdf(_Lambertian):
    """Cosine sampling, but the pdf 1/(2 pi) of uniform sampling."""

    def pdf(self, wo, wi, n):
        return np.where((dot(wo, n) > 0) & (dot(wi, n) > 0), 1 / (2 * math.pi), 0.0)


class WrongHemisphere(_Lambertian):
    """sample turns the local frame around -n: every direction lands below the surface."""

    def sample(self, wo, n, u):
        return to_world(cosine_hemisphere(u), -n)


class AlbedoAboveOne(Diffuse):
    """A Lambertian surface with albedo 1.5: it makes light."""

    def __init__(self):
        super().__init__(albedo=(1.5, 1.5, 1.5))


class MissingOneOverPi(_Lambertian):
    """f_r = albedo instead of albedo / pi: reflects pi times too much."""

    def eval(self, wo, wi, n):
        return super().eval(wo, wi, n) * math.pi


class RightOnlyForRepeatedRows:
    """Right only when every row of a call holds the same wo and the same n (as the grader's
    probes once did), and pi times too bright otherwise, as in every render. A plain class,
    as a student writes it."""

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        repeated = bool((wo == wo[:1]).all() and (n == n[:1]).all())
        return np.outer(above * (1.0 if repeated else math.pi) * 0.8 / math.pi, np.ones(3))

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        return to_world(cosine_hemisphere(u), n)


class DependsOnCallSize(_Lambertian):
    """eval is pi times too bright in calls of fewer than 1000 rows: the answer for a row
    depends on how many rows the call has."""

    def eval(self, wo, wi, n):
        return super().eval(wo, wi, n) * (math.pi if len(wo) < 1000 else 1.0)


class DependsOnRowOrder(_Lambertian):
    """sample turns row k's u into row k-1's direction (np.roll): the right distribution,
    but each row's answer depends on its neighbour."""

    def sample(self, wo, n, u):
        return super().sample(wo, n, np.roll(u, 1, axis=0))


class DependsOnMeanWo(_Lambertian):
    """eval's brightness follows the batch's mean cos(theta_o), computed once from the mean
    of wo over the rows (a shortcut that holds only when every row has the same wo)."""

    def eval(self, wo, wi, n):
        mean_cos_theta_o = float(np.mean(dot(wo, n)))
        return super().eval(wo, wi, n) * (0.5 + 0.5 * max(mean_cos_theta_o, 0.0))


class NonReciprocal(Microfacet):
    """A GGX metal masked by G1(wo) only, instead of G2(wo, wi): not symmetric in wo, wi."""

    def __init__(self):
        super().__init__(f0=(0.9, 0.6, 0.5), alpha=0.3)

    def eval(self, wo, wi, n):
        cos_theta_o, cos_theta_i = dot(wo, n), dot(wi, n)
        above = (cos_theta_o > 0) & (cos_theta_i > 0)
        cos_o, cos_i = np.maximum(cos_theta_o, 1e-7), np.maximum(cos_theta_i, 1e-7)
        h = normalize(wo + wi)
        F = F_schlick(dot(wo, h), self.f0)  # noqa: N806
        specular = D(dot(h, n), self.alpha) * G1(cos_o, self.alpha) / (4 * cos_o * cos_i) * above
        return F * specular[:, None]


class NanAtGrazing(Microfacet):
    """A GGX metal whose Lambda divides by cos(theta) unguarded: NaN at grazing angles."""

    def __init__(self):
        super().__init__(f0=(0.9, 0.6, 0.5), alpha=0.3)

    def eval(self, wo, wi, n):
        cos_theta_o, cos_theta_i = dot(wo, n), dot(wi, n)
        h = normalize(wo + wi)
        alpha2 = self.alpha**2
        with np.errstate(divide="ignore", invalid="ignore"):
            lambda_o = (np.sqrt(1 + alpha2 * (1 - cos_theta_o**2) / cos_theta_o**2) - 1) / 2
            lambda_i = (np.sqrt(1 + alpha2 * (1 - cos_theta_i**2) / cos_theta_i**2) - 1) / 2
            specular = D(dot(h, n), self.alpha) / (1 + lambda_o + lambda_i) / (4 * cos_theta_o * cos_theta_i)
        specular = np.where((cos_theta_o >= 0) & (cos_theta_i >= 0), specular, 0)
        return F_schlick(dot(wo, h), self.f0) * specular[:, None]


class WalterSampling(Microfacet):
    """Correct: GGX normals drawn with density D(h) cos(theta_h) (Walter et al. 2007, eq. 35-36).

    pdf(wi) = D(h) cos(theta_h) / (4 |wo . h|): the density of h times the Jacobian of the
    reflection h -> wi.
    """

    def __init__(self, alpha: float = 0.5):
        super().__init__(f0=(0.9, 0.6, 0.5), alpha=alpha)

    def sample(self, wo, n, u):
        tan2_theta = self.alpha**2 * u[:, 0] / (1 - u[:, 0])
        cos_theta = 1 / np.sqrt(1 + tan2_theta)
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta**2))
        phi = 2 * math.pi * u[:, 1]
        h = to_world(vec3(sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta), n)
        return reflect(wo, h)

    def half_vector_pdf(self, wo, wi, n):
        h = normalize(wo + wi)
        cos_theta_h = dot(h, n)
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return np.where(above, D(cos_theta_h, self.alpha) * cos_theta_h, 0.0), h

    def pdf(self, wo, wi, n):
        pdf_h, h = self.half_vector_pdf(wo, wi, n)
        return pdf_h / (4 * np.maximum(np.abs(dot(wo, h)), 1e-12))


class HalfVectorPdfWithoutJacobian(WalterSampling):
    """Walter's sampling, but pdf returns the density of h: the 1 / (4 |wo . h|) forgotten."""

    def pdf(self, wo, wi, n):
        return self.half_vector_pdf(wo, wi, n)[0]


# -- delta materials ----------------------------------------------------------------------


class MirrorOfIncomingDirection(Mirror):
    """GAMES101's reflect(I, N) = I - 2 (I . N) N applied to wo, which points away: wrong side."""

    def sample_weight(self, wo, n, u, front=None):
        return wo - (2 * dot(wo, n))[:, None] * n, np.ones_like(wo)

    def sample(self, wo, n, u, front=None):
        return self.sample_weight(wo, n, u)[0]


class MirrorWithEval(Mirror):
    """eval returns the reflectance: a delta material's eval must be 0."""

    def eval(self, wo, wi, n):
        return np.tile(self.reflectance, (len(wi), 1))


class _Glass(Dielectric):
    """Smooth glass written the way a student would (n outward, wo . n < 0 inside, no ``front``)."""

    def eta_rel(self, outside):
        return np.where(outside, self.eta, 1 / self.eta)

    def sample_weight(self, wo, n, u):
        cos_theta_o = dot(wo, n)
        outside = cos_theta_o > 0
        n = np.where(outside[:, None], n, -n)
        eta_rel = self.eta_rel(outside)
        R = fresnel_dielectric(np.abs(cos_theta_o), eta_rel)  # noqa: N806
        reflected = u[:, 0] < R
        wi = np.where(reflected[:, None], reflect(wo, n), refract(wo, n, eta_rel))
        return wi, self.weights(reflected, R, eta_rel)

    def weights(self, reflected, R, eta_rel):  # noqa: N803
        return np.where(reflected, 1.0, 1 / eta_rel**2)[:, None] * np.ones(3)

    def sample(self, wo, n, u):
        return self.sample_weight(wo, n, u)[0]


class GlassWithoutInversion(_Glass):
    """Uses eta on both sides: leaving the glass it should be 1/eta (and totally reflect)."""

    def eta_rel(self, outside):
        return np.full(len(outside), self.eta)


class GlassWeightedByFresnel(_Glass):
    """Chooses by Fresnel and multiplies by it too: the Fresnel factor counted twice."""

    def weights(self, reflected, R, eta_rel):  # noqa: N803
        return np.where(reflected, R, (1 - R) / eta_rel**2)[:, None] * np.ones(3)


__all__ = [
    "AlbedoAboveOne",
    "CosineSamplingUniformPdf",
    "CosineTwice",
    "DependsOnCallSize",
    "DependsOnMeanWo",
    "DependsOnRowOrder",
    "GlassWeightedByFresnel",
    "GlassWithoutInversion",
    "HalfVectorPdfWithoutJacobian",
    "MirrorOfIncomingDirection",
    "MirrorWithEval",
    "MissingCosineInPdf",
    "MissingCosineInWeight",
    "MissingOneOverPi",
    "NanAtGrazing",
    "NonReciprocal",
    "PdfOffByConstant",
    "RightOnlyForRepeatedRows",
    "UniformSamplingCosinePdf",
    "WalterSampling",
    "WrongHemisphere",
]
