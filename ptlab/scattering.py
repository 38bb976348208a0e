"""Scattering at a smooth surface: where light goes, and how much of it reflects.

The formulas that mirrors, glass, rough metals and the Whitted tracer share, in one place
(as pbrt-v4 keeps them in ``util/scattering.h``; pbrt-v4 section 9.3, "Specular Reflection
and Transmission"; GAMES101 lecture 13):

* ``reflect``: the law of specular reflection, wi = 2 (wo . n) n - wo (pbrt-v4 9.3.3);
* ``refract``: Snell's law, eta_i sin(theta_i) = eta_t sin(theta_t), in vector form
  (pbrt-v4 9.3.4);
* ``fresnel_dielectric``: the Fresnel reflectance of unpolarised light at the boundary of
  two dielectrics, 1 under total internal reflection (pbrt-v4 9.3.5);
* ``F_schlick``: Schlick's approximation of the Fresnel reflectance from its value F0 at
  normal incidence, the colour of a metal (Schlick 1994);
* ``FresnelSplit``: the three together at a smooth dielectric (glass): both directions and
  the fraction of the light that each carries (pbrt-v4 9.5), which the glass material picks
  one of at random and the Whitted tracer follows both of.

Conventions (the whole library's): directions are (N, 3) unit vectors pointing *away* from
the surface, ``n`` the unit normal. ``eta_rel`` is the index of refraction beyond the
boundary over the index on the side of the given direction (pbrt's eta = eta_t / eta_i):
1.5 entering glass from air, 1 / 1.5 leaving it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ptlab.vectors import channels, dot, vec3


def reflect(w: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(N, 3) mirror image of ``w`` about the unit normal ``n``: 2 (w . n) n - w.

    Both ``w`` and the result point away from the surface (pbrt-v4 ``Reflect``).
    """
    return (2 * dot(w, n))[:, None] * n - w


def refract(wo: np.ndarray, n: np.ndarray, eta_rel) -> np.ndarray:
    """(N, 3) refracted directions, for ``n`` facing ``wo`` (unit except under total internal reflection).

    wi = -wo / eta_rel + (cos_theta_o / eta_rel - cos_theta_i) n with
    cos_theta_i = sqrt(1 - sin^2(theta_o) / eta_rel^2) (pbrt-v4 ``Refract``); ``eta_rel`` a
    float or (N,). Under total internal reflection sin^2(theta_i) > 1 has no angle:
    cos_theta_i is taken as 0 there (no NaN), and ``fresnel_dielectric`` is 1.
    """
    cos_theta_o = dot(wo, n)
    sin2_theta_i = (1.0 - cos_theta_o * cos_theta_o) / (eta_rel * eta_rel)
    cos_theta_i = np.sqrt(np.maximum(0.0, 1.0 - sin2_theta_i))
    return -wo / _column(eta_rel) + (cos_theta_o / eta_rel - cos_theta_i)[:, None] * n


def _column(value):
    return value[:, None] if np.ndim(value) == 1 else value


def fresnel_dielectric(cos_theta_i: np.ndarray, eta_rel) -> np.ndarray:
    """(N,) Fresnel reflectance of unpolarised light arriving at ``cos_theta_i`` in [0, 1].

    F = (r_parallel^2 + r_perpendicular^2) / 2, the mean of the two polarisations' squared
    amplitude ratios; ``eta_rel`` a float or (N,); 1 under total internal reflection
    (pbrt-v4 ``FrDielectric``).
    """
    sin2_theta_t = (1.0 - cos_theta_i * cos_theta_i) / (eta_rel * eta_rel)
    cos_theta_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_theta_t))
    # 0 / 0 only at grazing incidence under total internal reflection, replaced below.
    with np.errstate(invalid="ignore"):
        r_parallel = (eta_rel * cos_theta_i - cos_theta_t) / (eta_rel * cos_theta_i + cos_theta_t)
        r_perpendicular = (cos_theta_i - eta_rel * cos_theta_t) / (cos_theta_i + eta_rel * cos_theta_t)
    reflectance = (r_parallel * r_parallel + r_perpendicular * r_perpendicular) / 2.0
    return np.where(sin2_theta_t >= 1.0, 1.0, reflectance).astype(np.result_type(cos_theta_i), copy=False)


