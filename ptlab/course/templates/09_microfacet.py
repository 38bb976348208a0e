"""Chapter 9: microfacet materials.

The chapter's page: ``ptlab exercise docs 9`` (中文: ``--zh``).

Write the GGX microfacet BRDF of a rough metal, piece by piece: the normal distribution
``D``, Smith's masking ``G1`` and masking-shadowing ``G2``, Schlick's Fresnel
``fresnel_schlick``, then ``GGXMetal.eval`` that puts them together, and finally its
importance sampling (``GGXMetal.sample`` and ``GGXMetal.pdf`` for ``sampling="ggx"``).
Check your work with

    ptlab exercise check 9 09_microfacet.py

Two steps: ``GGXMetal`` already samples the cosine-weighted hemisphere (chapter 6) when
``sampling="hemisphere"``, so once ``eval`` is right the "hemisphere" checks pass; the
importance sampling earns the rest.

Conventions: every direction is a unit vector pointing *away* from the surface (``wo``
toward the viewer, ``wi`` toward the light, ``n`` the unit normal), arrays are (N, 3).
Write whole-array NumPy code, never a Python loop over rays.
"""

import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import cosine_hemisphere, to_world
from ptlab.scattering import reflect
from ptlab.vectors import dot, normalize


def D(cos_theta_h, alpha):  # noqa: N802 (the papers' name)
    """The GGX (Trowbridge-Reitz) normal distribution.

    Args:
        cos_theta_h: (N,) n . h, the cosine of the angle between the microfacet normal h
            and the surface normal n, in [0, 1].
        alpha: the roughness parameter, a float in (0, 1].

    Returns:
        (N,) D(h): the density of microfacet normals (per steradian of h) at h.

    Hints:
        * D(h) = alpha^2 / (pi ((n . h)^2 (alpha^2 - 1) + 1)^2)  (Walter et al. 2007, eq. 33).
        * It is normalised so that the integral of D(h) cos(theta_h) over the hemisphere
          is 1: the projected area of the microfacets is that of the surface.
    """
    raise NotImplementedError("D")


def G1(cos_theta, alpha):  # noqa: N802 (the papers' name)
    """Smith's masking function for GGX: the fraction of microfacets seen from a direction.

    Args:
        cos_theta: (N,) n . w for the direction w, in (0, 1].
        alpha: the roughness parameter, a float.

    Returns:
        (N,) values in [0, 1]; 1 at normal incidence.

    Hints:
        * G1 = 1 / (1 + Lambda), Lambda = (sqrt(1 + alpha^2 tan^2(theta)) - 1) / 2 and
          tan^2(theta) = (1 - cos^2(theta)) / cos^2(theta)  (Heitz 2014, eq. 72).
        * Lambda is needed by ``G2`` too: write it as a small function of its own.
    """
    raise NotImplementedError("G1")


def G2(cos_theta_o, cos_theta_i, alpha):  # noqa: N802 (the papers' name)
    """Smith's height-correlated masking-shadowing function.

    Args:
        cos_theta_o, cos_theta_i: (N,) n . wo and n . wi, in (0, 1].
        alpha: the roughness parameter, a float.

    Returns:
        (N,) 1 / (1 + Lambda(wo) + Lambda(wi))  (Heitz 2014, eq. 99; pbrt-v4 section 9.6.3).
    """
    raise NotImplementedError("G2")


def fresnel_schlick(cos_theta, f0):
    """Schlick's approximation of the Fresnel reflectance, per colour channel.

    Args:
        cos_theta: (N,) the cosine of the angle between the light direction and h.
        f0: (3,) the reflectance at normal incidence (the metal's colour).

    Returns:
        (N, 3): F0 + (1 - F0) (1 - cos_theta)^5.
    """
    raise NotImplementedError("fresnel_schlick")


class GGXMetal(Material):
    """A rough metal: the Cook-Torrance BRDF with GGX normals.

    Args:
        f0: (3,) linear RGB reflectance at normal incidence (gold: 1.0, 0.782, 0.344), kept
            as float32, the renderer's type (a float64 f0 would turn its arrays into float64).
        alpha: GGX roughness in (0, 1] (the scenes' "roughness" r is alpha = r^2).
        sampling: ``"ggx"`` (your importance sampling) or ``"hemisphere"`` (cosine-weighted,
            already written).
    """

    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling="ggx"):
        self.f0 = np.asarray(f0, dtype=np.float32)
        self.alpha = float(alpha)
        self.sampling = sampling

    def eval(self, wo, wi, n):
        """The BRDF f_r(wo, wi), without the cosine factor.

        Args:
            wo, wi, n: (N, 3) unit vectors (float32 or float64).

        Returns:
            (N, 3): D(h) G2(wo, wi) F(wo . h) / (4 cos_theta_o cos_theta_i), h the unit half
            vector normalize(wo + wi); 0 in rows where wo or wi is below the surface.

        Hints:
            * At grazing directions cos_theta is 0 (or tiny): clamp the cosines to at least
              1e-7 before Lambda and the denominator, or you get NaN and infinity there.
            * ``fresnel_schlick`` returns (N, 3); the rest is (N,): ``[:, None]`` it.
        """
        raise NotImplementedError("GGXMetal.eval")

    def sample(self, wo, n, u):
        """Directions wi drawn with the density ``pdf``; u: (N, 2) uniforms in [0, 1).

        Hints (for ``"ggx"``, Walter et al. 2007, eqs. 35-36):
            * Draw a microfacet normal h with density D(h) cos(theta_h):
              tan^2(theta_h) = alpha^2 u0 / (1 - u0), phi = 2 pi u1; build it around +z and
              ``to_world(local, n)`` it.
            * Reflect wo about it: ``reflect(wo, h)`` (both point away from the surface).
            * wi may land below the surface: that is a failed sample; your pdf is 0 there,
              and the path simply ends. Do not "fix" it by flipping wi.
        """
        if self.sampling == "hemisphere":
            return to_world(cosine_hemisphere(u), n)
        raise NotImplementedError("GGXMetal.sample")

    def pdf(self, wo, wi, n):
        """The solid-angle density with which ``sample`` picks ``wi``; (N,).

        Hints (for ``"ggx"``):
            * The density of h is D(h) cos(theta_h); wi = reflect(wo, h) stretches it by the
              Jacobian |d omega_h / d omega_i| = 1 / (4 |wo . h|) (Walter et al. 2007, eq. 14):
              pdf(wi) = D(h) cos(theta_h) / (4 |wo . h|), with h = normalize(wo + wi).
            * 0 where wo or wi is below the surface.
        """
        if self.sampling == "hemisphere":
            cos_theta_i = dot(wi, n)
            return np.where((dot(wo, n) > 0) & (cos_theta_i > 0), cos_theta_i / math.pi, 0.0)
        raise NotImplementedError("GGXMetal.pdf")
