# %% [markdown]
# # Chapter 6 tutorial: Monte Carlo integration and the diffuse material
#
# The light a surface reflects toward the viewer is an integral over every direction light
# can come from, `∫ f_r(wo, wi) L_i(wi) cos(theta_i) dwi`. A path tracer estimates it: draw
# a direction `wi` with density `pdf(wi)`, and `f_r L_i cos / pdf` is right on average,
# whatever the density, as long as `pdf` is the density `wi` was really drawn with. A
# Lambertian surface has `f_r = albedo / pi`, so that its reflectance, the integral of
# `f_r cos` over the hemisphere, is the albedo. Chapter 6's exercise is that material:
# `sample`, `eval` and `pdf` (the chapter's page: `ptlab exercise docs 6`).
#
# This tutorial estimates the reflectance of a white Lambertian surface (exactly 1) with
# uniform and with cosine-weighted directions, and with the chapter's typical mistake, then
# renders the Cornell box with the library's `Diffuse` and with that mistake in place of
# every diffuse material.

# %%
"""Chapter 6 tutorial: Monte Carlo integration and the diffuse material.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/06_diffuse.py                # writes diffuse.png, diffuse-wrong.png
    python docs/tutorials/06_diffuse.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import numpy as np

import ptlab
from ptlab.course.renders import replace_materials
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.materials import Diffuse, Material

args, out = tutorial_options(__doc__, res=128, spp=64)


# %% [markdown]
# ## The mistake: the pdf of the whole sphere
#
# Uniform directions over the hemisphere have the density `1 / (2 pi)`: the hemisphere's
# area is `2 pi`. The typical mistake divides by `1 / (4 pi)`, the uniform density of the
# whole *sphere*: the pdf is 2x too small, so every bounce's weight `f_r cos / pdf` is 2x
# too big. Here it is as a material that samples and evaluates like the library's uniform
# `Diffuse`, but halves its pdf.


# %%
class SpherePdf(Material):
    """The typical mistake: uniform hemisphere sampling, but the pdf 1 / (4 pi) of the whole
    sphere (2x too small), so every bounce's weight f cos / pdf is 2x too big."""

    def __init__(self, albedo):
        self.diffuse = Diffuse(albedo, sampling="uniform")

    def eval(self, wo, wi, n):
        return self.diffuse.eval(wo, wi, n)

    def sample(self, wo, n, u):
        return self.diffuse.sample(wo, n, u)

    def pdf(self, wo, wi, n):
        return self.diffuse.pdf(wo, wi, n) / 2


# %% [markdown]
# ## Estimating the reflectance
#
# `sample_weight` draws a direction per row of `u` and returns it with its weight
# `f_r cos / pdf`; the mean of 16 weights is one estimate of the reflectance. A thousand
# such estimates show the estimator's mean (right or not) and its spread (the noise).


# %%
def reflectance_estimates(material, samples: int, estimates: int, rng) -> np.ndarray:
    """``estimates`` Monte Carlo estimates of the integral of f_r cos over the hemisphere,
    each the mean of ``samples`` terms f_r cos / pdf (what ``sample_weight`` returns)."""
    rows = samples * estimates
    n = np.tile([0.0, 0.0, 1.0], (rows, 1))
    wo = np.tile([0.6, 0.0, 0.8], (rows, 1))
    _, weight = material.sample_weight(wo, n, rng.random((rows, 2)))
    return weight[:, 0].reshape(estimates, samples).mean(axis=1)


# %%
rng = np.random.default_rng(0)
white = (1.0, 1.0, 1.0)
print("Monte Carlo estimates of the reflectance of a white Lambertian surface (exactly 1),")
print("1000 estimates of 16 samples each:")
for name, material in [
    ("uniform, pdf 1/(2 pi)", Diffuse(white, sampling="uniform")),
    ("cosine, pdf cos/pi", Diffuse(white, sampling="cosine")),
    ("uniform, pdf 1/(4 pi) (wrong)", SpherePdf(white)),
]:
    estimates = reflectance_estimates(material, 16, 1000, rng)
    print(f"  {name:30} mean {estimates.mean():.4f}  standard deviation {estimates.std():.4f}")
print("cosine sampling has no noise at all here: f cos / pdf = albedo for every sample")

# %% [markdown]
# With cosine-weighted directions the weight is `(albedo / pi) cos / (cos / pi) = albedo`
# for every sample: no noise at all, for free. The wrong pdf's estimates are as noisy as the
# right uniform ones, and twice as large.
#
# ## The two pictures
#
# `replace_materials` gives the scene the wrong material wherever it has a diffuse one. The
# light that reaches a wall straight from the lamp is still right (light sampling uses only
# `eval`), but every bounce after that doubles. Paths stop after 8 bounces: with the wrong
# pdf the weights grow at every bounce, so Russian roulette, which follows the path's
# throughput, would hardly ever end a path. (Both render in this process, `workers=1`: worker
# processes may not have this file's class.)

# %%
scene = ptlab.load_scene("cornell-box")
wrong = replace_materials(scene, lambda m: SpherePdf(m.albedo) if isinstance(m, Diffuse) else None)
options = dict(spp=args.spp, res=args.res, workers=1, max_depth=8)
right_image = ptlab.render(scene, **options)
wrong_image = ptlab.render(wrong, **options)
print(
    f"mean brightness: library {right_image.mean():.4f}, pdf off by 2 "
    f"{wrong_image.mean():.4f} ({wrong_image.mean() / right_image.mean():.2f}x)"
)
write_image(out / "diffuse.png", right_image)
write_image(out / "diffuse-wrong.png", wrong_image)
print(f"wrote {out / 'diffuse.png'} and {out / 'diffuse-wrong.png'}")
show_pictures(out)
