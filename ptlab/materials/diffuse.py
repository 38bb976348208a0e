"""The Lambertian (ideal diffuse) material.

A Lambertian surface reflects equally in every direction: f_r = albedo / pi, which makes
its reflectance, the integral of f_r cos(theta_i) over the hemisphere, equal to the albedo
(pbrt-v4 section 9.2; GAMES101 lecture 15). It is reflective only: ``eval`` and ``pdf``
are zero when ``wo`` or ``wi`` lies below the surface.

Two samplings (``sampling=``):

* ``"uniform"``: uniform over the hemisphere, pdf 1 / (2 pi) (the homework's choice);
* ``"cosine"``: cosine-weighted, pdf cos(theta_i) / pi, which cancels the cosine of the
  rendering equation so every sample carries the same weight, the albedo.
"""

from __future__ import annotations

import math

import numpy as np

from ptlab.materials.base import Material
from ptlab.sampling import cosine_hemisphere_around, uniform_hemisphere_around
from ptlab.textures import Texture
from ptlab.vectors import dot

SAMPLINGS = ("cosine", "uniform")


class Diffuse(Material):
    """Lambertian reflection.

    Args:
        albedo: (3,) reflectance in [0, 1], one number for a grey one, or a
            ``ptlab.textures.Texture`` of them over the surface's uv (either becomes (N, 3),
            one per hit, after ``take``).
        sampling: ``"cosine"`` (default) or ``"uniform"``.
        emission: (3,) emitted radiance, or None.
    """

    samplings = SAMPLINGS
    batched = ("albedo",)

    def __init__(self, albedo=(0.8, 0.8, 0.8), sampling: str = "cosine", emission=None):
        if sampling not in SAMPLINGS:
            raise ValueError(f"unknown sampling {sampling!r}; choose one of {', '.join(SAMPLINGS)}")
        if not isinstance(albedo, Texture):
            # One number is a grey albedo: eval returns a colour per row, (N, 3), as every
            # material's does (a scalar albedo made it (N, 1)).
            albedo = np.asarray(albedo, dtype=np.float64)
            albedo = np.full(3, float(albedo)) if albedo.ndim == 0 else albedo
        self.albedo = albedo
        self.sampling = sampling
        self.emission = None if emission is None else np.asarray(emission, dtype=np.float64)

    def __repr__(self) -> str:
        albedo = self.albedo if isinstance(self.albedo, Texture) else self.albedo.tolist()
        return f"Diffuse(albedo={albedo}, sampling={self.sampling!r})"

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        # Multiplying by the 0/1 mask is several times faster than np.where here.
        albedo = np.asarray(self.albedo, dtype=wi.dtype)  # (a batch's is float32 already: no copy)
        return (above * wi.dtype.type(1.0 / math.pi))[:, None] * albedo

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        cos_theta_i = dot(wi, n)
        above = (dot(wo, n) > 0) & (cos_theta_i > 0)
        if self.sampling == "uniform":
            density = np.full_like(cos_theta_i, 1.0 / (2.0 * math.pi))
        else:
            density = cos_theta_i / math.pi
        return np.where(above, density, 0).astype(wi.dtype, copy=False)

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        # The lecture's recipe is to warp u around +z and rotate the result to n
        # (to_world(uniform_hemisphere(u), n)); these draw the same densities directly
        # around n, 40% faster (ptlab.sampling).
        u = u.astype(n.dtype, copy=False)
        if self.sampling == "uniform":
            return uniform_hemisphere_around(n, u)
        return cosine_hemisphere_around(n, u)

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        # Closed forms of f cos / pdf, which the generic version reaches in more steps:
        # cosine sampling: (albedo / pi) cos / (cos / pi) = albedo;
        # uniform sampling: (albedo / pi) cos / (1 / 2 pi) = 2 albedo cos.
        # Both assume wo above the surface, which the renderer guarantees by facing n
        # toward wo; below it the weight is 0 as the contract asks.
        wi = self.sample(wo, n, u)
        albedo = np.asarray(self.albedo, dtype=n.dtype)
        scale = (dot(wo, n) > 0).astype(n.dtype)
        if self.sampling == "uniform":
            scale *= 2.0 * dot(wi, n)
        return wi, scale[:, None] * albedo

    # Every Diffuse with the same sampling shades in one vectorized call (a textured one in
    # its own).
    def batch_key(self) -> object:
        return id(self) if self.textured else ("diffuse", self.sampling)
