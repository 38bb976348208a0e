"""The sky: a constant radiance from every direction that no surface blocks."""

from __future__ import annotations

import math

import numpy as np

from ptlab.lights.base import LightLiSample, LightPoint
from ptlab.sampling import uniform_sphere


class Sky:
    """A constant radiance L from every direction that no surface blocks: what rays that
    escape the scene see (GAMES101 Homework 5's background colour), and a light.

    Light sampling picks directions uniformly on the sphere, pdf 1 / (4 pi), as pbrt-v4's
    ``UniformInfiniteLight`` does (section 12.5.1). Its density is the same for every
    direction, so the MIS weight of a ray that escapes needs nothing of the vertex it left;
    the half of the directions below the surface costs no shadow ray. (Cosine-weighted
    directions around the normal would suit a diffuse surface better when the sky is
    sampled alone, but their density depends on that normal.)

    Args:
        radiance: (3,) the sky's radiance L.
        distance: how far shadow rays toward the sky go: beyond the whole scene.
    """

    is_delta = False

    def __init__(self, radiance, distance: float = 1.0):
        self.radiance = np.asarray(radiance, dtype=np.float64).reshape(3)
        if (self.radiance < 0).any() or not np.isfinite(self.radiance).all():
            raise ValueError(f"the sky's radiance must be finite and >= 0, got {self.radiance.tolist()}")
        self.distance = float(distance)

    def __repr__(self) -> str:
        return f"Sky(radiance={self.radiance.tolist()})"

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) 1 / (4 pi) for every direction (``uniform_sphere``'s density)."""
        return np.full(len(found.radiance), 1 / (4 * math.pi), dtype=np.float32)

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """A direction uniform on the sphere for each point ``p`` (N, 3)."""
        wi = uniform_sphere(u).astype(np.float32)
        n = len(p)
        radiance = np.broadcast_to(self.radiance.astype(np.float32), (n, 3))
        return LightLiSample(
            wi=wi,
            radiance=radiance,
            pdf=self.pdf_li(LightPoint(radiance)),
            target=p + np.float32(self.distance) * wi,
        )
