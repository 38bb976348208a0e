"""Chapter 11's checks: how noisy is it? (``variance_of_mean``, ``allocation_weights``,
``allocate``), the pieces of a render to a noise target (``ptlab.rendering.adaptive``).

Every check works on films made here, as the renderer keeps them: per pixel the sum of the
samples, of their squares, and their count, the samples drawn from gamma distributions of
known mean and spread (from the grading seed, so every grading's numbers are new). The
references come from ``ptlab.rendering.adaptive`` in the grader's process. Known answers:
the variance of a mean of n samples is s^2 / n, s^2 unbiased (n - 1); the relMSE-optimal
share of samples grows as sigma / (mu + 0.01) (a Lagrange multiplier, Neyman's allocation);
a firefly, one sample far above the rest, must not decide alone where samples go. The
student's ``allocation_weights`` gets the variance of the mean as the renderer passes it
(``ptlab.rendering.api`` calls ``adaptive.allocation_weights(variance, sums, counts, ...)``),
here from the library's ``variance_of_mean``. The mistakes each check names are the variants
of the right answer computed by ``_variant``, and, in "weights", a pooling window of
another size or off centre (``_window_hint``), in "allocation", new samples below 0
(``_negative_new``).

Each pitfall of the page (docs/11-noise.md) is a case the checks try: the variance of the
samples, n for n - 1, one sample or none (counts of 1 and 0), and cancellation (a block of
pixels whose samples are all alike, where sum x^2 - (sum x)^2 / n rounds a hair below 0: a
variance below 0 fails, ``_require_not_negative``) in "variance of the mean"; sigma for
sigma / (mu + 0.01) in "relative error"; no pooling in "one firefly"; the pixel's own mean,
a window off by one, and the square root of a pooled value a hair below 0 (a band of
pixels of no noise below and beside heavy-tailed ones, where a running-sum filter leaves
-1e-16 in windows of zeros: NaN, ``_weights``) in "weights"; new samples for totals, and
new samples below 0, in "allocation". Every
check is deterministic (inputs from the grading seed, exact references, tolerances far
above float32's rounding and far below any mistake): none fails a right answer, at any
grading seed (the right answers of tests/exercises pass every check at 1000 grading seeds,
``python scripts/check_seeds.py --seeds 1000 --chapter 11``; each of ``WEIGHT_MISTAKES``
fails "weights" at 300 of 300).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.ndimage import median_filter

from ptlab.course.chapter import Chapter, ChapterCheck, CheckFailed, grading_rng, require
from ptlab.course.finite import at_pixel, channel_name, finite_array
from ptlab.course.messages import aside, text
from ptlab.measure.metrics import RELMSE_EPSILON
from ptlab.rendering import adaptive

#: Pixels this far from the film's edge are compared: nearer, the windows of the median
#: (3 x 3) and of the pooling (7 x 7) reach past the edge, where any sensible padding is right.
MARGIN = adaptive.REFERENCE_WINDOW // 2 + adaptive.POOL_RADIUS
#: Relative tolerance of the exact comparisons: float32 arithmetic passes, every mistake
#: named below differs by far more (factors, or whole pixels' values).
TOLERANCE = 1e-4


#: A film's sums: (sums, squares, counts), each pixel's sum of samples and of their squares
#: ((H, W, 3)) and its number of samples ((H, W)).
Film = tuple[np.ndarray, np.ndarray, np.ndarray]


def _film(samples: np.ndarray, counts: np.ndarray) -> Film:
    """(sums, squares, counts) of a film whose pixel (y, x) took the first counts[y, x] of
    ``samples[y, x]`` ((H, W, K, 3) values)."""
    taken = np.arange(samples.shape[2]) < counts[..., None]
    kept = np.where(taken[..., None], samples, 0.0)
    return kept.sum(axis=2), (kept * kept).sum(axis=2), counts.astype(np.int64)


def _gamma(rng: np.random.Generator, mean: np.ndarray, shape: float | np.ndarray, k: int) -> np.ndarray:
    """(H, W, k, 3) samples of gamma distributions with per-pixel ``mean`` (H, W) and shape
    parameter ``shape`` (small: heavy-tailed, as light found by chance)."""
    mean = np.asarray(mean, np.float64)[..., None, None]
    shape = np.asarray(shape, np.float64)
    if shape.ndim:
        shape = shape[..., None, None]
    tint = np.array([1.0, 0.8, 0.6])
    size = (*np.broadcast_shapes(mean.shape[:2], np.shape(shape)[:2]), k, 3)
    return rng.gamma(np.broadcast_to(shape, size), 1.0, size) / shape * mean * tint


# The student's functions, checked --------------------------------------------------------


def _variance_of_mean(module, sums, squares, counts) -> np.ndarray:
    (variance_of_mean,) = require(module, "variance_of_mean")
    with np.errstate(all="ignore"):
        result = variance_of_mean(sums.copy(), squares.copy(), counts.copy())
    return finite_array(result, "variance_of_mean", sums.shape, text("ch11.hint.few_samples"))


def _weights(module, sums, squares, counts) -> np.ndarray:
    """The student's weights for a film, given the variance of each pixel's mean as the
    renderer gives it (computed here, so that a wrong ``variance_of_mean`` costs its own
    check only)."""
    (allocation_weights,) = require(module, "allocation_weights")
    variance = adaptive.variance_of_mean(sums, squares, counts)
    with np.errstate(all="ignore"):
        result = allocation_weights(variance, sums.copy(), counts.copy())
    hint = _nan_hint(result, variance, sums, counts)
    weights = finite_array(result, "allocation_weights", counts.shape, hint)
    if not (weights >= 0).all():
        raise CheckFailed(text("ch11.negative", value=float(weights.min())))
    return weights


def _nan_hint(result, variance: np.ndarray, sums: np.ndarray, counts: np.ndarray) -> str:
    """What a NaN among the student's weights (``result``, as returned) likely is: where the
    pooled relative variance is 0 (a window of pixels without noise), the square root of a
    running sum's remainder a hair below 0; elsewhere a pixel of too few samples."""
    try:
        result = np.asarray(result, dtype=np.float64)
    except (TypeError, ValueError):  # (not numbers: finite_array says so)
        return ""
    if result.shape != counts.shape or not np.isnan(result).any():
        return text("ch11.hint.few_samples")
    pooled = adaptive.pooled(adaptive.relative_variance(variance, sums, counts))
    y, x = np.argwhere(np.isnan(result))[0]
    if abs(pooled[y, x]) <= 1e-12 * np.abs(pooled).max():
        return text("ch11.hint.pooled_below_zero", x=x, y=y)
    return text("ch11.hint.few_samples")


