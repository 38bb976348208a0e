"""Chapter 3: Whitted-style ray tracing: reflection, refraction and Fresnel.

The chapter's page: ``ptlab exercise docs 3`` (中文: ``--zh``).

Write the three laws of a smooth surface that Homework 5's ``castRay`` follows: the mirror
direction, the refracted direction (Snell's law) and the share of light that is reflected
(the Fresnel equations). The Whitted tracer (``ptlab.integrators.whitted``) then uses yours
for every mirror and glass surface. Check your work with

    ptlab exercise check 3 03_whitted.py

Conventions (as in the whole library): every direction is a unit vector pointing *away*
from the surface. ``wo`` points back toward where the ray came from, and the directions you
return point away from the surface too: the reflected one on ``wo``'s side, the refracted
one on the other side. ``n`` is the unit normal on ``wo``'s side (wo . n > 0). (GAMES101's
framework passes the incoming ray's direction I, which points *toward* the surface: its I
is our -wo, and its refract flips n itself; here the caller has done that.)

``eta`` is the *relative* index of refraction, eta_t / eta_i: the index of the medium beyond
the surface over the index of the medium ``wo`` is in. Entering glass from air it is 1.5;
leaving glass into air it is 1 / 1.5. It is a float or an (N,) array, one per row.

Everything is whole arrays: ``wo`` holds thousands of directions at once. Write each
function with NumPy operations on those arrays, never a Python loop over rows.
"""

import numpy as np

from ptlab.vectors import dot


def reflect(wo, n):
    """The mirror direction of ``wo`` about ``n``.

    Args:
        wo: (N, 3) unit directions pointing away from the surface.
        n: (N, 3) unit normals.

    Returns:
        (N, 3) unit directions pointing away from the surface, at the same angle to n as wo,
        in the plane of wo and n, on the other side of n.

    Hints:
        * The part of wo along n stays, the part across n flips: wi = 2 (wo . n) n - wo.
        * ``dot(wo, n)`` is the (N,) row-wise dot product; ``x[:, None] * n`` scales each row.
    """
    raise NotImplementedError("reflect")


def refract(wo, n, eta):
    """The direction in which light arriving along -wo continues through the surface.

    Args:
        wo: (N, 3) unit directions pointing away from the surface, on n's side.
        n: (N, 3) unit normals on wo's side (wo . n > 0).
        eta: eta_t / eta_i, a float or (N,) (1.5 entering glass, 1 / 1.5 leaving it).

    Returns:
        (N, 3) unit directions on the *other* side of the surface (. n < 0), bent by Snell's
        law eta_i sin(theta_i) = eta_t sin(theta_t), i.e. sin(theta_t) = sin(theta_i) / eta.
        Under total internal reflection (sin(theta_i) / eta > 1: no refracted ray) return any
        finite vector, e.g. with cos(theta_t) clamped to 0; ``fresnel`` gives it weight 0.

    Hints:
        * cos_i = wo . n; sin^2(theta_t) = (1 - cos_i^2) / eta^2;
          cos_t = sqrt(max(0, 1 - sin^2(theta_t))).
        * wt = -wo / eta + (cos_i / eta - cos_t) n (pbrt-v4 section 9.3, ``Refract``).
        * With eta an (N,) array, ``-wo / eta`` needs ``eta[:, None]``; ``np.ndim(eta)``
          tells the two cases apart.
    """
    raise NotImplementedError("refract")


def fresnel(cos_theta_i, eta):
    """The Fresnel reflectance: the fraction of unpolarised light that a smooth dielectric
    surface reflects (the rest is refracted).

    Args:
        cos_theta_i: (N,) cosines of the angle between the arriving light and n, in [0, 1].
        eta: eta_t / eta_i, a float or (N,).

    Returns:
        (N,) reflectances in [0, 1]: ((eta - 1) / (eta + 1))^2 at normal incidence, rising to
        1 at grazing incidence; exactly 1 under total internal reflection.

    Hints:
        * cos_t from Snell's law as in ``refract``; where sin^2(theta_t) >= 1, return 1.
        * r_parallel = (eta cos_i - cos_t) / (eta cos_i + cos_t),
          r_perpendicular = (cos_i - eta cos_t) / (cos_i + eta cos_t),
          F = (r_parallel^2 + r_perpendicular^2) / 2 (pbrt-v4 section 9.3.5; the homework's
          ``fresnel`` computes the same with etai and etat).
        * ``np.where(condition, 1.0, F)`` picks per row; silence 0 / 0 warnings where you
          replace the result anyway with ``np.errstate(invalid="ignore")``.
    """
    raise NotImplementedError("fresnel")
