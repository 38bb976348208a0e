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
* ``pick_from_cdf``: one of K items with the probabilities of a discrete CDF, and the uniform
  that picked it stretched back to [0, 1) to serve again (``discrete_cdf`` makes the CDF);
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

from ptlab.samplers import ONE_MINUS_EPSILON
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


def discrete_cdf(weights: np.ndarray) -> np.ndarray:
    """(K,) float64 cumulative distribution of (K,) non-negative ``weights`` (not all 0):
    item i has probability weights[i] / sum(weights); exactly 1 from the last item of
    non-zero weight on."""
    cdf = np.cumsum(weights, dtype=np.float64)
    cdf /= cdf[-1]
    return cdf


def pick_from_cdf(cdf: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse-CDF choice of one of K items per uniform, and the uniform reused (pbrt-v4's
    ``SampleDiscrete``, section 2.3.1).

    Item i is chosen where cdf[i - 1] <= u < cdf[i] (from 0 for the first item): with
    probability cdf[i] - cdf[i - 1], never an item of probability 0. ``u`` is then stretched
    from that interval back to [0, 1), (u - cdf[i - 1]) / (cdf[i] - cdf[i - 1]), so that it
    can serve again, as stratified as it was (``ptlab.samplers``).

    Args:
        cdf: (K,) non-decreasing, the last 1 (a u that rounding left at or above it picks
            the last item); float32 or float64, the type the stretch is computed in.
        u: (N,) uniforms in [0, 1).

    Returns:
        index: (N,) intp, the item chosen for each u;
        stretched: (N,) in u's float type, in [0, 1).
    """
    edges = cdf[:-1]
    # The number of edges at or below u. For a handful of items (the Cornell box has two
    # light triangles) counting them pass by pass is ~10x faster than a binary search.
    if len(edges) < 16:
        index = np.zeros(len(u), dtype=np.intp)
        for edge in edges:
            index += u >= edge
    else:
        index = np.searchsorted(edges, u, side="right")
    below = np.concatenate([[0.0], edges]).astype(cdf.dtype)
    # 1 / the interval's width, to multiply by (an interval of width 0 is never chosen; the
    # floor keeps its entry finite all the same).
    stretch = 1 / np.maximum(cdf - below, cdf.dtype.type(1e-30))
    stretched = (u - below.take(index)) * stretch.take(index)
    return index, np.minimum(stretched, ONE_MINUS_EPSILON).astype(u.dtype, copy=False)
