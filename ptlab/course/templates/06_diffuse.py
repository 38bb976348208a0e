"""Chapter 6: Monte Carlo and the diffuse material.

The chapter's page: ``ptlab exercise docs 6`` (中文: ``--zh``).

Write the three methods of ``Lambertian``, an ideal diffuse surface: ``eval`` (its BRDF),
``sample`` (a random direction to continue a path in) and ``pdf`` (the density with which
``sample`` picks a direction). Check your work with

    ptlab exercise check 6 06_diffuse.py

and see the material harness's whole table with ``ptlab grade 06_diffuse.py:Lambertian``.

Conventions (as in the whole library): every direction is a unit vector pointing *away*
from the surface: ``wo`` toward the viewer, ``wi`` toward the light, ``n`` the unit normal.
(GAMES101's framework passes the incoming ray, which points toward the surface: its ``wi``
is our ``-wo``.)

Everything is whole arrays: ``wo`` holds the directions of thousands of hits at once, and so
on. Write each method with NumPy operations on those arrays, never a Python loop over rays
(a loop would be thousands of times slower, and the checks have time limits).
"""

import math

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import to_world
from ptlab.vectors import dot


class Lambertian(Material):
    """Lambertian reflection: light leaves equally in every direction of the hemisphere.

    Subclassing ``ptlab.materials.Material`` gives you ``sample_weight``, which the path
    tracer calls at every bounce: it samples ``wi`` with your ``sample`` and returns the
    Monte Carlo weight ``eval * cos(theta_i) / pdf`` (0 where the pdf is 0).

    Args:
        albedo: (3,) reflectance in [0, 1], one number per colour channel (kept as float32,
            the renderer's type: a float64 albedo would turn its float32 arrays into float64).
    """

    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        """The BRDF value f_r(wo, wi), *without* the cosine factor.

        Args:
            wo, wi, n: (N, 3) unit vectors (float32 or float64).

        Returns:
            (N, 3): albedo / pi for every row where both wo and wi are above the surface
            (their dot product with n is > 0), and 0 in the other rows.

        Hints:
            * ``dot(wo, n)`` is the (N,) row-wise dot product.
            * A boolean (N,) mask times a (3,) colour: ``mask[:, None] * colour`` is (N, 3).
        """
        raise NotImplementedError("eval")

    def sample(self, wo, n, u):
        """Directions ``wi`` drawn at random over the hemisphere around ``n``.

        Args:
            wo, n: (N, 3) unit vectors.
            u: (N, 2) uniform random numbers in [0, 1), one pair per row.

        Returns:
            (N, 3) unit vectors with wi . n >= 0, drawn with the density your ``pdf`` gives.

        Hints:
            * Make the direction around +z first ("local" coordinates), then rotate it so
              that +z goes to n: ``to_world(local, n)`` does that for all rows at once.
            * Uniform over the hemisphere (pdf 1 / (2 pi), the homework's density):
              cos(theta) = u0, sin(theta) = sqrt(1 - u0^2), phi = 2 pi u1. (The homework
              draws cos(theta) = abs(1 - 2 u0), the sphere's z folded in half: the same
              density, but it undoes a stratified sampler's work; see the chapter's page.)
            * Cosine-weighted (pdf cos(theta) / pi, less noise): r = sqrt(u0),
              phi = 2 pi u1, local = (r cos(phi), r sin(phi), sqrt(1 - u0)).
            * Either passes, as long as ``pdf`` is the density of the one you choose.
            * ``np.stack([x, y, z], axis=1)`` builds an (N, 3) array from three (N,) ones.
        """
        raise NotImplementedError("sample")

    def pdf(self, wo, wi, n):
        """The solid-angle density with which ``sample`` picks ``wi`` (per steradian).

        Args:
            wo, wi, n: (N, 3) unit vectors.

        Returns:
            (N,): the density of your ``sample`` at ``wi``; 0 where wo or wi is below the
            surface. It must integrate to 1 over the hemisphere (its area is 2 pi).

        Hints:
            * Uniform sampling: 1 / (2 pi). Cosine-weighted: cos(theta_i) / pi.
            * Return ``wi``'s dtype: a boolean mask divided by a number is float64, which
              ``.astype(wi.dtype)`` turns back into the renderer's float32.
            * The density goes to 0 at grazing directions for cosine sampling: never divide
              by it here (``sample_weight`` handles pdf == 0), and never raise it to some
              small epsilon (that makes it integrate to more than 1).
        """
        raise NotImplementedError("pdf")
