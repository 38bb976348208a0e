# %% [markdown]
# # Chapter 7 tutorial: the path tracer, and its three classic mistakes
#
# The homework's `castRay` estimates the light a camera ray sees in two parts: the light
# that comes straight from the lights, found by sampling a point on a light and tracing a
# shadow ray to it (light sampling), and the light from everything else, found by following
# one random direction, with Russian roulette deciding when to stop. ptlab runs it as a
# wavefront: each step is done for every live path at once, each path carrying its
# throughput, the product of `f_r cos / pdf / P_RR` so far. Chapter 7's exercise is that
# loop and its steps (the chapter's page: `ptlab exercise docs 7`).
#
# This tutorial renders the white furnace and the Cornell box with the library's path
# tracer, then with each mistake of the homework's `castRay` put in its place:
#
# * **the black light**: the emission that camera rays see is never added;
# * **double counting**: emission added on every hit, although light sampling already
#   counted it;
# * **no shadow-ray epsilon**: shadow rays start exactly on their surface (shadow acne).

# %%
"""Chapter 7 tutorial: the path tracer, and its three classic mistakes.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/07_path_tracing.py             # writes path-tracing*.png
    python docs/tutorials/07_path_tracing.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import ptlab
from ptlab.course.chapters.ch07_path_tracing import furnace_scene
from ptlab.course.tutorial import show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.integrators.path import scatter, trace_paths
from ptlab.integrators.wavefront import SHADOW_EPSILON, add_to_film, shade
from ptlab.rendering.pieces import PathPieces, Pieces
from ptlab.vectors import dot

args, out = tutorial_options(__doc__, res=128, spp=64)


# %% [markdown]
# ## The black light
#
# `shade(p, wo)` returns reflected light only: a camera ray that hits the lamp sees what
# the lamp *reflects*, unless the loop adds the emission of the first hit. The library's
# loop adds a ray's hit emission only where `sees_emission` says so (camera rays, and rays
# after a mirror or glass); here none do.


# %%
def loop_with_black_light(film, scene, accel, paths, sampler, settings) -> int:
    """The black light: camera rays add nothing for the light they see. The library's path
    loop with light sampling (the homework's) adds a ray's hit emission only where
    ``sees_emission`` says so (camera rays, and rays after a mirror or glass): here none do."""
    blind = replace(paths, sees_emission=np.zeros_like(paths.sees_emission))
    return trace_paths(film, scene, accel, blind, sampler, settings)


# %% [markdown]
# ## Double counting
#
# The homework's indirect ray counts the light it hits only "if q does not emit": light
# sampling at the bounce has already counted all the light that comes straight from the
# lights. The mistake lets the rays after a diffuse bounce see emission too.


# %%
def scatter_seeing_emission(scene, hit, u, survive, with_pdf=False):
    """Double counting: the rays after a diffuse bounce add the emission they hit, although
    light sampling at the bounce has already counted that light."""
    paths = scatter(scene, hit, u, survive, with_pdf)
    paths.sees_emission[:] = True
    return paths


# %% [markdown]
# ## No shadow-ray epsilon
#
# Light sampling, written out: pick a point on a light (in proportion to its power), then
# the direction and distance to it, the two cosines, and a shadow ray that must reach the
# light unblocked. The area measure turns into solid angle by `cos(theta') / |x' - p|^2`.
# The library starts each shadow ray a little off its surface; this one starts it exactly
# on the surface, and in float32 most such rays hit the surface they start on.


# %%
def direct_light_without_epsilon(film, scene, accel, hit, u, settings) -> int:
    """Light sampling whose shadow rays start exactly on the surface (no offset): in float32
    most of them hit the surface they start on, "shadow acne"."""
    light = scene.area_lights.sample(u)
    to_light = light.points - hit.p
    dist2 = dot(to_light, to_light)
    wi = to_light / np.sqrt(dist2)[:, None]
    cosines = np.maximum(dot(hit.n, wi), 0) * np.maximum(-dot(light.normals, wi), 0)
    visible = ~accel.occluded(hit.p, to_light, 1 - SHADOW_EPSILON)
    f = shade(hit, "eval", hit.wo, wi, hit.n)
    scale = visible * cosines / (dist2 * light.pdf_area)
    add_to_film(film, hit.pixel, hit.throughput * f * light.radiance * scale[:, None])
    return len(wi)


# %% [markdown]
# ## Each mistake as the pieces of a render
#
# A render is made of pieces, the library's unless told otherwise: the black light replaces
# the whole path loop, the other two one step of the library's. The renders run in this
# process (`workers=1`): the mistakes are this file's functions, which worker processes may
# not have.

# %%
#: Each mistake as the pieces of a render: the path loop, or one step of the library's.
MISTAKES = {
    "black light": Pieces(trace_paths=loop_with_black_light),
    "double counting": Pieces(path=PathPieces(scatter=scatter_seeing_emission)),
    "no shadow epsilon": Pieces(path=PathPieces(direct_light=direct_light_without_epsilon)),
}


def render(scene, mistake: str | None, **options) -> np.ndarray:
    """The library's render, or with one mistake among its pieces (in this process,
    ``workers=1``: the mistakes are this script's functions, which worker processes may
    not have)."""
    return ptlab.render(scene, workers=1, **options, pieces=MISTAKES.get(mistake))


# %% [markdown]
# ## The white furnace
#
# A closed sphere whose inside glows `Le = 0.3` and reflects albedo `a = 0.5` everywhere:
# whatever a path hits, it sees `Le` plus `a` times the same radiance again, so every pixel
# is `Le (1 + a + a^2 + ...) = Le / (1 - a) = 0.6`. Any light lost or counted twice shows at
# once.

# %%
furnace = furnace_scene()
print("The white furnace: Le = 0.3, albedo 0.5, so Le / (1 - albedo) = 0.6 everywhere")
for mistake in (None, *MISTAKES):
    image = render(furnace, mistake, spp=8, res=16, rr=0.8, seed=1)
    print(f"  {mistake or 'library':18} mean {image[..., 0].mean():.4f}")

# %% [markdown]
# ## The Cornell box
#
# With the homework's roulette (`rr=0.8`). The black light leaves the lamp dark but the room
# lit, since light sampling still finds the lamp; double counting makes the room too bright
# and speckled, every diffuse bounce that happens to hit the lamp adding its emission again;
# without the epsilon, most points look shadowed.

# %%
cornell = ptlab.load_scene("cornell-box")
light = cornell.materials[cornell.material_names.index("light")].emission
print(
    f"The Cornell box, {args.res} x {args.res}, {args.spp} spp, rr 0.8 (the light's Le is "
    f"{np.round(light, 1)}):"
)
names = {
    None: "path-tracing.png",
    "black light": "path-tracing-black-light.png",
    "double counting": "path-tracing-double-counting.png",
    "no shadow epsilon": "path-tracing-no-epsilon.png",
}
right = None
for mistake, name in names.items():
    image = render(cornell, mistake, spp=args.spp, res=args.res, rr=0.8, seed=0)
    right = image if mistake is None else right
    print(
        f"  {mistake or 'library':18} brightest pixel {image.max():7.2f}, mean "
        f"{image.mean():.4f} ({image.mean() / right.mean():.2f}x the library's)"
    )
    write_image(out / name, image)
print(f"wrote {', '.join(str(out / name) for name in names.values())}")
show_pictures(out)
