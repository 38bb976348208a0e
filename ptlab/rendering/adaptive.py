"""Adaptive sampling: how noisy an image is, from its own samples, and where more samples go.

A render to a noise target (``render_result(..., target_error=E)``, ``ptlab render
--target-error E``) first takes the same samples everywhere, then, pass after pass, gives
new samples to the pixels whose error counts most, until its own estimate of the image's
relMSE (``ptlab.measure.metrics``) falls to E. This module is that estimate and that choice,
as functions of the film alone: per pixel, the sums of the samples, of their squares, and
their count.

**The estimate.** A pixel's value is the mean of its n samples. Were the samples
independent, the samples' unbiased variance s^2 over n would estimate the variance of that
mean (``variance_of_mean``). ptlab's samplers are not independent on purpose: sobol spreads a
pixel's samples so evenly that its error is about half of s^2 / n (docs/samplers.md), and
s^2 / n would then call the image twice as noisy as it is. So a render to a noise target
draws each pixel's even and odd samples as two independent sequences (each as well spread as
the whole), and the two halves' means, A and B, are two independent estimates of the pixel.
Since E[(A - B)^2] = 2 Var(A) and the pixel's mean (A + B) / 2 has Var(A) / 2,
(A - B)^2 / 4 is an unbiased estimate of the variance of the pixel's mean, whatever the
sampler (``variance_of_mean_from_halves``; the two "half buffers" of Rousselle, Knaus and
Zwicker, "Adaptive Rendering with Non-Local Means Filtering", SIGGRAPH Asia 2012, and of
Cycles' adaptive sampling). One pixel's estimate has a single degree
of freedom, so it is never trusted alone: the image's estimate is a mean over every pixel,
and the allocation below pools neighbours.

The relMSE divides each pixel's squared error by (R + 0.01)^2, and the reference R is
unknown. The pixel's own mean would do, but not where the noise is heavy-tailed: a pixel
that caught a firefly has a mean far above R, and would divide its large variance by its own
large mean, hiding exactly the noise that matters (the own mean gives 0.63-0.89 of the true
relMSE on the Cornell box and ``veach-mis``). The median of the 3 x 3 pixels' means
(``REFERENCE_WINDOW``) is what one firefly cannot move, and a step edge is its own median;
but it erases a feature smaller than the window, such as ``veach-mis``'s small lights seen
in its glossy plates, where it made the estimate thousands of times too high. So the
stand-in is the median, but never less than half the pixel's own mean (``OWN_MEAN_SHARE``):
a firefly's noise still counts up to four times its mean squared, and a small bright feature
is measured against its own brightness. On both scenes at 16 and 64 spp, three seeds each,
the estimate is then 0.85-1.11 of the true relMSE (``scripts/noise_target.py`` measures
renders to a target).

**Where the samples go.** The image's relMSE is the mean over pixels of v_i / n_i, with v_i
a pixel's relative variance per sample, s^2 / (R + 0.01)^2 averaged over the channels. For a
given number of samples it is least when n_i is proportional to sqrt(v_i) (a Lagrange
multiplier; the same rule as Neyman allocation in stratified survey sampling). One
pixel's s^2 from a few samples is too noisy to decide with, and deciding from a pixel's own
samples biases it (the pixels that happened to be quiet would keep their low values). So the
decision uses v pooled over a (2 ``POOL_RADIUS`` + 1)^2 window (as Cycles' adaptive sampling
judges a pixel with its neighbours): a pixel's own samples weigh 1/49 of its decision, and
decisions are made only between passes, from the film as it is then, which is the same bit
for bit whatever the workers. Pooling spreads the samples over a neighbourhood rather than
a pixel, which costs a little of the gain (an 8 x 8 block allocation gains about 1.3x over
uniform sampling where a per-pixel oracle, which knows each pixel's variance, gains 1.6x:
measured at 128x128 from 24 renders of 8 spp each of the Cornell box).
"""

from __future__ import annotations

import numpy as np

from ptlab.measure.metrics import RELMSE_EPSILON

# (scipy.ndimage is imported where it is used: importing it takes about 0.2 s, which every
# render would pay at start-up, and only a render to a noise target calls it.)

