"""Point lights: lights that sit at single points and shine equally in every direction."""

from __future__ import annotations

import math

import numpy as np

from ptlab.lights.base import LightLiSample, LightPoint
from ptlab.sampling import discrete_cdf, pick_from_cdf
from ptlab.vectors import dot


class PointLights:
    """Lights that sit at single points and shine equally in every direction.

    A point light of intensity I (W/sr, an RGB triple) sends the radiance-like quantity
    I / r^2 to a point at distance r: the irradiance there is E = I cos(theta) / r^2
    (pbrt-v4's ``PointLight``, section 12.2; GAMES101 lecture 14). No ray can hit a point,
    so only light sampling finds it: a *delta* light, whose multiple-importance weight is 1.
    Its power is 4 pi mean(I) (pbrt-v4's ``PointLight::Phi``, the mean over RGB as for area
    lights); light sampling picks one of them in proportion to it.

    Args:
        positions: (K, 3) where the lights are.
        intensity: (K, 3) their intensities, W/sr, each channel >= 0.
    """

    is_delta = True

    def __init__(self, positions, intensity):
        self.positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        self.intensity = np.asarray(intensity, dtype=np.float64).reshape(-1, 3)
        if len(self.positions) != len(self.intensity) or len(self.positions) == 0:
            raise ValueError(
                f"{len(self.positions)} positions for {len(self.intensity)} "
                f"intensities: give one (3,) intensity per point light"
            )
        if (self.intensity < 0).any() or not (self.intensity.mean(axis=1) > 0).all():
            raise ValueError("a point light's intensity must be >= 0 in each channel and not 0 in all three")
        #: (K,) each light's power, and their sum.
        self.powers = 4 * math.pi * self.intensity.mean(axis=1)
        self.power = float(self.powers.sum())
        #: (K,) the probability that ``sample_li`` picks each, and their cdf.
        self.probability = (self.powers / self.power).astype(np.float32)
        self.cdf = discrete_cdf(self.powers)

    def __len__(self) -> int:
        return len(self.positions)

    def __repr__(self) -> str:
        return f"PointLights(positions={self.positions.tolist()}, intensity={self.intensity.tolist()})"

    def pdf_li(self, found: LightPoint) -> np.ndarray:
        """(N,) zeros: no ray finds a point light."""
        return np.zeros(len(found.radiance), np.float32)

    def sample_li(self, p: np.ndarray, u: np.ndarray) -> LightLiSample:
        """One of the lights for each point ``p`` (N, 3), picked by power with ``u[:, 0]``."""
        index, _ = pick_from_cdf(self.cdf, u[:, 0])
        position = self.positions.astype(np.float32).take(index, axis=0)
        to_light = position - p
        dist2 = dot(to_light, to_light)
        radiance = self.intensity.astype(np.float32).take(index, axis=0) / dist2[:, None]
        return LightLiSample(
            wi=to_light / np.sqrt(dist2)[:, None],
            radiance=radiance,
            pdf=self.probability.take(index),
            target=position,
        )
