"""Deliberately wrong materials, each making one classic mistake the grader must catch, and
right ones written otherwise than the library's, which it must pass.

Used by ``tests/renderer/test_grading.py`` (and handy for ``ptlab grade tests/wrong_materials.py:NAME``).
Each class says its mistake (or why it is right) in its docstring; ``WRONG`` and ``RIGHT``
list them. The ones that are plain classes, or build on ``_Lambertian`` or ``_GGX`` (which
use none of the library's materials), can be graded by ``ptlab grade`` too, whose kit
leaves the library's materials out.
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.materials import Dielectric, Diffuse, Microfacet, Mirror
from ptlab.materials.base import Material
from ptlab.materials.microfacet import G1, D
from ptlab.sampling import cosine_hemisphere, to_world, uniform_hemisphere, uniform_sphere
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


# -- more mistakes of diffuse materials -------------------------------------------------------


class SkewedAzimuth(_Lambertian):
    """Cosine-weighted cos(theta), but phi = 2 pi u1^2: the azimuth crowds toward the tangent
    frame's x axis. Every angle to n follows the cosine pdf; on a wall (one normal, one
    frame) a render sees the skew."""

    def sample(self, wo, n, u):
        return super().sample(wo, n, np.column_stack([u[:, 0], u[:, 1] ** 2]))


class SkewedNearAnAxis(_Lambertian):
    """Samples crowded toward n (the disk's radius sqrt(u0^1.3)) only where n is within 10
    degrees of a coordinate axis: right on a tilted surface, wrong on the walls of a room,
    which is where a render of the Cornell box needs it."""

    def sample(self, wo, n, u):
        near = np.max(np.abs(n), axis=1) > math.cos(math.radians(10))
        skewed = np.column_stack([np.where(near, u[:, 0] ** 1.3, u[:, 0]), u[:, 1]])
        return super().sample(wo, n, skewed)


class AzimuthFromTheSameU(_Lambertian):
    """phi = 2 pi u0, from the number that also gives cos(theta): u1 ignored, the samples lie
    on one spiral."""

    def sample(self, wo, n, u):
        return super().sample(wo, n, np.column_stack([u[:, 0], u[:, 0]]))


class DiskWithoutSqrt(_Lambertian):
    """Malley's method with r = u0 instead of sqrt(u0): the disk point is not uniform, so the
    directions do not follow cos(theta) / pi, which pdf says."""

    def sample(self, wo, n, u):
        r, phi = u[:, 0], 2 * math.pi * u[:, 1]
        local = vec3(r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1 - r * r)))
        return to_world(local, n)


class PdfOfCosWo(_Lambertian):
    """pdf = cos(theta_o) / pi: the cosine of wo where the cosine of wi belongs."""

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return np.where(above, dot(wo, n) / math.pi, 0.0)


class WrongHemisphereOnSomeRows(_Lambertian):
    """A quarter of the samples (u0 < 1/4) mirrored below the surface, where pdf is 0."""

    def sample(self, wo, n, u):
        wi = super().sample(wo, n, u)
        return np.where((u[:, 0] < 0.25)[:, None], wi - (2 * dot(wi, n))[:, None] * n, wi)


class UniformSphereHemispherePdf(_Lambertian):
    """Uniform directions over the whole sphere, with the hemisphere's uniform pdf 1/(2 pi)
    above the surface: half the samples land below, which the pdf does not admit."""

    def sample(self, wo, n, u):
        return to_world(uniform_sphere(u), n)

    def pdf(self, wo, wi, n):
        return np.where((dot(wo, n) > 0) & (dot(wi, n) > 0), 1 / (2 * math.pi), 0.0)


class EvalNotZeroBelow(_Lambertian):
    """eval is albedo / pi for every wi, below the surface too."""

    def eval(self, wo, wi, n):
        return np.outer((dot(wo, n) > 0) / math.pi, self.albedo)


class PdfNotClamped(_Lambertian):
    """pdf = cos(theta_i) / pi unclamped: negative below the surface."""

    def pdf(self, wo, wi, n):
        return np.where(dot(wo, n) > 0, dot(wi, n) / math.pi, 0.0)


class SampleNotNormalised(_Lambertian):
    """n + a uniform point of the sphere (the Lambert sphere), not divided by its length."""

    def sample(self, wo, n, u):
        return n + uniform_sphere(u)


class WeightOfUniformSampling(_Lambertian):
    """Cosine sampling, with the weight 2 albedo cos(theta) of uniform sampling in its own
    sample_weight (the weight of the sampling it does is the albedo)."""

    def sample_weight(self, wo, n, u, front=None):
        wi = self.sample(wo, n, u)
        return wi, (2 * np.maximum(dot(wi, n), 0) * (dot(wo, n) > 0))[:, None] * self.albedo


class BrighterWithFewNormals:
    """3x too bright in a call whose rows hold few distinct normals (fewer than a tenth of
    the rows: the walls of a render), right when nearly every row has a normal of its own
    (as the grader's probes once had). A plain class."""

    albedo = np.array(ALBEDO)

    def bright(self, n) -> bool:
        return len(np.unique(np.asarray(n), axis=0)) < len(n) / 10

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return np.outer(above * (3.0 if self.bright(n) else 1.0) / math.pi, self.albedo)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        return to_world(cosine_hemisphere(u), n)


class BrighterWithManyNormals(BrighterWithFewNormals):
    """The other way round: 3x too bright in a call holding more than 1000 distinct normals
    (a curved surface's rows), right on a few walls (the grader's probes now)."""

    def bright(self, n) -> bool:
        return len(np.unique(np.asarray(n), axis=0)) > 1000


class RightOnlyAtTheGradersAngles(_Lambertian):
    """Right where wo or wi is at 0, 45 or 80 degrees from n (the grader's documented angles,
    to 1e-6 in the cosine), twice too bright elsewhere: reciprocal, and right in every lobe
    measured at exactly those angles."""

    def eval(self, wo, wi, n):
        graders = np.cos(np.radians([0.0, 45.0, 80.0]))

        def at_graders(w):
            return (np.abs(dot(w, n)[:, None] - graders) < 1e-6).any(axis=1)

        factor = np.where(at_graders(wo) | at_graders(wi), 1.0, 2.0)
        return super().eval(wo, wi, n) * factor[:, None]


class BrighterInLargeCalls(_Lambertian):
    """Twice too bright in calls of more than 50 000 rows (a render's), right in smaller ones."""

    def eval(self, wo, wi, n):
        return super().eval(wo, wi, n) * (2.0 if len(wo) > 50_000 else 1.0)


# -- right diffuse materials written otherwise -------------------------------------------------


class RightPlainLambertian:
    """Right: the homework's three functions in a class that inherits from nothing, float64."""

    albedo = np.array(ALBEDO)

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return np.outer(above / math.pi, self.albedo)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        return to_world(cosine_hemisphere(u), n)


class RightFloat32Lambertian:
    """Right: every computation in float32 (pi rounded to float32), uniform hemisphere sampling."""

    albedo = np.array(ALBEDO, dtype=np.float32)
    pi = np.float32(math.pi)

    def eval(self, wo, wi, n):
        wo, wi, n = (np.asarray(a, dtype=np.float32) for a in (wo, wi, n))
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return above[:, None] * (self.albedo / self.pi)

    def pdf(self, wo, wi, n):
        wo, wi, n = (np.asarray(a, dtype=np.float32) for a in (wo, wi, n))
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return np.where(above, 1 / (2 * self.pi), np.float32(0))

    def sample(self, wo, n, u):
        return to_world(uniform_hemisphere(np.asarray(u, dtype=np.float32)), np.asarray(n, dtype=np.float32))


class RightFloat64Albedo(_Lambertian):
    """Right: a float64 albedo, which turns float32 arguments into float64 answers (slower,
    and said by a warning, not a failure)."""


# -- rough metals written as a student would (none of the library's materials) -----------------


def ggx_d(cos_theta_h, alpha):
    """GGX's normal distribution (Walter et al. 2007, eq. 33)."""
    alpha2 = alpha * alpha
    denominator = cos_theta_h * cos_theta_h * (alpha2 - 1) + 1
    return alpha2 / (math.pi * denominator * denominator)


def smith_lambda(cos_theta, alpha):
    """Smith's Lambda for GGX (Heitz 2014, eq. 72)."""
    cos2 = cos_theta * cos_theta
    return (np.sqrt(1 + alpha * alpha * (1 - cos2) / cos2) - 1) / 2


def schlick(cos_theta, f0):
    return f0 + (1 - f0) * (1 - np.clip(cos_theta, 0, 1))[:, None] ** 5


class _GGX(Material):
    """A right GGX metal (D G2 F / (4 cos cos), Walter's sampling) written as a student would,
    to break one piece at a time."""

    def __init__(self, f0=(0.9, 0.6, 0.5), alpha: float = 0.3):
        self.f0, self.alpha = np.asarray(f0, dtype=np.float64), float(alpha)

    def D(self, cos_theta_h):  # noqa: N802 (the papers' name)
        return ggx_d(cos_theta_h, self.alpha)

    def fresnel(self, cos_theta):
        return schlick(cos_theta, self.f0)

    def eval(self, wo, wi, n):
        cos_o, cos_i = dot(wo, n), dot(wi, n)
        above = (cos_o > 0) & (cos_i > 0)
        cos_o, cos_i = np.maximum(cos_o, 1e-7), np.maximum(cos_i, 1e-7)
        h = normalize(wo + wi)
        g2 = 1 / (1 + smith_lambda(cos_o, self.alpha) + smith_lambda(cos_i, self.alpha))
        specular = self.D(dot(h, n)) * g2 / (4 * cos_o * cos_i)
        return self.fresnel(dot(wo, h)) * (specular * above)[:, None]

    def sample(self, wo, n, u):
        tan2_theta = self.alpha**2 * u[:, 0] / (1 - u[:, 0])
        cos_theta = 1 / np.sqrt(1 + tan2_theta)
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta**2))
        phi = 2 * math.pi * u[:, 1]
        return reflect(wo, to_world(vec3(sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta), n))

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        with np.errstate(invalid="ignore", divide="ignore"):  # wi = -wo has no half vector
            h = normalize(wo + wi)
            density = self.D(dot(h, n)) * dot(h, n) / (4 * np.abs(dot(wo, h)))
        return np.where(above, density, 0.0)