# variance_of_mean -------------------------------------------------------------------------

#: Pixels of known samples: [1, 3] has mean 2, s^2 = 2, and the variance of its mean is 1;
#: [0, 0, 6]: s^2 = 12, 4; [1, 2, 3, 4]: 5/3, 5/12; one sample, or none: 0 (no spread is known).
KNOWN_PIXELS: tuple[list[float], ...] = (
    [1.0, 3.0],
    [0.0, 0.0, 6.0],
    [1.0, 2.0, 3.0, 4.0],
    [2.0, 2.0, 2.0, 2.0, 2.0],
    [5.0],
    [],
)


def _known_film(rng: np.random.Generator) -> tuple[list[np.ndarray], Film]:
    """The known pixels, each channel scaled and shifted by numbers of the grading seed."""
    scale = rng.uniform(0.5, 2.0, 3)
    shift = rng.uniform(0.0, 1.0, 3)
    pixels = [np.array(p)[:, None] * scale + shift for p in KNOWN_PIXELS]
    k = max(len(p) for p in pixels)
    samples = np.zeros((1, len(pixels), k, 3))
    for i, p in enumerate(pixels):
        samples[0, i, : len(p)] = p
    counts = np.array([[len(p) for p in pixels]])
    return pixels, _film(samples, counts)


