"""Warping uniform random numbers into directions and points.

Each warp maps ``u`` in [0, 1)^2 to a sample with a known density (pbrt-v4, section A.5;
GAMES101 lecture 15/16):

* ``uniform_hemisphere``: pdf = 1 / (2 pi) per steradian (the homework's sampler);
* ``cosine_hemisphere``: pdf = cos(theta) / pi (Malley's method: a uniform disk point
  projected up onto the hemisphere);
* ``uniform_sphere``: pdf = 1 / (4 pi);
* ``uniform_hemisphere_around`` / ``cosine_hemisphere_around``: the same two hemisphere
  densities around any normal (the cosine one without a local frame: faster);
* ``uniform_triangle``: a uniform point on a triangle, as barycentrics;
* ``ggx_visible_normals``: GGX microfacet normals seen from a direction, with density
  D_wo(h) = G1(wo) max(0, wo . h) D(h) / cos(theta_o) (Heitz 2018; the spherical-cap form of
  Dupuy and Benyoub 2023).

Hemisphere samples are made around +z ("local" frame) and rotated around a normal with
``to_world``. All functions work on whole arrays, keep the input's float dtype and return
(N, 3) arrays in the column-major layout of ``ptlab.vectors``.

Every warp is one-to-one: distinct u give distinct samples, so evenly spread u
(``ptlab.samplers``) give evenly spread samples. (Folding, e.g. mirroring the lower half of
a uniform sphere up onto the hemisphere, would map two strata of u onto one region and
undo the stratification.)
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.vectors import dot, normalize, vec3

TWO_PI = 2.0 * math.pi


def uniform_hemisphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors around +z, pdf 1 / (2 pi)."""
    cos_theta = u[:, 0]
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
    phi = TWO_PI * u[:, 1]
    return vec3(sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta)


def cosine_hemisphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors around +z, pdf cos(theta) / pi (Malley)."""
    r = np.sqrt(u[:, 0])
    phi = TWO_PI * u[:, 1]
    # 1 - u can round to exactly 0 only for u = 1, which random() never returns.
    cos_theta = np.sqrt(1.0 - u[:, 0])
    return vec3(r * np.cos(phi), r * np.sin(phi), cos_theta)


def uniform_sphere(u: np.ndarray) -> np.ndarray:
    """(N, 2) uniforms -> (N, 3) unit vectors uniform on the sphere, pdf 1 / (4 pi)."""
    z = 1.0 - 2.0 * u[:, 0]
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = TWO_PI * u[:, 1]
    return vec3(r * np.cos(phi), r * np.sin(phi), z)


def uniform_hemisphere_around(n: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N, 3) unit vectors uniform on the hemisphere around unit normals ``n``, pdf 1 / (2 pi):
    ``uniform_hemisphere`` rotated to ``n`` (the lecture's recipe)."""
    return to_world(uniform_hemisphere(u), n)


def cosine_hemisphere_around(n: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(N, 3) unit vectors around unit normals ``n`` with pdf cos(theta) / pi.

    The same distribution as ``to_world(cosine_hemisphere(u), n)`` without building a
    frame: the direction to a uniform point on the unit sphere that touches the surface at
    the shading point (centre n). That sphere's area element is 4 cos(theta) times the solid
    angle it subtends, so uniform area gives density 4 cos(theta) / (4 pi) (Lambert's
    sphere; as in Shirley's "Ray Tracing in One Weekend"). The factor 1 + 1e-6 keeps the
    sum away from zero when the sphere point lands exactly opposite n.
    """
    d = n * (1.0 + 1e-6) + uniform_sphere(u)
    return d / np.sqrt(dot(d, d))[:, None]


def to_world(local: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rotate (N, 3) vectors from the frame whose +z is ``n`` (N, 3 unit) to world space.

    The tangent frame is the branchless one of Duff et al., "Building an Orthonormal
    Basis, Revisited" (JCGT 2017): continuous everywhere except where n.z flips sign.
    """
    nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
    sign = np.where(nz >= 0, n.dtype.type(1), n.dtype.type(-1))
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    # world = x * t + y * s + z * n with t = (1 + sign nx^2 a, sign b, -sign nx),
    # s = (b, sign + ny^2 a, -ny).
    return vec3(
        x * (1.0 + sign * nx * nx * a) + y * b + z * nx,
        x * (sign * b) + y * (sign + ny * ny * a) + z * ny,
        x * (-sign * nx) - y * ny + z * nz,
    )


def ggx_visible_normals(wo: np.ndarray, n: np.ndarray, alpha, u: np.ndarray) -> np.ndarray:
    """(N, 3) GGX microfacet normals h visible from ``wo``, density D_wo(h) per steradian.

    D_wo(h) = G1(wo) max(0, wo . h) D(h) / cos(theta_o) is the distribution of the normals
    that ``wo`` sees (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", eq. 2).
    Dupuy and Benyoub ("Sampling Visible GGX Normals with Spherical Caps", HPG 2023) draw it
    in three steps: stretch ``wo`` to the configuration where alpha = 1, in which the visible
    normals are the half vectors between ``wo`` and a point uniform on the spherical cap
    z > -wo.z; then unstretch. Done here in world space, so no local frame is needed but
    the one ``to_world`` builds for the cap.

    Args:
        wo: (N, 3) unit directions with wo . n > 0 (others give some unit vector).
        n: (N, 3) unit normals.
        alpha: GGX roughness, a float or (N,) per row.
        u: (N, 2) uniforms in [0, 1).
    """
    alpha = alpha[:, None] if np.ndim(alpha) == 1 else alpha
    cos_theta_o = dot(wo, n)
    wo_std = normalize(alpha * (wo - cos_theta_o[:, None] * n) + cos_theta_o[:, None] * n)
    wo_std_z = dot(wo_std, n)
    # A uniform point on the spherical cap z in (-wo_std.z, 1].
    z = (1.0 - u[:, 0]) * (1.0 + wo_std_z) - wo_std_z
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = TWO_PI * u[:, 1]
    cap = to_world(vec3(sin_theta * np.cos(phi), sin_theta * np.sin(phi), z), n)
    h_std = cap + wo_std
    h_std_z = dot(h_std, n)[:, None]
    return normalize(alpha * (h_std - h_std_z * n) + h_std_z * n)


def uniform_triangle(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) uniforms -> barycentrics (b1, b2) of a uniform point on a triangle.

    The point is ``(1 - b1 - b2) v0 + b1 v1 + b2 v2``; its pdf is 1 / area
    (pbrt-v3, section 13.6.5).
    """
    s = np.sqrt(u[:, 0])
    return u[:, 1] * s, 1.0 - s