class RightWalter(_GGX):
    """Right: GGX normals drawn with density D(h) cos(theta_h) (Walter et al. 2007, eqs.
    35-36), reflected; pdf the density of h times the Jacobian 1 / (4 |wo . h|)."""


def heitz_visible_normal(Ve, alpha, U1, U2):  # noqa: N803 (the paper's names)
    """Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)), Listing 1,
    as published, with alpha_x = alpha_y = alpha: (N, 3) local view directions ``Ve`` (+z the
    normal) to (N, 3) local visible normals."""
    # Section 3.2: transforming the view direction to the hemisphere configuration
    Vh = normalize(np.stack([alpha * Ve[:, 0], alpha * Ve[:, 1], Ve[:, 2]], axis=1))  # noqa: N806
    # Section 4.1: orthonormal basis (with special case if cross product is zero)
    lensq = Vh[:, 0] * Vh[:, 0] + Vh[:, 1] * Vh[:, 1]
    T1 = (  # noqa: N806
        np.stack([-Vh[:, 1], Vh[:, 0], np.zeros_like(lensq)], axis=1)
        / np.sqrt(np.where(lensq > 0, lensq, 1))[:, None]
    )
    T1[lensq <= 0] = (1, 0, 0)
    T2 = np.cross(Vh, T1)  # noqa: N806
    # Section 4.2: parameterization of the projected area
    r = np.sqrt(U1)
    phi = 2.0 * math.pi * U2
    t1 = r * np.cos(phi)
    t2 = r * np.sin(phi)
    s = 0.5 * (1.0 + Vh[:, 2])
    t2 = (1.0 - s) * np.sqrt(1.0 - t1 * t1) + s * t2
    # Section 4.3: reprojection onto hemisphere
    z = np.sqrt(np.maximum(0.0, 1.0 - t1 * t1 - t2 * t2))
    Nh = t1[:, None] * T1 + t2[:, None] * T2 + z[:, None] * Vh  # noqa: N806
    # Section 3.4: transforming the normal back to the ellipsoid configuration
    return normalize(np.stack([alpha * Nh[:, 0], alpha * Nh[:, 1], np.maximum(0.0, Nh[:, 2])], axis=1))


