"""How far a denoised image is from the truth, estimated from the render's own samples:
a number that can be trusted, or a refusal that says why.

The image (``ptlab.denoise.pipeline``) is D = (D_a + D_b) / 2, where D_a is the denoiser's
output for the half image X_a (the mean of each pixel's even samples) and D_b for X_b (the odd
ones). Per pixel and channel, with R the unknown truth:

* D_a and D_b are independent, with the same mean m and variance v, so
  E (D - R)^2 = (m - R)^2 + v / 2: a bias b = m - R, and a variance;
* the residuals r_a = D_a - X_a and r_b = D_b - X_b are independent too (each is a function
  of its own half), and X_a, X_b are unbiased (E X_a = R), so E r_a = E r_b = b and
  E [r_a r_b] = b^2 exactly;
* E (D_a - D_b)^2 = 2 v.

So ``r_a r_b + (D_a - D_b)^2 / 4`` is an unbiased estimate of the pixel's squared error,
whatever the denoiser does, bias included: the "variance part" (D_a - D_b)^2 / 4 alone misses
the bias, and the bias is what fails on scenes the denoiser does not know (the issue measured
it 260x too optimistic on ``veach-mis``). This is cross-validation with two independent
halves, the idea of the half buffers of Rousselle, Knaus and Zwicker ("Adaptive Rendering
with Non-Local Means Filtering", SIGGRAPH Asia 2012), made exact for the squared error by
multiplying the two halves' residuals. It needs no assumption on the noise, where Stein's
unbiased risk estimate (SURE: Ramani, Blu and Unser, "Monte-Carlo SURE", IEEE TIP 2008;
used for reconstruction by Li, Wu and Chuang, "SURE-based Optimization for Adaptive Sampling
and Reconstruction", SIGGRAPH Asia 2012) assumes Gaussian noise: on ``veach-mis``, whose
noise is far from Gaussian, SURE with a Monte Carlo divergence gave 0.34-0.69 of the truth
where this estimate gave 0.92-1.01 at 4-64 spp, both with the true brightness in the
denominator (``scripts/denoise_study.py``).

**Its price is noise.** r_a r_b carries the product of the two halves' noises, whose mean is
0 but whose spread is that of the *noisy* image, squared: the estimate of an image that the
denoiser made 40 times cleaner is as noisy as if it had 1/40 of its pixels. Its sampling
error is measured, not assumed: the image is cut into ``BLOCK`` x ``BLOCK`` blocks (the
denoiser's errors are correlated over a few pixels, blocks of them nearly independent), and
the spread of the blocks' means gives the standard error of their mean.

**Relative error needs the truth's brightness.** relMSE divides each pixel's squared error
by (R + 0.01)^2 (``ptlab.measure.metrics``), and R is unknown. A stand-in that is too bright
hides error, so the stand-in is chosen so as to err dark (``brightness``):
* the light that reached the camera through the denoiser (the image less the light seen
  directly) stands in as the *lesser* of the denoised value and a local value of the noisy
  image: where the denoiser spread a bright highlight into its dark neighbours, it is the
  noisy image that is right. That local value is the larger of the noisy values' mean over
  ``INDIRECT_WINDOW`` x ``INDIRECT_WINDOW`` pixels and their median over 3 x 3: the mean
  alone, on the bright side of an edge, averages in the dark side (on ``games101-hw5`` at 64
  spp it made the estimate 1.3-1.46x the truth, the median's maximum 1.05-1.18x), and the
  median alone sits low in noisy, skewed regions;
* the light seen directly, which the denoiser never touched, stands in as the noisy image's
  estimate does (``ptlab.rendering.adaptive.reference_estimate``).
Two places defeat any stand-in, and there the estimate is computed again with the other
plausible brightness (``brightness``'s ``alternative``), and refused if the two differ by
more than ``MAX_BRIGHTNESS_SPREAD``:
* the edge of a small, bright light whose light one half's samples caught and the other's
  did not (``light_edges``): how much of the pixel the light covers is a guess, so the alternative
  stand-in is ``LIGHT_EDGE_DIMMING`` times darker there (on ``veach-mis`` at 16 spp, two
  such pixels held a third of the true error, while the stand-ins saw a fiftieth of it);
* a highlight of a pixel or two, which the local values erase: the alternative lets each
  pixel be as bright as half the darker of its halves says (on ``veach-mis`` at 256 spp the
  estimate was 1.7x the truth without it, 1.0x with it; but with it, at 64 spp, 0.6-0.8x).

**Refusals.** The estimate says nothing, and gives its reason, when
* it is not positive (its noise is larger than the error itself);
* the brightness is uncertain where the error is (above);
* it is above ``MAX_RELMSE``: a denoised image that far from the truth (a pixel off by
  sqrt(relMSE), 14% at 0.02, on average) cannot stand in for the truth's brightness, and the
  squared denominator would carry that error twice (a texture of 3-pixel period that the
  denoiser blurred away, made to test this, was estimated at a third of its true relMSE);
* its standard error is above ``MAX_STANDARD_ERROR`` of its value: the estimate is trusted
  only where its value +- 2 standard errors is within a factor 1.5 of it,
  (1 - 1 / 1.5) / 2 = 1/6. (A threshold of 0.3 let through estimates 1.6-1.85x too high on
  a synthetic scene: the standard error is a share of the noisy value itself, so a loose
  threshold keeps the values that happened to come out high.)
On four scenes at 4-64 spp and four seeds each (the renderer's own inputs: 0.83-1.37 of the
truth), and on synthetic scenes whose truth is known (0.80-1.40), every estimate these rules
let through was within a factor 1.5 of the truth (``scripts/denoise_study.py``,
``tests/renderer/test_denoise.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ptlab.denoise.inputs import DenoiseInputs
from ptlab.measure.metrics import RELMSE_EPSILON
from ptlab.rendering.adaptive import reference_estimate

#: Edge, in pixels, of the blocks whose means give the estimate's standard error.
BLOCK = 8
#: The fewest blocks a standard error is computed from (a smaller image is not estimated).
MIN_BLOCKS = 16
#: The largest standard error, as a share of the estimate, that is trusted.
MAX_STANDARD_ERROR = 1 / 6
#: The largest estimate that is trusted (module docstring).
MAX_RELMSE = 0.02
#: Edge of the window whose mean noisy value may stand in for the truth's brightness.
INDIRECT_WINDOW = 5
#: The most the estimate may change with the alternative brightness before it is refused.
MAX_BRIGHTNESS_SPREAD = 1.5
#: A pixel's directly seen light is "caught by one half" when one half's is this many times
#: the other's; the alternative brightness divides its stand-in by ``LIGHT_EDGE_DIMMING``.
LIGHT_EDGE_RATIO = 2.0
LIGHT_EDGE_DIMMING = 10.0
#: ... where that light is this many times the pixel's other light (``light_edges``).
LIGHT_EDGE_CONTRAST = 4.0
#: The share of the darker half's value that a pixel may be as bright as, in the alternative.
HIGHLIGHT_SHARE = 0.5


@dataclass(frozen=True)
class ErrorEstimate:
    """The estimated relMSE of a denoised image, or why there is none.

    Attributes:
        relmse: the estimate, or None when it is refused.
        reason: None, or why it is refused (one line).
        value: the estimate's value, refused or not (for studies of the estimate).
        alternative: the same estimate with the alternative brightness (module docstring):
            the larger of the two is the one to take for a bound.
        standard_error: its standard error, as a share of ``value``.
        error_map: (H, W) each pixel's estimated relative squared error (its mean is
            ``value``): unbiased in its numerator, but a single pixel's is very noisy and may
            be negative; pool it over a neighbourhood before using it.
    """

    relmse: float | None
    reason: str | None
    value: float
    alternative: float
    standard_error: float
    error_map: np.ndarray

    @property
    def brightness_spread(self) -> float:
        """How many times the larger of ``value`` and ``alternative`` is the smaller
        (infinite unless both are positive)."""
        low, high = sorted((self.value, self.alternative))
        return high / low if low > 0 else float("inf")

    def describe(self) -> str:
        """One line: the estimate with its standard error, or the refusal."""
        if self.relmse is None:
            return f"denoised relMSE not estimated: {self.reason}"
        return f"denoised relMSE estimate {self.relmse:.3g} (standard error {self.standard_error:.0%})"


def squared_error(inputs: DenoiseInputs, denoised_a: np.ndarray, denoised_b: np.ndarray) -> np.ndarray:
    """(H, W, 3) per pixel and channel, the unbiased estimate r_a r_b + (D_a - D_b)^2 / 4 of
    the squared error of (D_a + D_b) / 2 (module docstring), from the halves' denoised
    images ``denoised_a`` (D_a) and ``denoised_b`` (D_b), (H, W, 3)."""
    denoised_a = np.asarray(denoised_a, np.float64)
    denoised_b = np.asarray(denoised_b, np.float64)
    residual_a = denoised_a - inputs.half_a
    residual_b = denoised_b - inputs.half_b
    return residual_a * residual_b + (denoised_a - denoised_b) ** 2 / 4


def brightness(
    inputs: DenoiseInputs, denoised_a: np.ndarray, denoised_b: np.ndarray, alternative: bool = False
) -> np.ndarray:
    """(H, W, 3) what stands in for the truth R in relMSE's denominator (module docstring):
    the lesser of the denoised and the local noisy value of the light that is not seen
    directly, plus the stand-in for the light that is; or, if ``alternative``, the other
    plausible brightness at light edges and small highlights."""
    # (Imported here: every render imports this package, few estimate, and scipy.ndimage takes
    # about 0.2 s to import; ``ptlab.rendering.adaptive`` does the same.)
    from scipy.ndimage import median_filter, uniform_filter

    direct = inputs.direct
    through_denoiser = (np.asarray(denoised_a, np.float64) + denoised_b) / 2 - direct
    noisy = np.maximum(inputs.image - direct, 0.0)
    local_mean = uniform_filter(noisy, size=(INDIRECT_WINDOW, INDIRECT_WINDOW, 1), mode="nearest")
    local = np.maximum(local_mean, median_filter(noisy, size=(3, 3, 1), mode="nearest"))
    seen_directly = reference_estimate(direct, np.ones(direct.shape[:2]))
    if alternative:
        darker_half = np.minimum(inputs.half_a - inputs.direct_a, inputs.half_b - inputs.direct_b)
        edges = light_edges(inputs, np.maximum(np.minimum(through_denoiser, local), 0.0))
        local = np.maximum(local, HIGHLIGHT_SHARE * darker_half)
        seen_directly = np.where(edges, seen_directly / LIGHT_EDGE_DIMMING, seen_directly)
    return np.maximum(np.minimum(through_denoiser, local), 0.0) + seen_directly


def light_edges(inputs: DenoiseInputs, other_light: np.ndarray) -> np.ndarray:
    """(H, W, 1) bool: the edges of small, bright lights, seen by a few samples: where one
    half caught more than ``LIGHT_EDGE_RATIO`` times the other's directly seen light, and that
    light is more than ``LIGHT_EDGE_CONTRAST`` times the pixel's ``other_light`` (H, W, 3),
    at least ``RELMSE_EPSILON`` (where it is not, how much of the pixel the light covers
    matters little to the pixel's brightness); each judged on the mean of the channels, so
    that a colour that one surface barely reflects does not make a dim sky a bright light."""
    more = np.maximum(inputs.direct_a, inputs.direct_b).mean(axis=-1, keepdims=True)
    less = np.minimum(inputs.direct_a, inputs.direct_b).mean(axis=-1, keepdims=True)
    other = np.maximum(other_light.mean(axis=-1, keepdims=True), RELMSE_EPSILON)
    return (more > LIGHT_EDGE_RATIO * less) & (more > LIGHT_EDGE_CONTRAST * other)


def standard_error(error_map: np.ndarray) -> float:
    """The standard error of the mean of ``error_map`` (H, W), from the spread of its
    ``BLOCK`` x ``BLOCK`` blocks' means (the edges that do not fill a block left out), as a
    share of the mean; infinite where there are fewer than ``MIN_BLOCKS`` blocks."""
    height, width = (size // BLOCK * BLOCK for size in error_map.shape)
    blocks = (
        error_map[:height, :width].reshape(height // BLOCK, BLOCK, width // BLOCK, BLOCK).mean(axis=(1, 3))
    )
    mean = float(error_map.mean())
    if blocks.size < MIN_BLOCKS or mean == 0.0:
        return float("inf")
    return float(blocks.std(ddof=1) / np.sqrt(blocks.size) / abs(mean))


def estimate_error(inputs: DenoiseInputs, denoised_a: np.ndarray, denoised_b: np.ndarray) -> ErrorEstimate:
    """The estimated relMSE of the image (D_a + D_b) / 2, or a refusal (module docstring).

    Args:
        inputs: what the halves were denoised from.
        denoised_a, denoised_b: (H, W, 3) the denoised half images, each with its own
            directly seen light added back (``ptlab.denoise.pipeline``).
    """
    error = squared_error(inputs, denoised_a, denoised_b)

    def relative(stand_in: np.ndarray) -> np.ndarray:
        return (error / (stand_in + RELMSE_EPSILON) ** 2).mean(axis=-1)

    error_map = relative(brightness(inputs, denoised_a, denoised_b))
    value = float(error_map.mean())
    other = float(relative(brightness(inputs, denoised_a, denoised_b, alternative=True)).mean())
    error_spread = standard_error(error_map)
    blocks = (error_map.shape[0] // BLOCK) * (error_map.shape[1] // BLOCK)
    reason = None
    if blocks < MIN_BLOCKS:
        reason = (
            f"the image is too small to check the denoiser against: it has {blocks} blocks of "
            f"{BLOCK} x {BLOCK} pixels, at least {MIN_BLOCKS} are needed"
        )
    elif value <= 0:
        reason = f"it came out at {value:.2g}, not positive: its noise is larger than the error"
    elif max(value, other) > MAX_BRIGHTNESS_SPREAD * min(value, other):
        reason = (
            f"it is {value:.3g} or {other:.3g} as the truth's brightness is taken at light edges seen by "
            "one half's samples only and at small highlights: too few samples to tell"
        )
    elif value > MAX_RELMSE:
        reason = (
            f"it came out at {value:.2g}, above {MAX_RELMSE}: the denoised image is too far from the truth "
            "to stand in for its brightness"
        )
    elif error_spread > MAX_STANDARD_ERROR:
        reason = (
            f"its standard error is {error_spread:.0%} of its value {value:.3g} (at most "
            f"{MAX_STANDARD_ERROR:.0%} is trusted): the noisy image is too noisy, or too small, to check "
            "the denoiser against"
        )
    return ErrorEstimate(
        relmse=None if reason else value,
        reason=reason,
        value=value,
        alternative=other,
        standard_error=error_spread,
        error_map=error_map,
    )
