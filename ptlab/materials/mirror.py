"""The perfect mirror: a delta material that reflects every ray in one direction.

An ideal mirror sends light from ``wo`` only to its mirror image about the normal,
wi = reflect(wo, n) = 2 (wo . n) n - wo (pbrt-v4 section 9.3; GAMES101 lecture 13, Whitted
ray tracing). Its BRDF is a Dirac delta, f_r = R delta(wi - reflect(wo, n)) / cos_theta_i,
which no direction chosen independently of ``wo`` ever hits. Following pbrt-v4's convention
for specular BxDFs, ``eval`` and ``pdf`` return 0, ``is_delta`` is True, and the only way to
scatter is ``sample_weight``, whose weight f_r cos_theta_i / pdf is the reflectance R
(the delta functions cancel).

The reflectance is constant, or with ``fresnel=True`` Schlick's approximation
R = R0 + (1 - R0) (1 - cos_theta_o)^5 with R0 the given reflectance (a polished metal,
brightening toward grazing angles). Reflective only: the weight is 0 when ``wo`` is below
the surface.
"""

from __future__ import annotations

import numpy as np

from ptlab.materials.base import DeltaMaterial
from ptlab.scattering import F_schlick, reflect
from ptlab.vectors import channels, dot


class Mirror(DeltaMaterial):
    """Perfect specular reflection.

    Args:
        reflectance: (3,) fraction of light reflected, in [0, 1] (default 1: a perfect mirror).
        fresnel: if True, ``reflectance`` is R0 of Schlick's approximation, rising to 1 at
            grazing angles (default False: the same reflectance at every angle).
    """

    batched = ("reflectance",)

    def __init__(self, reflectance=(1.0, 1.0, 1.0), fresnel: bool = False):
        self.reflectance = np.asarray(reflectance, dtype=np.float64)
        if (
            self.reflectance.shape != (3,)
            or not np.isfinite(self.reflectance).all()
            or (self.reflectance < 0).any()
            or (self.reflectance > 1).any()
        ):
            raise ValueError(f"reflectance must be three numbers in [0, 1], got {reflectance!r}")
        self.fresnel = bool(fresnel)

    def __repr__(self) -> str:
        return f"Mirror(reflectance={self.reflectance.tolist()}, fresnel={self.fresnel})"

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        """(N, 3) the mirror directions reflect(wo, n); ``u`` and ``front`` are not used."""
        return reflect(wo, n)

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) mirror directions and (N, 3) weights R (``reflectance_at``)."""
        return reflect(wo, n), self.reflectance_at(wo, n)

    def reflectance_at(self, wo: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N, 3) R, the share of the light the mirror reflects toward ``wo``: the
        reflectance, or Schlick's R with it as R0; 0 where wo is below the surface."""
        cos_theta_o = dot(wo, n)
        reflectance = self.reflectance.astype(n.dtype, copy=False)
        above = (cos_theta_o > 0).astype(n.dtype)
        if self.fresnel:
            return (F_schlick(cos_theta_o, reflectance).T * above).T
        return (channels(reflectance) * above).T

    def batch_key(self) -> object:
        return ("mirror", self.fresnel)
