# %%
"""Chapter 9 tutorial: GGX microfacet metals and their importance sampling.

Prints the checks' first principles (D is normalised, G1 is 1 at the normal and falls at
grazing angles), then renders the two metal spheres of ``cornell-box-microfacet`` (seen from
closer, as the chapter's checks see them) three times at the same samples per pixel: with
cosine hemisphere sampling, with the library's importance sampling (visible normals), and
with the chapter's typical mistake, Walter's sampling of h whose pdf forgets the Jacobian
1 / (4 |wo . h|) of the reflection.

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


# %%
def main() -> None:
    args, out = tutorial_options(__doc__, res=128, spp=32)

    mu = 1 - np.concatenate([[0.0], np.geomspace(1e-14, 1.0, 20001)])
    for alpha in (0.04, 0.25, 1.0):
        total = np.trapezoid(D(mu, alpha) * mu * 2 * math.pi, 1 - mu)
        print(
            f"alpha {alpha:4}: integral of D cos over the hemisphere {total:.5f}, "
            f"D(n) = 1/(pi alpha^2) = {D(np.array([1.0]), alpha)[0]:9.3f}, "
            f"G1 at 0/60/85/89.9 degrees: "
            + " ".join(f"{G1(np.cos(np.radians([d])), alpha)[0]:.3f}" for d in (0, 60, 85, 89.9))
        )

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


# %%
if __name__ == "__main__":
    main()