def _vom_mistake(ratio: np.ndarray, n: np.ndarray) -> str:
    """The mistake whose answers are ``ratio`` times the right ones (pixels of n >= 2 samples)."""
    candidates = (
        (n, "ch11.hint.samples"),
        ((n - 1) / n, "ch11.hint.bessel"),
        (n - 1.0, "ch11.hint.samples_bessel"),
        (n / (n - 1.0), "ch11.hint.n_minus_1_twice"),
    )
    for factor, message_id in candidates:
        if np.allclose(ratio, factor, rtol=1e-3):
            return text(message_id)
    return ""


#: The whole film of "variance of the mean": SIZE x SIZE pixels of 1 to 16 samples, whose
#: CONSTANT x CONSTANT top right block has samples all alike in each pixel and colour.
SIZE, CONSTANT = 16, 8


def check_variance_of_mean(module) -> str:
    rng = grading_rng(110)
    pixels, (sums, squares, counts) = _known_film(rng)
    expected = adaptive.variance_of_mean(sums, squares, counts)
    yours = _variance_of_mean(module, sums, squares, counts)
    _require_not_negative(yours, (sums, squares, counts), lambda y, x, c: _known_pixel(pixels[x][:, c], c))
    _compare_variances(pixels, squares[0], counts[0], expected[0], yours[0])
    # A whole film: counts from 1 to 16, heavy tails, shifted means (a test of rounding too),
    # and a block of pixels whose samples are all alike (light seen directly, say), where
    # the cancellation of sum x^2 - (sum x)^2 / n rounds a hair either side of 0.
    mean = rng.uniform(0.05, 3.0, (SIZE, SIZE))
    samples = _gamma(rng, mean, rng.choice([0.3, 1.0, 8.0], (SIZE, SIZE)), 16)
    samples[:CONSTANT, -CONSTANT:] = samples[:CONSTANT, -CONSTANT:, :1]
    film = _film(samples, rng.integers(1, 17, (SIZE, SIZE)))
    expected = adaptive.variance_of_mean(*film)
    yours = _variance_of_mean(module, *film)
    _require_not_negative(yours, film, lambda y, x, c: at_pixel((y, x, c), yours.shape))
    off = ~(np.abs(yours - expected) <= TOLERANCE * expected + _rounding(film[1], film[2]))
    if off.any():
        y, x, c = np.argwhere(off)[0]
        n = int(film[2][y, x])
        raise CheckFailed(
            text(
                "ch11.vom_film",
                x=x,
                y=y,
                channel=channel_name(c),
                n=n,
                expected=expected[y, x, c],
                yours=yours[y, x, c],
            )
        )
    return text("ch11.vom_ok", pixels=len(KNOWN_PIXELS), film=mean.size, alike=CONSTANT * CONSTANT)


def _shown(samples: np.ndarray) -> str:
    """A known pixel's samples of one colour, as the messages list them: "[1, 3]"."""
    return "[" + ", ".join(f"{v:.4g}" for v in samples) + "]"


def _known_pixel(samples: np.ndarray, channel: int) -> str:
    """A known pixel in words: "the pixel whose samples are [1, 3] (red)"."""
    return text("ch11.known_pixel", samples=_shown(samples), channel=channel_name(channel))


def _require_not_negative(yours: np.ndarray, film: Film, pixel: Callable) -> None:
    """Fail if a variance of ``yours`` (H, W, 3) is below 0, naming the pixel (``pixel(y, x,
    channel)`` in words) and, where its samples are all alike (n sum x^2 = (sum x)^2 up to
    rounding), the cancellation that made it. ``film``: (sums, squares, counts)."""
    negative = yours < 0
    if not negative.any():
        return
    sums, squares, counts = film
    y, x, c = np.argwhere(negative)[0]
    n = int(counts[y, x])
    alike = n > 1 and abs(n * squares[y, x, c] - sums[y, x, c] ** 2) <= 1e-9 * sums[y, x, c] ** 2
    hint = text("ch11.hint.cancellation", sample=sums[y, x, c] / n) if alike else ""
    raise CheckFailed(
        text("ch11.vom_negative", value=yours[y, x, c], pixel=pixel(y, x, c), n=n) + aside(hint)
    )


