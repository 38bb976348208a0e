# %% [markdown]
# # Chapter 3 tutorial: Whitted-style ray tracing with a mirror and a glass sphere
#
# Whitted's ray tracer follows light only along the directions that are easy to follow: at a
# diffuse surface a camera ray stops and adds the light that a shadow ray finds unblocked; at
# a mirror it goes on along the mirror direction; at glass it splits in two, a reflected ray
# weighted by the Fresnel reflectance `F` and a refracted ray weighted by `(1 - F) / eta^2`.
# Chapter 3's exercise is the three laws of a smooth surface that decide those directions
# and weights: `reflect`, `refract` and `fresnel` (the chapter's page: `ptlab exercise docs 3`).
#
# This tutorial prints the laws at a few angles, renders the Cornell box's walls with a
# mirror sphere and a glass sphere with the Whitted tracer of Homework 5, then again with
# the chapter's typical mistake, the index of refraction the wrong way up; last, Homework
# 5's own scene, with the Whitted tracer beside the path tracer.

# %%
"""Chapter 3 tutorial: Whitted-style ray tracing with a mirror and a glass sphere.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/03_whitted.py      # writes whitted.png, whitted-wrong.png, games101-hw5.png
    python docs/tutorials/03_whitted.py --res 64 --spp 1 --out /tmp/t
"""

from __future__ import annotations

import math

import numpy as np

import ptlab
from ptlab.course.chapters.ch03_whitted import spheres_scene, whitted_image
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.scattering import fresnel_dielectric, reflect, refract

args, out = tutorial_options(__doc__, res=160, spp=8)

# %% [markdown]
# ## The laws at a few angles
#
# Every direction points *away* from the surface: `wo` back along the incoming ray, the
# reflected and refracted directions away on either side. `eta` is the *relative* index
# `eta_t / eta_i`: 1.5 entering glass from air, `1 / 1.5` leaving it. Reflection flips the
# part of `wo` across the normal, `reflect(wo, n) = 2 (wo . n) n - wo`; refraction follows
# Snell's law, `sin(theta_t) = sin(theta_i) / eta`; the Fresnel reflectance `F` is the share
# of the light that the surface reflects.

# %%
n = np.array([[0.0, 1.0, 0.0]])
print("Rays arriving at a surface with normal n = +y (wo points back along each ray, away from the surface):")
for degrees, eta, where in [(45, 1.5, "entering glass"), (30, 1 / 1.5, "leaving glass")]:
    theta = math.radians(degrees)
    wo = np.array([[math.sin(theta), math.cos(theta), 0.0]])
    wt = refract(wo, n, eta)[0]
    print(
        f"  {where:14} at {degrees} degrees: wo {np.round(wo[0], 4)}, reflect "
        f"{np.round(reflect(wo, n)[0], 4)}, refract (eta {eta:.3f}) {np.round(wt, 4)}: "
        f"theta_t {math.degrees(math.acos(-wt[1])):.2f} degrees, F = "
        f"{fresnel_dielectric(np.array([wo[0, 1]]), eta)[0]:.4f}"
    )

# %% [markdown]
# `F` is 4% at normal incidence, `((eta - 1) / (eta + 1))^2` either way through the glass,
# and rises to 1 at grazing incidence. Leaving glass, beyond the critical angle
# `asin(1 / 1.5)`, there is no refracted ray at all: total internal reflection, `F = 1`.

# %%
print("The Fresnel reflectance of glass (eta 1.5) from normal to grazing incidence:")
degrees = np.array([0, 30, 45, 60, 75, 85, 89.9])
for eta, where in [(1.5, "entering"), (1 / 1.5, "leaving")]:
    F = fresnel_dielectric(np.cos(np.radians(degrees)), eta)
    print(f"  {where:9} " + "  ".join(f"{d:4g} deg {f:.3f}" for d, f in zip(degrees, F, strict=True)))
print(
    f"  normal incidence: ((eta - 1) / (eta + 1))^2 = {(0.5 / 2.5) ** 2:.3f}; leaving glass, "
    f"everything is reflected beyond the critical angle asin(1 / 1.5) = "
    f"{math.degrees(math.asin(1 / 1.5)):.1f} degrees"
)


# %% [markdown]
# ## The mistake: eta the wrong way up
#
# The homework's `refract` works with `etai / etat`, the inverse of ptlab's `eta`. Carried
# over, it makes entering the glass look like leaving a denser medium: glass bends light
# the wrong way, and reflects most of it totally on the way *in*.


# %%
def refract_inverted(wo, n, eta):
    """The typical mistake: eta used the wrong way up."""
    return refract(wo, n, 1 / np.asarray(eta, dtype=wo.dtype))


def fresnel_inverted(cos_theta_i, eta):
    return fresnel_dielectric(cos_theta_i, 1 / np.asarray(eta, dtype=np.result_type(cos_theta_i)))


# %% [markdown]
# ## The two pictures
#
# `whitted_image` renders a scene with the Whitted tracer in this process, with the given
# functions in place of the library's. The tracer spends no random numbers on mirrors and
# glass, so with the same seed the two pictures differ only where the mistake matters: in
# the glass sphere, and in its image in the mirror sphere.

# %%
scene = spheres_scene()
options = dict(spp=args.spp, res=args.res, seed=0)
right = whitted_image(scene, **options)
wrong = whitted_image(scene, refract=refract_inverted, fresnel=fresnel_inverted, **options)
differ = ~np.isclose(right, wrong, rtol=1e-3, atol=1e-4).all(axis=2)
print(
    f"Whitted render, {args.res} x {args.res}, {args.spp} spp: with eta the wrong way up "
    f"{differ.mean():.0%} of the pixels change (the glass sphere, and its image in the mirror)"
)
write_image(out / "whitted.png", right)
write_image(out / "whitted-wrong.png", wrong)
print(f"wrote {out / 'whitted.png'} and {out / 'whitted-wrong.png'}")

# %% [markdown]
# ## Homework 5's scene
#
# `games101-hw5` is the homework's scene at its 4:3 shape: a checkerboard floor, a glossy
# and a glass sphere, two point lights and a sky. The Whitted tracer (`integrator="whitted"`)
# gives the homework's picture: hard shadows, black where no point light reaches, the sky
# only seen. The path tracer (`strategy="mis"`) renders the same scene with all its light,
# the sky's too. (Both render in this process, `workers=1`, like those above.)

# %%
homework = dict(res=(args.res * 4 // 3, args.res), seed=0, workers=1)
whitted = ptlab.render("games101-hw5", spp=args.spp, integrator="whitted", **homework)
path = ptlab.render("games101-hw5", spp=4 * args.spp, strategy="mis", **homework)
dark = whitted.max(axis=2) < 0.02
lit_by_sky = f"{path[dark].mean():.3f}" if dark.any() else "-"
print(
    f"games101-hw5, Whitted: {dark.mean():.1%} of the pixels black (no point light reaches "
    f"them: the shadows, the big sphere's far side), as in the homework; the path tracer "
    f"lights them with the sky (mean {lit_by_sky} there)"
)
write_image(out / "games101-hw5.png", np.concatenate([whitted, path], axis=1))
print(f"wrote {out / 'games101-hw5.png'}: Whitted (left) and path tracing with MIS (right)")
show_pictures(out)
