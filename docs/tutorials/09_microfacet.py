# %% [markdown]
# # Chapter 9 tutorial: GGX microfacet metals and their importance sampling
#
# A rough surface is a field of tiny mirrors, each with its own normal `h`; light goes from
# `wi` to `wo` off the facets whose normal is the half vector `normalize(wo + wi)`. Counting
# them (`D`, the distribution of normals), the ones hidden from either direction (`G`,
# Smith's masking-shadowing) and how much each mirror reflects (`F`, Fresnel) gives the
# Cook-Torrance BRDF, `D G2 F / (4 cos(theta_o) cos(theta_i))`. Chapter 9's exercise is
# those terms and a GGX metal that samples its own lobe (the chapter's page:
# `ptlab exercise docs 9`).
#
# This tutorial prints the checks' first principles, then renders the two metal spheres of
# `cornell-box-microfacet` three times at the same samples per pixel: with cosine hemisphere
# sampling, with the library's importance sampling (visible normals), and with the
# chapter's typical mistake, a pdf that forgets a Jacobian.

# %%
"""Chapter 9 tutorial: GGX microfacet metals and their importance sampling.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/09_microfacet.py   # microfacet-hemisphere.png, microfacet(-wrong).png
    python docs/tutorials/09_microfacet.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import math

import numpy as np

import ptlab
from ptlab.course.chapters.ch09_microfacet import metals_scene
from ptlab.course.renders import replace_materials
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.materials import Material, Microfacet
from ptlab.materials.microfacet import G1, D
from ptlab.sampling import to_world
from ptlab.scattering import reflect
from ptlab.vectors import dot, normalize, vec3

args, out = tutorial_options(__doc__, res=128, spp=32)

# %% [markdown]
# ## D and G1 at a glance
#
# GGX's `D` is a density of normals, normalised so that the facets' projected area is the
# surface's: the integral of `D(h) cos(theta_h)` over the hemisphere is 1, whatever the
# roughness `alpha`. At the normal `D = 1 / (pi alpha^2)`, a tall narrow peak for a smooth
# surface. `G1`, the share of facets a direction sees, is 1 at the normal and falls toward
# grazing angles, faster on a rougher surface.

# %%
mu = 1 - np.concatenate([[0.0], np.geomspace(1e-14, 1.0, 20001)])
for alpha in (0.04, 0.25, 1.0):
    total = np.trapezoid(D(mu, alpha) * mu * 2 * math.pi, 1 - mu)
    print(
        f"alpha {alpha:4}: integral of D cos over the hemisphere {total:.5f}, "
        f"D(n) = 1/(pi alpha^2) = {D(np.array([1.0]), alpha)[0]:9.3f}, "
        f"G1 at 0/60/85/89.9 degrees: "
        + " ".join(f"{G1(np.cos(np.radians([d])), alpha)[0]:.3f}" for d in (0, 60, 85, 89.9))
    )


# %% [markdown]
# ## The mistake: the density of h as the density of wi
#
# Walter et al. (2007, eqs. 35-36) sample the half vector `h` with density
# `D(h) cos(theta_h)` and reflect `wo` about it. But the pdf a path tracer divides by is the
# density of `wi`, and reflecting changes densities by the Jacobian `1 / (4 |wo . h|)`. This
# material samples that way and returns the density of `h`, Jacobian forgotten.


# %%
class HalfVectorPdf(Material):
    """The typical mistake: h drawn with density D(h) cos(theta_h) (Walter et al. 2007,
    eqs. 35-36) and wi = reflect(wo, h), but that density of h returned as the pdf of wi."""

    def __init__(self, metal: Microfacet):
        self.metal = metal
        self.alpha = metal.alpha

    def eval(self, wo, wi, n):
        return self.metal.eval(wo, wi, n)

    def sample(self, wo, n, u):
        tan2_theta = self.alpha**2 * u[:, 0] / (1 - u[:, 0])
        cos_theta = 1 / np.sqrt(1 + tan2_theta)
        sin_theta = np.sqrt(np.maximum(0, 1 - cos_theta * cos_theta))
        phi = 2 * math.pi * u[:, 1]
        h = to_world(vec3(sin_theta * np.cos(phi), sin_theta * np.sin(phi), cos_theta), n)
        return reflect(wo, h)

    def pdf(self, wo, wi, n):
        h = normalize(wo + wi)
        above = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return above * D(dot(h, n), self.alpha) * dot(h, n)  # / (4 |wo . h|) forgotten


# %% [markdown]
# ## Three pictures at the same samples per pixel
#
# The metals are seen from closer, as the chapter's checks see them. `replace_materials`
# swaps each metal for a variant: the same metal sampling the cosine hemisphere
# (`with_sampling("hemisphere")`), the library's own, and the mistake. (In this process,
# `workers=1`: worker processes may not have this file's class.) Hemisphere sampling is
# right but noisy on the smooth gold sphere: few random directions fall into its narrow
# lobe, which importance sampling aims at. The mistake's pdf is `4 |wo . h|` times too big
# near the normal, so the reflections come out too dark.

# %%
scene = metals_scene()
print(f"the metals: {', '.join(repr(m) for m in scene.materials if isinstance(m, Microfacet))}")
options = dict(spp=args.spp, res=args.res, workers=1)
pictures = {
    "microfacet-hemisphere.png": replace_materials(
        scene, lambda m: m.with_sampling("hemisphere") if isinstance(m, Microfacet) else None
    ),
    "microfacet.png": scene,
    "microfacet-wrong.png": replace_materials(
        scene, lambda m: HalfVectorPdf(m) if isinstance(m, Microfacet) else None
    ),
}
for name, variant in pictures.items():
    image = ptlab.render(variant, **options)
    write_image(out / name, image)
    print(f"wrote {out / name}: mean brightness {image.mean():.4f}")
print(
    "same spp: the hemisphere picture is noisier on the sharp gold sphere; the wrong one is "
    "darker in the reflections, where the pdf 4 |wo . h| times too big shrinks the weights"
)
show_pictures(out)
