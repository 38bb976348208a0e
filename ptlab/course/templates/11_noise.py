"""Chapter 11: how noisy is it?

The chapter's page: ``ptlab exercise docs 11`` (中文: ``--zh``).

A render to a noise target (``ptlab render SCENE --target-error E``) must say how noisy its
image is without a reference, and give its next samples to the pixels whose error counts
most. It keeps, per pixel, three numbers: the sum of the samples, the sum of their squares,
and their count. From them, write

* ``variance_of_mean``: how much each pixel's mean would change from one render to the next;
* ``allocation_weights``: what each pixel's share of the next samples is proportional to;
* ``allocate``: the next pass's samples, pixel by pixel.

Check your work with

    ptlab exercise check 11 11_noise.py

Everything is whole arrays: ``sums`` holds every pixel at once. Write it with NumPy (and,
for the windows, ``scipy.ndimage``) operations, never a Python loop over pixels.
"""

import numpy as np


def variance_of_mean(sums, squares, counts):
    """The estimated variance of each pixel's mean, per channel.

    Args:
        sums: (H, W, 3) float64, per pixel and channel the sum of its samples, sum x.
        squares: (H, W, 3) float64, the sum of their squares, sum x^2.
        counts: (H, W) int64, how many samples each pixel has, n.

    Returns:
        (H, W, 3): s^2 / n, where s^2 = sum (x - mean)^2 / (n - 1) is the samples'
        unbiased variance; 0 where a pixel has fewer than 2 samples.

    Hints:
        * sum (x - mean)^2 = sum x^2 - (sum x)^2 / n: no need for the samples themselves.
          Rounding can make it a hair below 0: clip it at 0.
        * A pixel's value is the *mean* of its n samples: it varies n times less than one
          sample does.
        * ``counts`` is (H, W): ``counts[..., None]`` lines it up with the channels.
    """
    raise NotImplementedError("variance_of_mean")


def allocation_weights(variance, sums, counts):
    """What each pixel's share of new samples is proportional to (only the proportions
    count: any common factor is fine).

    Args:
        variance: (H, W, 3) the variance of each pixel's mean: ``variance_of_mean``'s, or,
            in a render with the sobol sampler, the renderer's estimate from two half buffers
            (the chapter's page says why).
        sums, counts: the film, as for ``variance_of_mean``.

    Returns:
        (H, W) weights >= 0, computed in four steps:

        1. R, what stands in for the unknown reference: per channel, the median of the
           means (sums / max(counts, 1): 0 for a pixel of no samples) of the 3 x 3 pixels
           around each pixel
           (``scipy.ndimage.median_filter`` with ``size=(3, 3, 1)``), but never less than
           half the pixel's own mean;
        2. v, each pixel's relative variance per sample: n times the variance of its mean,
           over (R + 0.01)^2, averaged over the three channels;
        3. v pooled: the mean of v over the 7 x 7 pixels centred on each pixel, rows
           y - 3 to y + 3 and columns x - 3 to x + 3 (``scipy.ndimage.uniform_filter``
           with ``size=7``);
        4. the square root of the pooled v.

    Hints:
        * The relMSE is the mean over pixels of v_i / n_i. For a given total number of
          samples it is least when n_i is proportional to sqrt(v_i) = sigma_i / (R_i + 0.01)
          (a Lagrange multiplier): not to sigma_i, which would spend the samples on the
          bright pixels, where an error of the same size counts least.
        * One pixel's s^2 from a few samples is noisy: a pixel that caught one firefly has a
          huge one. Pooling lets no single pixel decide.
        * The median, not the pixel's own mean, in the denominator: a firefly raises its
          own pixel's mean, and would hide the noise it brings. But a median erases a
          bright feature narrower than its window (a small light, a light's edge): half the
          pixel's own mean is the floor that keeps such a pixel bright.
        * Near the film's edges, pad any sensible way (the checks look inside).
        * ``uniform_filter`` keeps a running sum: after a huge value, a window of zeros can
          come out a hair below 0, whose square root is NaN. Clip at 0 first.
    """
    raise NotImplementedError("allocation_weights")


def allocate(weights, counts, budget, most):
    """The next pass's new samples, per pixel.

    Args:
        weights: (H, W) from ``allocation_weights``.
        counts: (H, W) int64, the samples each pixel has.
        budget: how many new samples to hand out, in all.
        most: the most samples a pixel may have.

    Returns:
        (H, W) int64 new samples >= 0, adding up to ``budget`` exactly (or to what is left
        below ``most``, if that is less), no pixel's total past ``most``, and each pixel's
        *total* (counts + new) as near to proportional to its weight as can be: the totals
        are max(n_i, lambda w_i) for the lambda that spends the budget ("water-filling").

    Hints:
        * A pixel that already has more than its share gets nothing, never a number below
          0: it cannot give samples back.
        * Find lambda by bisection: the samples wanted, sum of clip(lambda w - n, 0,
          most - n), grow with lambda.
        * Round down, then give the samples left, one each, to the pixels with the largest
          fractions.
    """
    raise NotImplementedError("allocate")
