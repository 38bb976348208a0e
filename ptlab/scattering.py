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
  normal incidence, the colour of a metal (Schlick 1994).

Conventions (the whole library's): directions are (N, 3) unit vectors pointing *away* from
the surface, ``n`` the unit normal. ``eta_rel`` is the index of refraction beyond the
boundary over the index on the side of the given direction (pbrt's eta = eta_t / eta_i):
1.5 entering glass from air, 1 / 1.5 leaving it.
"""

from __future__ import annotations

import numpy as np

from ptlab.vectors import channels, dot


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
