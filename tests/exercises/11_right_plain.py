"""A right chapter-11 answer written the plain way the exercise file's hints lead to, close
to the library's own: it must not be taken for a copy of it."""

import numpy as np
from scipy.ndimage import median_filter, uniform_filter


def variance_of_mean(sums, squares, counts):
    n = counts[..., None].astype(np.float64)
    deviations = np.maximum(squares - sums**2 / np.maximum(n, 1), 0)
    return np.where(n >= 2, deviations / (np.maximum(n - 1, 1) * np.maximum(n, 1)), 0.0)


def allocation_weights(variance, sums, counts):
    n = counts.astype(np.float64)[..., None]
    means = sums / np.maximum(n, 1)
    reference = np.maximum(median_filter(means, size=(3, 3, 1)), 0.5 * means)
    v = (n * variance / (reference + 0.01) ** 2).mean(axis=-1)
    return np.sqrt(np.maximum(uniform_filter(v, size=7), 0))


def allocate(weights, counts, budget, most):
    room = np.maximum(most - counts, 0)
    if budget >= room.sum():
        return room
    low, high = 0.0, 1.0
    while np.clip(high * weights - counts, 0, room).sum() < budget:
        high *= 2
    for _ in range(100):
        middle = (low + high) / 2
        if np.clip(middle * weights - counts, 0, room).sum() < budget:
            low = middle
        else:
            high = middle
    share = np.clip(high * weights - counts, 0, room)
    extra = np.floor(share).astype(np.int64)
    left = int(budget - extra.sum())
    if left > 0:
        order = np.argsort(-(share - extra).ravel(), kind="stable")[:left]
        extra.ravel()[order] += 1
    return extra
