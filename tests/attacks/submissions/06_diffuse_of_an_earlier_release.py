"""A chapter-6 answer copied from an earlier release of ptlab: the ``Diffuse`` of commit 10d12b8
(2026-11-27) as its text was then, under the exercise's name. Today's library reads otherwise:
only the earlier releases' answers (ptlab/course/sandbox/past_answers.json) find it."""

from __future__ import annotations

import math

import numpy as np

from ptlab.materials.base import Material, dot
from ptlab.sampling import cosine_hemisphere, to_world, uniform_hemisphere

SAMPLINGS = ("cosine", "uniform")


class Lambertian(Material):
    """Lambertian reflection.

    Args:
        albedo: (3,) reflectance in [0, 1] (or (N, 3) per hit after ``take``).
        sampling: ``"cosine"`` (default) or ``"uniform"``.
        emission: (3,) emitted radiance, or None.
    """

    def __init__(self, albedo=(0.8, 0.8, 0.8), sampling: str = "cosine", emission=None):
        if sampling not in SAMPLINGS:
            raise ValueError(f"unknown sampling {sampling!r}; choose one of {', '.join(SAMPLINGS)}")
        self.albedo = np.asarray(albedo, dtype=np.float64)
        self.sampling = sampling
        self.emission = None if emission is None else np.asarray(emission, dtype=np.float64)

    def __repr__(self) -> str:
        return f"Lambertian(albedo={self.albedo.tolist()}, sampling={self.sampling!r})"

    def _f(self, dtype) -> np.ndarray:
        return (self.albedo / math.pi).astype(dtype, copy=False)

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return np.where(above[:, None], self._f(wi.dtype), 0).astype(wi.dtype, copy=False)

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        cos_theta_i = dot(wi, n)
        above = (dot(wo, n) > 0) & (cos_theta_i > 0)
        if self.sampling == "uniform":
            density = np.full_like(cos_theta_i, 1.0 / (2.0 * math.pi))
        else:
            density = cos_theta_i / math.pi
        return np.where(above, density, 0).astype(wi.dtype, copy=False)

    def sample(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray) -> np.ndarray:
        warp = uniform_hemisphere if self.sampling == "uniform" else cosine_hemisphere
        return to_world(warp(u.astype(n.dtype, copy=False)), n)

    def sample_weight(self, wo: np.ndarray, n: np.ndarray,
                      u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # Closed forms of f cos / pdf, which the generic version reaches in more steps:
        # cosine sampling: (albedo / pi) cos / (cos / pi) = albedo;
        # uniform sampling: (albedo / pi) cos / (1 / 2 pi) = 2 albedo cos.
        # Both assume wo above the surface, which the renderer guarantees by facing n
        # toward wo; below it the weight is 0 as the contract asks.
        wi = self.sample(wo, n, u)
        albedo = self.albedo.astype(n.dtype, copy=False)
        above = dot(wo, n) > 0
        if self.sampling == "uniform":
            weight = 2.0 * dot(wi, n)[:, None] * albedo
        else:
            weight = np.broadcast_to(albedo, wi.shape)
        return wi, np.where(above[:, None], weight, 0).astype(n.dtype, copy=False)

    # Every Diffuse with the same sampling shades in one vectorized call.
    def batch_key(self) -> object:
        return ("diffuse", self.sampling)

    @classmethod
    def stack(cls, materials: list[Material]) -> Lambertian:
        stacked = cls(sampling=materials[0].sampling)
        stacked.albedo = np.stack([m.albedo for m in materials])
        return stacked

    def take(self, index: np.ndarray) -> Lambertian:
        taken = Lambertian(sampling=self.sampling)
        taken.albedo = self.albedo.take(index, axis=0)
        return taken
