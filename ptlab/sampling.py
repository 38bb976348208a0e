"""Warping uniform random numbers into directions and points, and the random streams.

Each warp maps ``u`` in [0, 1)^2 to a sample with a known density (pbrt-v4, chapter A.5;
GAMES101 lecture 15/16):

* ``uniform_hemisphere``: pdf = 1 / (2 pi) per steradian (the homework's sampler);
* ``cosine_hemisphere``: pdf = cos(theta) / pi (Malley's method: a uniform disk point
  projected up onto the hemisphere);
* ``uniform_triangle``: a uniform point on a triangle, as barycentrics.

Hemisphere samples are made around +z ("local" frame) and rotated around a normal with
``to_world``. All functions work on whole arrays, keep the input's float dtype and return
(N, 3) arrays in the column-major layout of ``ptlab.vectors``.

Random streams: every (seed, tile, pass) gets its own generator through
``numpy.random.SeedSequence``, so an image does not depend on how many processes render
it or in which order tiles finish.
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.vectors import vec3

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


def to_world(local: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rotate (N, 3) vectors from the frame whose +z is ``n`` (N, 3 unit) to world space.

    The tangent frame is the branchless one of Duff et al., "Building an Orthonormal
    Basis, Revisited" (JCGT 2017): continuous everywhere except where n.z flips sign.
    """
    nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
    sign = np.where(nz >= 0, 1.0, -1.0).astype(n.dtype)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    # world = x * t + y * s + z * n with t = (1 + sign nx^2 a, sign b, -sign nx),
    # s = (b, sign + ny^2 a, -ny).
    return vec3(x * (1.0 + sign * nx * nx * a) + y * b + z * nx,
                x * (sign * b) + y * (sign + ny * ny * a) + z * ny,
                x * (-sign * nx) - y * ny + z * nz)


def uniform_triangle(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) uniforms -> barycentrics (b1, b2) of a uniform point on a triangle.

    The point is ``(1 - b1 - b2) v0 + b1 v1 + b2 v2``; its pdf is 1 / area
    (pbrt-v3, section 13.6.5).
    """
    s = np.sqrt(u[:, 0])
    return u[:, 1] * s, 1.0 - s


def stream(seed: int, tile: int, pass_index: int) -> np.random.Generator:
    """The random generator of one tile in one pass, independent of all the others."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, tile, pass_index])))