def F_schlick(cos_theta: np.ndarray, f0: np.ndarray) -> np.ndarray:  # noqa: N802 (the papers' name)
    """(N, 3) Schlick's Fresnel: F0 + (1 - F0) (1 - cos_theta)^5; f0: (3,) or (N, 3)."""
    m = (1.0 - np.clip(cos_theta, 0.0, 1.0)) ** 5
    f0 = channels(f0)
    return (f0 + (1.0 - f0) * m).T


@dataclass
class FresnelSplit:
    """What a smooth boundary between two dielectrics does with the light that leaves it
    toward ``wo``: the fraction R of it (Fresnel) came by reflection, along ``reflected``; the
    rest by refraction, along ``refracted``, its radiance scaled by 1 / eta_rel^2 as it
    crossed (pbrt-v4 section 9.5, ``TransportMode::Radiance``).

    Attributes:
        reflected: (N, 3) unit directions wi of the reflection, reflect(wo, n).
        refracted: (N, 3) directions wi of the refraction, refract(wo, n, eta_rel) (not unit
            under total internal reflection, where R = 1).
        R: (N,) the Fresnel reflectance, fresnel_dielectric(wo . n, eta_rel).
        eta_rel: (N,) the index beyond the boundary over the index on ``wo``'s side.
    """

    reflected: np.ndarray
    refracted: np.ndarray
    R: np.ndarray
    eta_rel: np.ndarray

    @classmethod
    def at(
        cls,
        wo: np.ndarray,
        n: np.ndarray,
        eta,
        outside: np.ndarray,
        *,
        reflect: Callable[..., np.ndarray] = reflect,
        refract: Callable[..., np.ndarray] = refract,
        fresnel: Callable[..., np.ndarray] = fresnel_dielectric,
    ) -> FresnelSplit:
        """The split of the light that leaves a smooth dielectric toward ``wo``.

        Args:
            wo: (N, 3) unit directions toward the viewer.
            n: (N, 3) unit normals on the side of ``wo``.
            eta: the index of refraction inside over outside, a float or (N,).
            outside: (N,) bool, True where ``wo`` is outside: eta_rel is ``eta`` there,
                1 / eta inside.
            reflect, refract, fresnel: the three formulas (default: this module's; a caller
                given others, as the Whitted tracer may be, passes them on).
        """
        eta = eta if np.ndim(eta) == 0 else np.asarray(eta, dtype=n.dtype)
        eta_rel = np.where(outside, eta, 1.0 / eta).astype(n.dtype, copy=False)
        return cls(
            reflected=reflect(wo, n),
            refracted=refract(wo, n, eta_rel),
            R=fresnel(dot(wo, n), eta_rel),
            eta_rel=eta_rel,
        )

    def refracted_weight(self, fraction: np.ndarray, transmittance: np.ndarray) -> np.ndarray:
        """(N, 3) the weight of rays that carry ``fraction`` (N,) of the refracted light, of
        colour ``transmittance`` ((3,) or (N, 3)): transmittance x fraction / eta_rel^2."""
        transmittance = channels(transmittance.astype(self.eta_rel.dtype, copy=False))
        return (transmittance * (fraction / (self.eta_rel * self.eta_rel))).T

    def choose(self, u: np.ndarray, transmittance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One of the two directions per row: reflection where ``u`` (N,) < R, so with
        probability R, else refraction; each weighted by its fraction of the light over its
        probability: 1 reflected, transmittance / eta_rel^2 refracted (a random walk's choice,
        pbrt-v4's ``DielectricBxDF::Sample_f``).

        Returns:
            wi: (N, 3) directions; weight: (N, 3).
        """
        reflected = u < self.R
        wi = np.where(reflected[:, None], self.reflected, self.refracted)
        refracted = self.refracted_weight(~reflected, transmittance)
        return wi, reflected.astype(self.eta_rel.dtype)[:, None] + refracted

    def both(self, transmittance: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """Both directions, each weighted by its fraction of the light (Whitted's split):
        [(reflected, R), (refracted, (1 - R) transmittance / eta_rel^2)], (N, 3) each."""
        R = self.R  # noqa: N806 (the formula's name)
        refracted = self.refracted_weight(1 - R, transmittance)
        return [(self.reflected, vec3(R, R, R)), (self.refracted, refracted)]
