"""From a render's half images and features to a denoised image and its error estimate.

**Light seen directly stays out of the denoiser.** OIDN spreads a small, very bright light
into the dark pixels beside it: on ``veach-mis`` (16 spp) the denoised image's relMSE was
1.6-2.7 where the noisy one's was 0.1. Production renderers keep what the camera sees of a
light out of the denoiser and add it back after (the "direct" of
``ptlab.integrators.features``), and so does ``denoise``: the colour OIDN is given is each
half image less its directly seen light (at least 0, against rounding), and that light is
added back to the output unchanged. It is the noisy image's own there, unbiased: at a
light's edge it keeps the noise of the few samples that found the light, which no denoiser
could tell from detail. On ``veach-mis`` this alone brought the denoised relMSE to
0.037-0.056 at 16 spp, and on the Cornell box it gained 1.1-2.7x (its light's edges); on
``games101-hw5``, whose light seen directly is a dim sky, seen through glass too, it cost
1.2-1.4x (``scripts/denoise_study.py``).

**The image is the mean of the two halves' denoised images**, D = (D_a + D_b) / 2, not the
denoised mean of all samples. Its error can then be estimated with no model of the denoiser
(``ptlab.denoise.estimate``), from two denoiser runs; the denoised mean of all samples would
need a third run and a guess at how the denoiser's error falls with the samples (measured:
its relMSE is 0.81-1.05 of D's on four scenes at 4-64 spp). A preview, which needs no estimate,
denoises the whole image in one run (``estimate=False``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ptlab.denoise.estimate import ErrorEstimate, estimate_error
from ptlab.denoise.inputs import DenoiseInputs
from ptlab.denoise.oidn import DEFAULT_QUALITY, denoise_colour, oidn_version, prefilter
from ptlab.errors import PtlabError

#: The ``features`` ``denoise`` takes, and what the image's header says of each.
FEATURES = {
    "prefilter": "albedo and normal, prefiltered",
    "noisy": "albedo and normal, as rendered",
    "none": "none (the colour alone)",
}


@dataclass(frozen=True)
class Denoised:
    """A denoised image and how it was made.

    Attributes:
        image: (H, W, 3) float32, the denoised image.
        halves: the two halves' denoised images (H, W, 3) float32, or None for a preview
            (``estimate=False``), whose image is the whole image's.
        estimate: its error estimate (``ptlab.denoise.estimate``), or None for a preview.
        seconds: wall time of the denoising, estimate included.
        settings: what made it, for an image file's header.
    """

    image: np.ndarray
    halves: tuple[np.ndarray, np.ndarray] | None
    estimate: ErrorEstimate | None
    seconds: float
    settings: dict = field(default_factory=dict)


def denoise(
    inputs: DenoiseInputs,
    *,
    estimate: bool = True,
    keep_direct: bool = True,
    features: str = "prefilter",
    quality: str = DEFAULT_QUALITY,
    threads: int | None = None,
) -> Denoised:
    """Denoise a render with OIDN (module docstring).

    Args:
        inputs: the render's half images, their directly seen light and its features.
        estimate: denoise each half and estimate the error of their mean (two denoiser
            runs); False: denoise the whole image once, with no estimate (a preview; and
            the only choice where the halves are not independent).
        keep_direct: keep the directly seen light out of the denoiser (False: give it all
            to the denoiser, as a plain ``oidnDenoise`` would; for comparisons).
        features: how OIDN takes the albedo and normal: "prefilter", denoised first (once
            for both halves) and then trusted as clean, as OIDN's documentation recommends
            for noisy features; "noisy", as they are; "none", not at all (the colour alone).
        quality: OIDN's filter quality, "high", "balanced" or "fast" (``DEFAULT_QUALITY``).
        threads: the most threads OIDN may use (None: its choice).
    """
    if features not in FEATURES:
        raise PtlabError(f"denoising: features {features!r}: choose one of {', '.join(FEATURES)}")
    start = time.perf_counter()
    clipped = np.clip(inputs.albedo, 0.0, 1.0)  # (OIDN's albedo is in [0, 1])
    albedo: np.ndarray | None = clipped
    normal: np.ndarray | None = inputs.normal
    given = features
    if features == "prefilter":
        albedo, normal = prefilter(clipped, inputs.normal, threads=threads, quality=quality)
        given = "clean"
    elif features == "none":
        albedo = normal = None
        given = "noisy"  # (no features: nothing to prefilter or trust)

    def denoised(colour: np.ndarray, direct: np.ndarray) -> np.ndarray:
        """``colour`` denoised, its directly seen light ``direct`` kept out if asked."""
        if not keep_direct:
            direct = np.zeros_like(direct)
        through = np.maximum(colour - direct, 0.0)  # (>= 0 but for rounding)
        return (
            denoise_colour(through, albedo, normal, threads=threads, quality=quality, features=given) + direct
        )

    settings = dict(
        denoiser=f"Intel Open Image Denoise {oidn_version()} (RT filter, HDR)",
        denoiser_quality=quality,
        denoiser_features=FEATURES[features],
        denoiser_direct_light="kept out, added back" if keep_direct else "denoised",
    )
    if not estimate:
        image = denoised(inputs.image, inputs.direct).astype(np.float32)
        settings["denoised"] = "the whole image"
        return Denoised(image, None, None, time.perf_counter() - start, settings)
    half_a = denoised(inputs.half_a, inputs.direct_a).astype(np.float32)
    half_b = denoised(inputs.half_b, inputs.direct_b).astype(np.float32)
    image = ((half_a.astype(np.float64) + half_b) / 2).astype(np.float32)
    error = estimate_error(inputs, half_a, half_b)
    settings["denoised"] = "each half image; the image is their mean"
    return Denoised(image, (half_a, half_b), error, time.perf_counter() - start, settings)
