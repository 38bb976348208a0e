# %% [markdown]
# # Chapter 10 tutorial: multiple importance sampling on Veach's scene
#
# A path tracer finds the light reaching a point in two ways: light sampling picks a point
# on a light and sends a shadow ray to it; BSDF sampling draws a direction from the material
# and sees whether it hits a light. Each is good where the other is bad: a small light seen
# in a rough surface is found by light sampling every time and by BSDF sampling almost
# never; a big light seen in a sharp highlight, the other way round. Multiple importance
# sampling (Veach and Guibas 1995) runs both and weighs each sample, so that every light
# path is counted once in all, mostly by the strategy that finds it more easily. Chapter
# 10's exercise is the weights: the balance and power heuristics (the chapter's page:
# `ptlab exercise docs 10`).
#
# This tutorial prints the two strategies' weights for a few pairs of densities, then
# renders `veach-mis` (four glossy plates, from smooth at the top to rough at the bottom,
# lit by four lights of equal power, small on the left, big on the right) with light
# sampling only, BSDF sampling only, MIS with the power heuristic (all the library's), and
# with the chapter's typical mistake: both strategies weighted 1, which counts light twice.

# %%
"""Chapter 10 tutorial: multiple importance sampling on Veach's scene.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/10_mis.py              # mis-nee.png, mis-bsdf.png, mis.png, mis-wrong.png
    python docs/tutorials/10_mis.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import numpy as np

import ptlab
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.integrators.path import mis_weight
from ptlab.rendering.pieces import PathPieces, Pieces

args, out = tutorial_options(__doc__, res=128, spp=32)

# %% [markdown]
# ## The weights
#
# `mis_weight(pdf, other)` is the weight of a sample drawn by a strategy with density
# `pdf`, where `other` is the density with which the other strategy would have drawn the
# same sample: `pdf / (pdf + other)` for the balance heuristic, `pdf^2 / (pdf^2 + other^2)`
# for the power heuristic, which trusts the better strategy more.

# %%
pdf_light = np.array([0.1, 1.0, 5.0, 400.0], dtype=np.float32)
pdf_bsdf = np.array([40.0, 1.0, 1.0, 2.0], dtype=np.float32)
print("  pdf_light  pdf_bsdf   power: w_light  w_bsdf   balance: w_light  w_bsdf")
for light, bsdf, *w in zip(
    pdf_light,
    pdf_bsdf,
    mis_weight(pdf_light, pdf_bsdf),
    mis_weight(pdf_bsdf, pdf_light),
    mis_weight(pdf_light, pdf_bsdf, "balance"),
    mis_weight(pdf_bsdf, pdf_light, "balance"),
    strict=True,
):
    print(f"  {light:9g} {bsdf:9g}   {w[0]:13.4f} {w[1]:7.4f}   {w[2]:15.4f} {w[3]:7.4f}")
print("each pair of weights adds up to 1: every light path is counted once in all")

# %% [markdown]
# ## Veach's scene, one strategy at a time
#
# `strategy="nee"` samples the lights only, `"bsdf"` the materials only, `"mis"` both,
# weighted by the power heuristic. Light sampling is noisy where a big light shows in a
# smooth plate (top right); BSDF sampling where a small light shows in a rough plate (bottom
# left); MIS is clean everywhere.

# %%
scene = ptlab.load_scene("veach-mis")
options = dict(spp=args.spp, res=args.res, seed=0)
for strategy, name in (("nee", "mis-nee.png"), ("bsdf", "mis-bsdf.png"), ("mis", "mis.png")):
    result = ptlab.render_result(scene, strategy=strategy, **options)
    write_image(out / name, result.image)
    print(
        f"wrote {out / name}: strategy {strategy!r}, {result.seconds:.1f} s, "
        f"mean brightness {result.image.mean():.4f}"
    )


# %% [markdown]
# ## The mistake: both strategies weighted 1
#
# The MIS weight is one of the path tracer's pieces, so a render in this process
# (`workers=1`: worker processes may not have this file's function) can be given a weight
# of its own. Weighted 1, every light path that both strategies can find is counted twice.


# %%
def weight_one(pdf, other, heuristic="power"):
    """The classic mistake: every sample of both strategies counted fully."""
    return np.ones_like(pdf)


# %%
weights_of_one = Pieces(path=PathPieces(mis_weight=weight_one))
image = ptlab.render(scene, strategy="mis", workers=1, **options, pieces=weights_of_one)
write_image(out / "mis-wrong.png", image)
print(
    f"wrote {out / 'mis-wrong.png'}: both strategies weighted 1, mean brightness "
    f"{image.mean():.4f} (too bright: double counting)"
)
show_pictures(out)
