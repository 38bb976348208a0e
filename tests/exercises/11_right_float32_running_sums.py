"""A right chapter-11 answer that keeps everything in float32 and pools with running sums of
its own (a cumulative sum along each axis, differenced 7 apart), as a student would who
follows "float32 arithmetic passes". Its pooled values carry float32's rounding of sums that
ran through the whole film: in windows of pixels without noise, where the pooled value is 0,
the square root of that rounding is far above the library's; the checks allow it. The median
is a sort of the nine neighbours, and the water-filling a bisection on the total."""

import numpy as np


def variance_of_mean(sums, squares, counts):
    n = counts.astype(np.float32)[:, :, None]
    mean = sums.astype(np.float32) / np.maximum(n, 1)
    spread = np.maximum(squares.astype(np.float32) / np.maximum(n, 1) - mean * mean, 0)
    result = np.where(n > 1, spread / np.maximum(n - 1, 1), 0)
    return result.astype(np.float64)


def _neighbours(image):
    """(H, W, 9, C): each pixel's 3 x 3 neighbourhood, the edges repeated."""
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    height, width = image.shape[:2]
    return np.stack([padded[dy : dy + height, dx : dx + width] for dy in range(3) for dx in range(3)], axis=2)


def _running_box(values, radius=3):
    """Mean over (2 radius + 1)^2 windows, by running sums along each axis (edges mirrored)."""
    size = 2 * radius + 1
    out = np.pad(values, radius, mode="symmetric").astype(np.float32)
    for axis in (0, 1):
        running = np.cumsum(out, axis=axis, dtype=np.float32)
        zero = np.zeros_like(np.take(running, [0], axis=axis))
        running = np.concatenate([zero, running], axis=axis)
        length = out.shape[axis] - size + 1
        out = np.take(running, np.arange(size, size + length), axis=axis) - np.take(
            running, np.arange(length), axis=axis
        )
    return out / np.float32(size * size)


def allocation_weights(variance, sums, counts):
    n = counts.astype(np.float32)[:, :, None]
    means = sums.astype(np.float32) / np.maximum(n, 1)
    median = np.sort(_neighbours(means), axis=2)[:, :, 4]
    reference = np.maximum(median, means / 2)
    relative = (n * variance.astype(np.float32) / (reference + np.float32(0.01)) ** 2).mean(axis=2)
    return np.sqrt(np.maximum(_running_box(relative), 0))


def allocate(weights, counts, budget, most):
    room = np.maximum(most - counts, 0)
    if budget >= room.sum():
        return room

    def spent(level):
        return np.clip(level * weights - counts, 0, room).sum()

    low, high = 0.0, 1.0
    while spent(high) < budget:
        high *= 2
    for _ in range(100):
        low, high = ((low + high) / 2, high) if spent((low + high) / 2) < budget else (low, (low + high) / 2)
    wanted = np.clip(high * weights - counts, 0, room)
    extra = np.floor(wanted).astype(np.int64)
    short = int(budget - extra.sum())
    if short > 0:
        extra.flat[np.argsort(extra.ravel() - wanted.ravel(), kind="stable")[:short]] += 1
    return extra
