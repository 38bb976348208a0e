"""A right chapter-11 answer in unusual but valid code: float32 arithmetic, the windows by
scipy.ndimage with other edge modes than the library's ('reflect' for the median, 'mirror'
for the pooling), the channels summed rather than averaged, the weights in per cent (only
their proportions count), and lambda found by scipy's root finder. It must get full marks."""

import numpy as np
from scipy import ndimage, optimize


def variance_of_mean(sums, squares, counts):
    n = np.float32(1) * counts[:, :, np.newaxis]
    deviations = squares.astype(np.float32) - sums.astype(np.float32) ** 2 / np.fmax(n, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        result = np.fmax(deviations, 0) / (n * (n - 1))
    return np.where(n >= 2, result, 0).astype(np.float64)


def allocation_weights(variance, sums, counts):
    n = counts[:, :, np.newaxis].astype(np.float32)
    means = sums.astype(np.float32) / np.fmax(n, 1)
    reference = ndimage.median_filter(means, footprint=np.ones((3, 3, 1), bool), mode="reflect")
    reference = np.maximum(reference, means * np.float32(0.5))
    v = (variance.astype(np.float32) * n / np.square(reference + 0.01)).sum(axis=-1)
    return 100 * np.sqrt(np.fmax(ndimage.uniform_filter(v, size=(7, 7), mode="mirror"), 0))


def allocate(weights, counts, budget, most):
    room = np.clip(most - counts, 0, None)
    if budget >= room.sum():
        return room

    def overspent(scale):
        return np.clip(scale * weights - counts, 0, room).sum() - budget

    top = (counts + room).max() / weights[weights > 0].min()
    scale = optimize.brentq(overspent, 0.0, top, xtol=1e-12)
    wanted = np.clip(scale * weights - counts, 0, room)
    new = wanted.astype(np.int64)  # (floor: wanted >= 0)
    short = budget - new.sum()
    if short > 0:
        fractions = np.where(new < room, wanted - new, -1).ravel()
        new.flat[np.argpartition(-fractions, short - 1)[:short]] += 1
    return new
