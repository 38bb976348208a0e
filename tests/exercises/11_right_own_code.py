"""A right chapter-11 answer, written as a student would (not the library's code): the
variance of the mean from the mean of the squares, the median by NumPy's sliding windows,
the pooling by an integral image, and the water-filling by a bisection of its own. It must
get full marks; the chapter's typical wrong answers are this file with the mistake patched
in (wrong_answers.toml)."""

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def variance_of_mean(sums, squares, counts):
    n = counts[..., None].astype(float)
    several = n > 1
    safe_n = np.where(several, n, 2.0)
    mean = sums / safe_n
    spread = np.clip(squares / safe_n - mean * mean, 0, None)  # the biased variance
    samples_variance = spread * safe_n / (safe_n - 1)
    return np.where(several, samples_variance / safe_n, 0.0)


def _median3(means):
    padded = np.pad(means, ((1, 1), (1, 1), (0, 0)), mode="edge")
    windows = sliding_window_view(padded, (3, 3), axis=(0, 1))
    return np.median(windows.reshape(*means.shape, 9), axis=-1)


def _box7(values):
    padded = np.pad(values, 3, mode="symmetric")
    table = np.zeros((padded.shape[0] + 1, padded.shape[1] + 1))
    table[1:, 1:] = padded.cumsum(0).cumsum(1)
    h, w = values.shape
    total = table[7 : 7 + h, 7 : 7 + w] - table[:h, 7 : 7 + w] - table[7 : 7 + h, :w] + table[:h, :w]
    return total / 49


def allocation_weights(variance, sums, counts):
    n = counts.astype(float)
    means = sums / np.maximum(n, 1)[..., None]
    reference = np.maximum(_median3(means), means / 2)
    per_sample = variance * n[..., None]
    v = np.mean(per_sample / (reference + 0.01) ** 2, axis=2)
    pooled = _box7(v)
    return np.sqrt(np.maximum(pooled, 0))


def allocate(weights, counts, budget, most):
    room = np.maximum(most - counts, 0)
    if budget >= room.sum():
        return room.astype(np.int64)
    low, high = 0.0, 1.0
    while np.clip(high * weights - counts, 0, room).sum() < budget:
        high *= 2
    for _ in range(80):
        middle = (low + high) / 2
        if np.clip(middle * weights - counts, 0, room).sum() < budget:
            low = middle
        else:
            high = middle
    wanted = np.clip(high * weights - counts, 0, room)
    given = np.floor(wanted).astype(np.int64)
    left = int(budget - given.sum())  # (below the number of pixels with a fraction: wanted is continuous)
    largest = np.argsort(-(wanted - given).ravel(), kind="stable")[: max(left, 0)]
    given.ravel()[largest] += 1
    return given