def _rounding(squares: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """What rounding may add to a variance of the mean: sum x^2 - (sum x)^2 / n cancels, in
    float32 to about 1e-7 of sum x^2 (where the samples are all alike); 1e-6 of the mean
    square over n, far below any noise a render has."""
    n = np.maximum(np.asarray(counts, np.float64), 1.0)[..., None]
    return 1e-6 * squares / (n * n)


def _compare_variances(pixels, squares, counts, expected, yours) -> None:
    off = ~(np.abs(yours - expected) <= TOLERANCE * expected + _rounding(squares, counts))
    if not off.any():
        return
    i, c = np.argwhere(off)[0]
    n = counts.astype(np.float64)
    # (pixels whose expected value is not the rounding of a constant pixel)
    usable = (n >= 2) & (expected[:, c] > 1e-9 * expected[:, c].max())
    ratio = yours[usable, c] / expected[usable, c]
    hint = text("ch11.hint.one_sample") if n[i] < 2 else _vom_mistake(ratio, n[usable])
    raise CheckFailed(
        text(
            "ch11.vom_known",
            samples=_shown(pixels[i][:, c]),
            n=int(n[i]),
            channel=channel_name(c),
            expected=expected[i, c],
            yours=yours[i, c],
            hint=aside(hint),
        )
    )


# allocation_weights -----------------------------------------------------------------------


def _library(sums, squares, counts) -> np.ndarray:
    """``adaptive.allocation_weights`` of a film, as the student's is called (``_weights``)."""
    return adaptive.allocation_weights(adaptive.variance_of_mean(sums, squares, counts), sums, counts)


def _variant(sums, squares, counts, mistake: str) -> np.ndarray:
    """``adaptive.allocation_weights`` with one typical ``mistake``."""
    n = np.asarray(counts, np.float64)
    variance = adaptive.variance_of_mean(sums, squares, counts)
    per_sample = variance if mistake == "of_mean" else variance * n[..., None]
    if mistake == "own_mean":
        reference = sums / np.maximum(n, 1)[..., None]
    elif mistake == "median_only":
        means = sums / np.maximum(n, 1)[..., None]
        size = (adaptive.REFERENCE_WINDOW, adaptive.REFERENCE_WINDOW, 1)
        reference = median_filter(means, size=size, mode="nearest")
    else:
        reference = adaptive.reference_estimate(sums, counts)
    relative = per_sample if mistake == "sigma" else per_sample / (reference + RELMSE_EPSILON) ** 2
    v = relative.mean(axis=-1)
    if mistake == "no_pooling":
        return np.sqrt(v)
    if mistake == "pooled_sigma":
        return adaptive.pooled(np.sqrt(v))
    if mistake == "no_sqrt":
        return adaptive.pooled(v)
    return np.sqrt(np.maximum(adaptive.pooled(v), 0.0))


#: The mistakes ``_variant`` knows, each with the hint that names it.
WEIGHT_MISTAKES = {
    "sigma": "ch11.hint.sigma",
    "no_sqrt": "ch11.hint.no_sqrt",
    "no_pooling": "ch11.hint.no_pooling",
    "own_mean": "ch11.hint.own_mean",
    "median_only": "ch11.hint.median_only",
    "of_mean": "ch11.hint.of_mean",
    "pooled_sigma": "ch11.hint.pooled_sigma",
}


#: float32's relative rounding: a pooled sum of float32 numbers may be off by this times the
#: sum of what it ran through (an integral image runs through the whole film).
FLOAT32_EPSILON = float(np.finfo(np.float32).eps)


def _inner(margin: int) -> tuple[slice, slice]:
    """The pixels ``margin`` or more inside the edges of a film."""
    return (slice(margin, -margin), slice(margin, -margin))


def _common_factor(yours: np.ndarray, expected: np.ndarray) -> float:
    """The one number that ``expected`` times comes nearest to ``yours`` (least squares)."""
    return float(np.sum(yours * expected) / max(float(np.sum(expected * expected)), 1e-300))


def _same_up_to_scale(
    yours: np.ndarray, expected: np.ndarray, rounding: float = 0.0, margin: int = MARGIN
) -> bool:
    """Whether ``yours`` is ``expected`` times one positive number (only the weights'
    proportions decide where samples go), on the pixels ``margin`` inside the edges.

    ``rounding``: how far a pooled v may be off by rounding alone (in ``expected``'s units
    squared). A weight sqrt(p) is then off by at most rounding / (2 sqrt(p)), and by
    sqrt(rounding) where p is about as small (a window without noise, whose weight is 0):
    that much is allowed beside TOLERANCE of the weight."""
    yours, expected = yours[_inner(margin)], expected[_inner(margin)]
    scale = _common_factor(yours, expected)
    floor = math.sqrt(rounding)
    slack = floor * np.minimum(1.0, floor / np.maximum(expected, 1e-300))
    allowed = scale * (TOLERANCE * expected + slack)
    return scale > 0 and bool(np.all(np.abs(yours - scale * expected) <= allowed))


def _halves(rng: np.random.Generator) -> Film:
    """A film of two halves with the same kind of noise: dark on the left (mean 0.02),
    bright on the right (mean 2), 32 samples a pixel, both times one number of the grading
    seed in [0.9, 1.1]. Right weights: sigma / (mu + 0.01) gives 0.02 / 0.03 over 2 / 2.01,
    0.67, in red; with the tint (1, 0.8, 0.6) of ``_gamma`` green and blue are darker, and
    v, averaged over the channels, makes it 0.59-0.64 by the seed's number (0.58-0.65 as
    the library's estimates from the samples give it). By sigma alone: 0.01."""
    height, width = 24, 48
    mean = np.where(np.arange(width) < width // 2, 0.02, 2.0) * rng.uniform(0.9, 1.1)
    samples = _gamma(rng, np.broadcast_to(mean, (height, width)), 4.0, 32)
    return _film(samples, np.full((height, width), 32))


def _dark_over_bright(weights: np.ndarray) -> float:
    """The median weight of the dark half over the bright half's, away from edges."""
    width = weights.shape[1]
    rows = slice(MARGIN, -MARGIN)
    dark = weights[rows, MARGIN : width // 2 - MARGIN]
    bright = weights[rows, width // 2 + MARGIN : -MARGIN]
    return float(np.median(dark) / max(float(np.median(bright)), 1e-300))


def check_relative(module) -> str:
    film = _halves(grading_rng(111))
    expected = _dark_over_bright(_library(*film))
    yours = _dark_over_bright(_weights(module, *film))
    if abs(yours / expected - 1) <= 0.1:
        return text("ch11.relative_ok", ratio=yours)
    hint = text("ch11.hint.other_values")
    for mistake in ("sigma", "no_sqrt"):
        if abs(yours / _dark_over_bright(_variant(*film, mistake)) - 1) <= 0.1:
            hint = text(WEIGHT_MISTAKES[mistake])
    if abs(yours - 1) <= 0.05:
        hint = text("ch11.hint.uniform")
    raise CheckFailed(text("ch11.relative", expected=expected, yours=yours, hint=hint))


def _firefly_film(rng: np.random.Generator) -> tuple[Film, tuple[int, int]]:
    """A film of even noise (mean 0.5, 16 samples a pixel) in which one pixel's sample is a
    firefly 200 times the mean: the light of a rare path that happened to be found there."""
    size = 24
    samples = _gamma(rng, np.full((size, size), 0.5), 4.0, 16)
    y, x = (int(v) for v in rng.integers(MARGIN + 2, size - MARGIN - 2, 2))
    samples[y, x, rng.integers(16)] = 100.0 * rng.uniform(0.9, 1.1)
    return _film(samples, np.full((size, size), 16)), (y, x)


def check_firefly(module) -> str:
    film, (y, x) = _firefly_film(grading_rng(112))
    weights = _weights(module, *film)
    around = np.delete(weights[y - 1 : y + 2, x - 1 : x + 2].ravel(), 4)
    ratio = float(weights[y, x] / max(float(np.median(around)), 1e-300))
    if ratio <= 2.0:
        return text("ch11.firefly_ok", ratio=ratio)
    raise CheckFailed(text("ch11.firefly", x=x, y=y, ratio=ratio, hint=text("ch11.hint.no_pooling")))


#: The band of pixels without noise along the bottom and the right of the weights film:
#: wide enough for windows of the pooling (7 x 7) that hold nothing else, and whole 4 x 4
#: blocks of counts.
QUIET_BAND = 8


def _weights_film(rng: np.random.Generator) -> Film:
    """A film as a render leaves it after a few adaptive passes: a gradient with a step edge,
    noise from smooth to heavy-tailed, counts from 2 to 16 by 4 x 4 blocks, three fireflies;
    along its bottom and right a band QUIET_BAND wide of pixels whose samples are all alike
    (a light seen directly), in values a sum holds exactly, so that their variance is 0.

    The band is the pitfall of the square root of a pooled value a hair below 0: a
    running-sum filter (``scipy.ndimage.uniform_filter``, an integral image) that has passed
    the heavy-tailed pixels leaves a remainder of about -1e-16 or +1e-16 in the windows of
    the band that hold nothing else, one per row and one per column (whichever axis it
    filters first), so some are below 0 and their square root is NaN.
    """
    size = 28
    y, x = np.mgrid[0:size, 0:size] / size
    mean = 0.03 + 1.5 * x * y + np.where(x > 0.55, 0.8, 0.0)
    shape = np.where(y > 0.5, 0.4, 6.0)
    samples = _gamma(rng, mean, shape, 16)
    for _ in range(3):
        py, px = rng.integers(0, size, 2)
        samples[py, px, 0] *= 50.0
    full = size + QUIET_BAND
    quiet = np.round(64 * rng.uniform(0.1, 2.0, (full, full, 1, 3))) / 64  # (multiples of 1/64: exact)
    quiet = np.broadcast_to(quiet, (full, full, 16, 3)).copy()
    quiet[:size, :size] = samples
    blocks = rng.integers(2, 17, (full // 4, full // 4))
    return _film(quiet, np.kron(blocks, np.ones((4, 4), np.int64)))


def check_weights(module) -> str:
    film = _weights_film(grading_rng(113))
    yours = _weights(module, *film)
    # (float32 pooling may round each pooled v by this much: the windows without noise)
    v = adaptive.relative_variance(adaptive.variance_of_mean(*film), film[0], film[2])
    rounding = FLOAT32_EPSILON * float(v.sum())
    expected = _library(*film)
    if _same_up_to_scale(yours, expected, rounding):
        return text("ch11.weights_ok", pixels=(film[2].shape[0] - 2 * MARGIN) ** 2)
    hint = _mistake_hint(yours, film, rounding) or _window_hint(yours, expected, v, rounding)
    raise CheckFailed(text("ch11.weights", hint=hint or text("ch11.hint.other_values")))


def _mistake_hint(yours: np.ndarray, film: Film, rounding: float) -> str:
    """The hint of the first of WEIGHT_MISTAKES whose weights ``yours`` are; "" if none."""
    for mistake, message_id in WEIGHT_MISTAKES.items():
        if _same_up_to_scale(yours, _variant(*film, mistake), rounding):
            return text(message_id)
    return ""


#: Pixels each side of the pixel in the recipe's pooling window (7 x 7).
POOL = adaptive.POOL_RADIUS
#: How far a pooling window that "weights" tries may reach from its pixel, per side: a size,
#: an origin or a slice end off by one makes the recipe's 3 a 2 or a 4.
WINDOW_REACH = 5


def _pooled_window(v: np.ndarray, reach: tuple[int, int, int, int]) -> np.ndarray:
    """(H, W) the mean of ``v`` over rows y - up .. y + down and columns x - left .. x + right
    of each pixel, ``reach`` = (up, down, left, right); reflected at the edges."""
    from scipy.ndimage import uniform_filter1d

    for axis, before, after in ((0, *reach[:2]), (1, *reach[2:])):
        size = before + after + 1
        # (scipy's window of ``size`` reaches size // 2 before its pixel; origin moves it)
        v = uniform_filter1d(v, size, axis=axis, mode="reflect", origin=before - size // 2)
    return v


def _windows_near_the_recipe() -> list[tuple[int, int, int, int]]:
    """Every window of up to WINDOW_REACH each side but the recipe's, the nearest first."""
    reaches = range(WINDOW_REACH + 1)
    windows = [(u, d, le, r) for u in reaches for d in reaches for le in reaches for r in reaches]
    windows.remove((POOL, POOL, POOL, POOL))
    return sorted(windows, key=lambda w: sum(abs(side - POOL) for side in w))


def _window_hint(yours: np.ndarray, expected: np.ndarray, v: np.ndarray, rounding: float) -> str:
    """The hint for weights that are the recipe's but for the pooling window, the square root
    of ``v`` (each pixel's relative variance) pooled over another window than 7 x 7 centred
    on the pixel: which window, and a pixel where it shows; "" for any other answer. A window
    is compared only where it and its pixels' 3 x 3 medians stay inside the film (the
    student's padding is free)."""
    for reach in _windows_near_the_recipe():
        margin = max(max(reach), POOL) + adaptive.REFERENCE_WINDOW // 2
        pooled_here = np.sqrt(np.maximum(_pooled_window(v, reach), 0.0))
        if _same_up_to_scale(yours, pooled_here, rounding, margin):
            return _window_found(yours, expected, reach)
    return ""


def _window_found(yours: np.ndarray, expected: np.ndarray, reach: tuple[int, int, int, int]) -> str:
    """The pooling window ``reach`` in words, with the pixel where the student's weights
    (scaled to the recipe's) differ most from the recipe's, relatively: among the pixels
    whose windows stay inside the film, and whose weight is not about 0 (the band without
    noise, where the recipe's weight is rounding)."""
    inner = _inner(MARGIN)
    scaled = yours / _common_factor(yours[inner], expected[inner])
    shown = np.zeros_like(expected, dtype=bool)
    shown[_inner(WINDOW_REACH + 1)] = True
    shown &= expected > 0.01 * expected.max()
    gap = np.where(shown, np.abs(scaled / np.where(shown, expected, 1.0) - 1.0), -1.0)
    y, x = np.unravel_index(np.argmax(gap), gap.shape)
    up, down, left, right = reach
    centred = up == down and left == right
    return text(
        "ch11.hint.pool_window",
        height=up + down + 1,
        width=left + right + 1,
        top=_offset("y", -up),
        bottom=_offset("y", down),
        left=_offset("x", -left),
        right=_offset("x", right),
        x=x,
        y=y,
        yours=scaled[y, x],
        expected=expected[y, x],
        cause=text("ch11.hint.pool_size" if centred else "ch11.hint.pool_shifted"),
    )


def _offset(axis: str, step: int) -> str:
    """A row or column ``step`` from the pixel's, in words: "y - 3", "x + 2", "y"."""
    return f"{axis} - {-step}" if step < 0 else f"{axis} + {step}" if step > 0 else axis


# allocate ---------------------------------------------------------------------------------


def _allocation_case(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Weights of a small film (smooth, with a noisy corner), its counts after a pass or
    two, the next pass's budget (a third of what it has) and the cap, which a few pixels reach."""
    size = 12
    y, x = np.mgrid[0:size, 0:size] / size
    weights = 0.2 + x + np.where((x > 0.7) & (y < 0.3), 6.0, 0.0) * rng.uniform(0.8, 1.2)
    counts = rng.integers(4, 13, (size, size))
    budget = int(counts.sum() // 3)
    return weights, counts, budget, 24


def _proportional_new(
    extra: np.ndarray, weights: np.ndarray, counts: np.ndarray, budget: int, most: int
) -> str:
    """The hint for new samples shared in proportion to the weights (clipped at the cap or
    not), with no regard to the samples each pixel has; "" for any other answer."""
    share = weights * budget / weights.sum()
    for wanted in (share, np.minimum(share, np.maximum(most - counts, 0))):
        if (np.abs(extra - wanted) <= 1).all():
            return text("ch11.hint.new_not_total")
    return ""


def _negative_new(extra: np.ndarray, expected: np.ndarray, weights: np.ndarray, counts: np.ndarray) -> str:
    """The failure of new samples below 0 (``extra``; ``expected``, the library's): the
    first such pixel, and, where the water-filling gives it nothing (it has more than its
    share already), the cause: the share less what it has, not clipped at 0."""
    y, x = np.argwhere(extra < 0)[0]
    n = int(counts[y, x])
    hint = text("ch11.hint.negative_new", n=n, total=float(n + extra[y, x])) if expected[y, x] == 0 else ""
    return text(
        "ch11.allocate_negative", x=x, y=y, yours=float(extra[y, x]), n=n, weight=weights[y, x]
    ) + aside(hint)


def check_allocate(module) -> str:
    (allocate,) = require(module, "allocate")
    weights, counts, budget, most = _allocation_case(grading_rng(114))
    with np.errstate(all="ignore"):
        result = allocate(weights.copy(), counts.copy(), budget, most)
    extra = finite_array(result, "allocate", counts.shape)
    hint = aside(_proportional_new(extra, weights, counts, budget, most))
    expected = adaptive.allocate(weights, counts, budget, most)
    if (extra < 0).any():
        raise CheckFailed(_negative_new(extra, expected, weights, counts))
    if not np.array_equal(extra, np.round(extra)):
        raise CheckFailed(text("ch11.allocate_integers") + hint)
    total = int(extra.sum())
    if total != budget:
        raise CheckFailed(text("ch11.allocate_budget", total=total, budget=budget) + hint)
    if (counts + extra > most).any():
        y, x = np.argwhere(counts + extra > most)[0]
        total = int(counts[y, x] + extra[y, x])
        raise CheckFailed(text("ch11.allocate_most", x=x, y=y, total=total, most=most) + hint)
    off = np.abs(extra - expected) > 1
    if off.any():
        y, x = np.argwhere(off)[0]
        raise CheckFailed(
            text(
                "ch11.allocate",
                x=x,
                y=y,
                n=int(counts[y, x]),
                weight=weights[y, x],
                expected=int(expected[y, x]),
                yours=int(extra[y, x]),
                hint=hint,
            )
        )
    capped = int((counts + extra == most).sum())
    return text("ch11.allocate_ok", budget=budget, pixels=counts.size, capped=capped)


CHAPTER = Chapter(
    number=11,
    slug="noise",
    title="How noisy is it?",
    functions=("variance_of_mean", "allocation_weights", "allocate"),
    answers=(
        "ptlab.rendering.adaptive.variance_of_mean",
        "ptlab.rendering.adaptive.allocation_weights",
        "ptlab.rendering.adaptive.allocate",
        # (steps 1 and 2 of allocation_weights, which would leave only the pooling to write)
        "ptlab.rendering.adaptive.reference_estimate",
        "ptlab.rendering.adaptive.relative_variance",
    ),
    # The rest of the noise target: its estimate and its pooling.
    also_left_out=("ptlab.rendering.adaptive",),
    checks=(
        ChapterCheck("variance of the mean", 3, check_variance_of_mean, timeout=30),
        ChapterCheck("relative error", 2, check_relative, timeout=30),
        ChapterCheck("one firefly", 2, check_firefly, timeout=30, requires=("relative error",)),
        ChapterCheck("weights", 2, check_weights, timeout=30),
        ChapterCheck("allocation", 1, check_allocate, timeout=30),
    ),
)