#: Edge of the window whose median mean stands in for the reference in the denominator.
REFERENCE_WINDOW = 3
#: ... but never less than this share of the pixel's own mean (module docstring).
OWN_MEAN_SHARE = 0.5
#: The share of the samples a pass's estimate says are still needed that the pass takes.
UNDERSHOOT = 0.8
#: The most a pixel's samples grow in one pass (a pass's estimate of one pixel is noisy).
GROWTH = 4
#: Half-width of the window a pixel's relative variance is pooled over (7 x 7 pixels).
POOL_RADIUS = 3


def variance_of_mean(sums: np.ndarray, squares: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(H, W, 3) the estimated variance of each pixel's mean for *independent* samples:
    s^2 / n, with s^2 the unbiased sample variance (n - 1 below), from the per-pixel sums of
    the samples (H, W, 3), of their squares (H, W, 3), and their counts (H, W). 0 where a
    pixel has fewer than 2 samples. (Too high for sobol's samples: module docstring.)"""
    n = np.asarray(counts, np.float64)[..., None]
    safe = np.maximum(n, 2.0)
    # sum (x - mean)^2 = sum x^2 - (sum x)^2 / n, never below 0 (rounding)
    deviations = np.maximum(squares - sums * sums / np.maximum(n, 1.0), 0.0)
    return np.where(n >= 2, deviations / ((safe - 1.0) * safe), 0.0)


def variance_of_mean_from_halves(differences: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(H, W, 3) the estimated variance of each pixel's mean from its two independent halves
    (module docstring): with D the even samples' sum less the odd samples' sum and n the
    count (even), A - B = 2 D / n, and the variance of the mean is (A - B)^2 / 4 = (D / n)^2."""
    n = np.maximum(np.asarray(counts, np.float64), 1.0)[..., None]
    return (differences / n) ** 2


def reference_estimate(sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(H, W, 3) what stands in for the unknown reference R: the median, channel by channel,
    of the pixel means in a ``REFERENCE_WINDOW``-wide window, but at least
    ``OWN_MEAN_SHARE`` of the pixel's own mean (module docstring)."""
    from scipy.ndimage import median_filter

    means = sums / np.maximum(np.asarray(counts, np.float64), 1.0)[..., None]
    median = median_filter(means, size=(REFERENCE_WINDOW, REFERENCE_WINDOW, 1), mode="nearest")
    return np.maximum(median, OWN_MEAN_SHARE * means)


def relative_variance(variance: np.ndarray, sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(H, W) each pixel's relative variance per sample, v = n var / (R + 0.01)^2 averaged
    over the channels (so that the pixel's relMSE is v / n), from ``variance`` (H, W, 3), the
    variance of each pixel's mean (``variance_of_mean_from_halves``, or ``variance_of_mean``
    for independent samples)."""
    n = np.asarray(counts, np.float64)[..., None]
    reference = reference_estimate(sums, counts)
    return (n * variance / (reference + RELMSE_EPSILON) ** 2).mean(axis=-1)


def estimated_relmse(variance: np.ndarray, sums: np.ndarray, counts: np.ndarray) -> float:
    """The image's relMSE as its own samples estimate it: the mean over pixels and channels
    of ``variance``, the variance of each pixel's mean, over (R + 0.01)^2
    (``reference_estimate`` for R)."""
    reference = reference_estimate(sums, counts)
    return float(np.mean(variance / (reference + RELMSE_EPSILON) ** 2))


def pooled(values: np.ndarray, radius: int = POOL_RADIUS) -> np.ndarray:
    """(H, W) the mean of ``values`` over the (2 radius + 1)^2 window around each pixel
    (the window reflected at the image's edges)."""
    from scipy.ndimage import uniform_filter

    return uniform_filter(np.asarray(values, np.float64), size=2 * radius + 1, mode="reflect")


def allocation_weights(variance: np.ndarray, sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(H, W) what each pixel's share of new samples is proportional to: sqrt of its relative
    variance per sample, pooled over its neighbourhood (``pooled``), so that n_i grows as
    sigma_i / (R_i + 0.01) where the noise is."""
    # (A running-sum filter can round a window of zeros to -1e-20: clipped.)
    return np.sqrt(np.maximum(pooled(relative_variance(variance, sums, counts)), 0.0))


def _water_level(weights: np.ndarray, counts: np.ndarray, cap: np.ndarray, enough) -> np.ndarray:
    """The totals clip(lambda w_i, n_i, cap_i) for the least lambda whose totals are
    ``enough`` (a test of the totals that more samples can only pass), by bisection on
    lambda between the level where no pixel has more than it has and the level where every
    pixel with a weight is at its cap. The bisection halves the interval's ratio, not its
    length: the levels span as many orders of magnitude as the weights do."""

    def totals(scale: float) -> np.ndarray:
        return np.clip(scale * weights, counts, cap)

    weighted = weights > 0
    if not weighted.any():
        return counts.astype(np.float64)
    low = float(np.min(np.maximum(counts[weighted], 1) / weights[weighted]))
    high = float(np.max(np.maximum(cap[weighted], 1) / weights[weighted]))
    if not enough(totals(high)):
        return totals(high)
    for _ in range(BISECTIONS):
        middle = np.sqrt(low * high)
        low, high = (low, middle) if enough(totals(middle)) else (middle, high)
    return totals(high)


#: Halvings of the water level's interval (of its logarithm): 2^-64 of it.
BISECTIONS = 64


def allocate(weights: np.ndarray, counts: np.ndarray, budget: int, most: int | np.ndarray) -> np.ndarray:
    """(H, W) int64 new samples per pixel, ``budget`` in all, so that each pixel's total
    count comes as close as it can to being proportional to its weight (sqrt(v) for the
    least relMSE), no pixel going past ``most`` samples (less than ``budget`` if the pixels
    with a weight above 0 have no more room).

    Water-filling: the totals are max(n_i, lambda w_i) for the lambda that spends the budget
    (found by bisection); the fractions left by rounding down go, one sample each, to the
    pixels with the largest (ties: the first in row order), so the result is exact and
    reproducible.
    """
    weights = np.asarray(weights, np.float64)
    counts = np.asarray(counts, np.int64)
    cap = np.maximum(counts, most)
    room = cap - counts
    if budget >= room.sum():
        return room
    if budget <= 0:
        return np.zeros_like(counts)
    share = _water_level(weights, counts, cap, lambda totals: totals.sum() - counts.sum() >= budget) - counts
    extra = np.floor(share).astype(np.int64)
    left = int(budget - extra.sum())
    if left > 0:  # (only to pixels with a weight and room left: the budget may go unspent)
        open_ = (extra < room) & (weights > 0)
        fraction = np.where(open_, share - extra, -1.0).ravel()
        order = np.argsort(-fraction, kind="stable")[: min(left, int(open_.sum()))]
        np.add.at(extra.reshape(-1), order, 1)
    elif left < 0:  # (the level's last step past the budget: take the smallest fractions back)
        given = extra > 0
        fraction = np.where(given, share - extra, np.inf).ravel()
        order = np.argsort(fraction, kind="stable")[: min(-left, int(given.sum()))]
        np.add.at(extra.reshape(-1), order, -1)
    return extra


def pass_budget(weights: np.ndarray, counts: np.ndarray, target: float, most: int | np.ndarray) -> int:
    """How many samples the next pass takes: the samples that, spent as ``allocate`` spends
    them (the totals max(n_i, lambda w_i)), bring the predicted relMSE, the mean of
    w_i^2 / n_i, to ``target``; times ``UNDERSHOOT``, but at least an eighth and at most all
    of what the film has (so that the estimate is renewed before the render has doubled),
    and no more than the pixels' room below ``most``."""
    weights = np.asarray(weights, np.float64)
    counts = np.asarray(counts, np.int64)
    cap = np.maximum(counts, most)
    taken, room = int(counts.sum()), int((cap - counts).sum())
    variance = weights * weights  # (per sample: w = sqrt(v))
    totals = _water_level(
        weights, counts, cap, lambda totals: np.mean(variance / np.maximum(totals, 1)) <= target
    )
    needed = float(totals.sum()) - taken
    # (A little short of the need: the estimate it comes from is itself noisy, and a last
    # small pass costs less than samples past the target.)
    budget = min(max(UNDERSHOOT * needed, taken / 8), taken)
    return int(min(np.ceil(budget), room))
