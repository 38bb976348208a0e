"""What the denoiser is given: per pixel, the two half images and what the camera saw.

The renderer gathers these from one render's samples (``ptlab.integrators.features``); the
denoiser knows nothing of the film: arrays in, arrays out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ptlab.errors import PtlabError


@dataclass(frozen=True)
class DenoiseInputs:
    """Per pixel, (H, W, 3) float64 arrays.

    Attributes:
        half_a: the mean of each pixel's even samples (independent of the odd ones).
        half_b: the mean of its odd samples. Every pixel has as many samples in each half,
            so the image is (half_a + half_b) / 2.
        direct_a, direct_b: the part of half_a, half_b that is emission seen directly: by the
            camera ray, or through mirrors and glass only (the sky seen so too).
        albedo: the mean albedo of each sample's first hit that is not a perfect mirror or
            glass, in [0, 1] (0 where the ray escaped).
        normal: the mean shading normal there (world space, length at most 1; 0 on escape).
    """

    half_a: np.ndarray
    half_b: np.ndarray
    direct_a: np.ndarray
    direct_b: np.ndarray
    albedo: np.ndarray
    normal: np.ndarray

    def __post_init__(self) -> None:
        shape = np.shape(self.half_a)
        if len(shape) != 3 or shape[2] != 3 or min(shape) == 0:
            raise PtlabError(f"denoising: half_a is {shape}, not an (H, W, 3) image")
        for name in ("half_b", "direct_a", "direct_b", "albedo", "normal"):
            if np.shape(getattr(self, name)) != shape:
                raise PtlabError(
                    f"denoising: {name} is {np.shape(getattr(self, name))}, not {shape} like half_a"
                )

    @property
    def image(self) -> np.ndarray:
        """(H, W, 3) the noisy image: the mean of all the samples."""
        return (np.asarray(self.half_a, np.float64) + self.half_b) / 2

    @property
    def direct(self) -> np.ndarray:
        """(H, W, 3) the part of the image seen directly (the mean of the halves')."""
        return (np.asarray(self.direct_a, np.float64) + self.direct_b) / 2