class RightVisibleNormals(_GGX):
    """Right: visible normals drawn exactly as Heitz (2018) publishes them (Listing 1), in a
    local frame of the material's own with einsum dot products. At wo = n its ``lensq`` is
    rounding noise, which NumPy's einsum rounds differently for a column-major batch and for
    one row: rows there differ between batchings by rounding, not dependence. pdf(wi) =
    D_wo(h) / (4 wo . h) = G1(wo) D(h) / (4 cos(theta_o)) (Heitz 2018, eq. 17)."""

    def sample(self, wo, n, u):
        helper = np.zeros_like(n)
        helper[:, 0] = np.abs(n[:, 0]) <= 0.9
        helper[:, 1] = np.abs(n[:, 0]) > 0.9
        t = normalize(np.cross(helper, n))
        b = np.cross(n, t)
        ve = np.stack([np.einsum("ij,ij->i", wo, axis) for axis in (t, b, n)], axis=1)
        h = heitz_visible_normal(ve, self.alpha, u[:, 0], u[:, 1])
        return reflect(wo, h[:, :1] * t + h[:, 1:2] * b + h[:, 2:] * n)

    def visible_normal_pdf(self, wo, wi, n):
        """(N,) D_wo(h) for the half vector h of wo and wi, and h."""
        cos_o = np.maximum(dot(wo, n), 1e-7)
        with np.errstate(invalid="ignore", divide="ignore"):
            h = normalize(wo + wi)
            g1 = 1 / (1 + smith_lambda(cos_o, self.alpha))
            density = g1 * np.maximum(dot(wo, h), 0) * self.D(dot(h, n)) / cos_o
        return density, h

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        density, h = self.visible_normal_pdf(wo, wi, n)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(above & (dot(wo, h) > 0), density / (4 * dot(wo, h)), 0.0)


