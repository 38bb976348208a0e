# %% [markdown]
# # Chapter 11 tutorial: how noisy is the Cornell box, and where should the next samples go?
#
# A user wants an image that is clean enough, as soon as possible; so a renderer must tell,
# from its own samples and with no reference, how noisy the image is and where the next
# samples should go. A pixel's value is the mean of its `n` samples; with independent
# samples of variance `sigma^2`, that mean has variance `sigma^2 / n`, estimated by the
# samples' own `s^2 / n`. The image's error is measured as the relMSE, the mean over pixels
# of `(I - R)^2 / (R + 0.01)^2`; its expectation is the mean of `var(mean) / (R + 0.01)^2`.
# Chapter 11's exercise is the variance of a pixel's mean, the weights that share out more
# samples, and the sharing (the chapter's page: `ptlab exercise docs 11`).
#
# This tutorial renders the Cornell box one sample per pixel per pass, keeping per pixel the
# sum of its samples, of their squares, and their count; estimates the image's relMSE from
# those alone and compares it with the relMSE against a render of 16 times the samples;
# then shares a budget of three times the samples taken among the pixels, by
# `sigma / (mu + 0.01)` (right) and by `sigma` alone (the chapter's typical mistake), and
# prints the relMSE each would give.

# %%
"""Chapter 11 tutorial: how noisy is the Cornell box, and where should the next samples go?

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/11_noise.py        # noise.png, noise-estimate.png, spp.png, spp-wrong.png
    python docs/tutorials/11_noise.py --res 64 --spp 8 --out /tmp/t
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import ptlab
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.measure.metrics import RELMSE_EPSILON, relmse
from ptlab.rendering.adaptive import (
    allocate,
    allocation_weights,
    pooled,
    reference_estimate,
    relative_variance,
    variance_of_mean,
)

args, out = tutorial_options(__doc__, res=128, spp=16, spp_help="passes of 1 sample per pixel, at least 4")
spp, res = max(args.spp, 4), args.res


# %% [markdown]
# ## A film of samples
#
# A render calls `on_pass` with its film after every pass; with one sample per pixel per
# pass, what the film's sums gained in a pass is that pass's sample. The samples are
# independent (`sampler="independent"`), as `s^2 / n` assumes: sobol's are spread so evenly
# that its mean varies less than `s^2 / n` says.


# %%
def film_of_samples(scene, spp: int, res: int, seed: int) -> tuple[np.ndarray, ...]:
    """(sums, squares, counts) of a render of ``spp`` passes of one sample per pixel: each
    pass's samples are what the film's sums gained in it. The samples are independent
    (``sampler="independent"``), as s^2 / n assumes: sobol's are spread more evenly than
    independent ones, and its mean varies less than s^2 / n says (the chapter's page)."""
    sums = np.zeros((res, res, 3))
    squares = np.zeros((res, res, 3))
    before = np.zeros((res, res, 3))
    taken: list[int] = []

    def take(film) -> None:
        assert (film.passes_done == len(taken) + 1).all()  # (one whole pass, no more)
        sample = film.sums - before
        sums[...] += sample
        squares[...] += sample * sample
        before[...] = film.sums
        taken.append(1)

    options = dict(spp=spp, res=res, seed=seed, workers=1, spp_per_pass=1, sampler="independent")
    ptlab.render_result(scene, **options, on_pass=take)
    return sums, squares, np.full((res, res), len(taken), dtype=np.int64)


# %%
scene = ptlab.load_scene("cornell-box")
sums, squares, counts = film_of_samples(scene, spp, res, seed=0)
image = sums / counts[..., None]
write_image(out / "noise.png", image)


# %% [markdown]
# ## How noisy is it
#
# Per pixel, the variance of the mean, `s^2 / n`, from the sums alone. The reference `R` in
# the relMSE's denominator is unknown: it is estimated by the median of the 3 x 3 pixels'
# means, which one firefly cannot move, but never less than half the pixel's own mean. The
# heat map is each pixel's estimated relative error, `sqrt(var(mean)) / (R + 0.01)`
# (brighter: noisier). The estimate is then checked against the relMSE measured against a
# render of 16 times the samples.


# %%
def heat_map(path: Path, values: np.ndarray, top: float) -> None:
    """``values`` from 0 to ``top`` as colours (matplotlib's inferno), written as a PNG."""
    import matplotlib.pyplot as plt

    plt.imsave(path, np.clip(values / top, 0, 1), cmap="inferno", vmin=0, vmax=1)


# %%
variance = variance_of_mean(sums, squares, counts)
denominator = (reference_estimate(sums, counts) + RELMSE_EPSILON) ** 2
estimate = float(np.mean(variance / denominator))
relative_error = np.sqrt((variance / denominator).mean(axis=-1))
heat_map(out / "noise-estimate.png", relative_error, top=float(np.quantile(relative_error, 0.99)))
reference = ptlab.render(scene, spp=16 * spp, res=res, seed=1, workers=1)  # (sobol: less noise)
true = relmse(image, reference)
print(f"wrote {out / 'noise.png'}: {spp} spp, relMSE {estimate:.4f} estimated, {true:.4f} measured")
print("  (measured against 16x the spp, whose own noise adds about 1/16 to the measurement:")
print("  the estimate is within 10% of the true error; the chapter's page)")
print(f"wrote {out / 'noise-estimate.png'}: sqrt(var(mean)) / (R + 0.01), each pixel's relative error")


# %% [markdown]
# ## Where the next samples go
#
# For a given total, the relMSE, the mean of `v_i / n_i` (`v_i` a pixel's relative variance
# per sample), is smallest when `n_i` follows `sqrt(v_i)`, that is `sigma_i / (R_i + 0.01)`.
# The typical mistake follows `sigma` alone, whatever the pixel's brightness: its samples go
# to the light and the bright ceiling, which need them least.


# %%
def by_sigma(variance, sums, counts) -> np.ndarray:
    """The typical mistake: weights that follow each pixel's sigma, whatever its brightness."""
    per_sample = variance * counts[..., None]
    return np.sqrt(np.maximum(pooled(per_sample.mean(axis=-1)), 0.0))  # (rounding: a hair below 0)


# %% [markdown]
# A budget of three times the samples taken so far, shared by each rule (`allocate`, at
# most 16 times `--spp` in a pixel), and the relMSE each sharing would give on average,
# beside sharing it uniformly. The heat maps show each pixel's samples in all.

# %%
budget, most = 3 * int(counts.sum()), 16 * spp
v = relative_variance(variance, sums, counts)  # (per sample, unpooled: an unbiased figure)
print(f"relMSE predicted after {4 * spp} spp in all (mean of v / n):")
print(f"  uniform                       {np.mean(v / (4 * counts)):.5f}")
rules = (
    ("spp.png", "sigma / (mu + 0.01)", allocation_weights(variance, sums, counts)),
    ("spp-wrong.png", "sigma alone (wrong)", by_sigma(variance, sums, counts)),
)
for name, rule, weights in rules:
    total = counts + allocate(weights, counts, budget, most)
    heat_map(out / name, total, top=most)
    spread = f"spp {total.min()}-{total.max()}"
    print(f"  by {rule:26s}  {np.mean(v / total):.5f}   wrote {out / name}: {spread}")
show_pictures(out)