# -- mistakes of rough metals ------------------------------------------------------------------


class GGXAlphaNotSquared(_GGX):
    """D written with alpha where alpha^2 belongs (in eval and pdf), sampled with alpha^2."""

    def D(self, cos_theta_h):  # noqa: N802
        return ggx_d(cos_theta_h, math.sqrt(self.alpha))


class VisibleNormalsPdfWithoutJacobian(RightVisibleNormals):
    """Heitz's visible normals, but pdf returns their density D_wo(h): the Jacobian
    1 / (4 wo . h) of the reflection forgotten."""

    def pdf(self, wo, wi, n):
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        density, h = self.visible_normal_pdf(wo, wi, n)
        return np.where(above & (dot(wo, h) > 0), density, 0.0)


class VisibleNormalsPdfWithG1OfWi(RightVisibleNormals):
    """Heitz's visible normals, but pdf masks with G1(wi) where G1(wo) belongs."""

    def pdf(self, wo, wi, n):
        right = super().pdf(wo, wi, n)
        cos_o, cos_i = np.maximum(dot(wo, n), 1e-7), np.maximum(dot(wi, n), 1e-7)
        return right * (1 + smith_lambda(cos_o, self.alpha)) / (1 + smith_lambda(cos_i, self.alpha))


class FlippedBelow(_GGX):
    """Walter's sampling, but a wi below the surface is mirrored back up instead of failing:
    those directions come twice as often as pdf says."""

    def sample(self, wo, n, u):
        wi = super().sample(wo, n, u)
        return np.where((dot(wi, n) < 0)[:, None], wi - (2 * dot(wi, n))[:, None] * n, wi)


class SchlickTimesFive(_GGX):
    """Schlick's Fresnel with (1 - cos) * 5 where (1 - cos) ** 5 belongs: above 1 toward grazing."""

    def fresnel(self, cos_theta):
        return self.f0 + (1 - self.f0) * ((1 - np.clip(cos_theta, 0, 1)) * 5)[:, None]


class FresnelOfNormal(_GGX):
    """Schlick's Fresnel at n . wo where h . wo belongs: not reciprocal."""

    def eval(self, wo, wi, n):
        h = normalize(wo + wi)
        return super().eval(wo, wi, n) * self.fresnel(dot(wo, n)) / self.fresnel(dot(wo, h))


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


#: The wrong materials: each must fail ``check_material``.
WRONG = [
    "AlbedoAboveOne",
    "SkewedNearAnAxis",
    "AzimuthFromTheSameU",
    "BrighterInLargeCalls",
    "BrighterWithFewNormals",
    "BrighterWithManyNormals",
    "CosineSamplingUniformPdf",
    "CosineTwice",
    "DependsOnCallSize",
    "DependsOnMeanWo",
    "DependsOnRowOrder",
    "DiskWithoutSqrt",
    "EvalNotZeroBelow",
    "FlippedBelow",
    "FresnelOfNormal",
    "GGXAlphaNotSquared",
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
    "PdfNotClamped",
    "PdfOfCosWo",
    "PdfOffByConstant",
    "RightOnlyAtTheGradersAngles",
    "RightOnlyForRepeatedRows",
    "SampleNotNormalised",
    "SchlickTimesFive",
    "SkewedAzimuth",
    "UniformSamplingCosinePdf",
    "UniformSphereHemispherePdf",
    "VisibleNormalsPdfWithG1OfWi",
    "VisibleNormalsPdfWithoutJacobian",
    "WeightOfUniformSampling",
    "WrongHemisphere",
    "WrongHemisphereOnSomeRows",
]

#: The right materials written otherwise than the library's: each must pass (the library's
#: ``Diffuse(0.5)``, a scalar albedo, is the test's own).
RIGHT = [
    "RightFloat32Lambertian",
    "RightFloat64Albedo",
    "RightPlainLambertian",
    "RightVisibleNormals",
    "RightWalter",
    "WalterSampling",
]

__all__ = sorted(WRONG + RIGHT)
