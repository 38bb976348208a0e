"""Whitted-style ray tracing (GAMES101 Homework 5), run over a whole batch of rays at once.

Whitted's ray tracer (T. Whitted 1980, "An Improved Illumination Model for Shaded Display";
GAMES101 lecture 13) follows light only where it is easy to follow: along the single
directions in which mirrors reflect and glass reflects and refracts. Homework 5's
``castRay(ray, depth)``, per ray:

1. find the closest hit; a ray that sees a light adds its emission Le;
2. at a mirror: trace the reflected ray, times the mirror's reflectance R;
3. at glass: trace *both* the reflected and the refracted ray and add them, weighted by the
   Fresnel reflectance kr and by 1 - kr (total internal reflection: kr = 1, the reflected
   ray only);
4. at any other surface (diffuse, glossy): add the direct light, Le f_r cos(theta)
   cos(theta') / |x - x'|^2 / pdf_light if the shadow ray reaches the light, and stop. The
   light that reaches the surface after bouncing off other diffuse surfaces (indirect
   light) is missing: that is what the path tracer of Homework 7 adds
   (``ptlab.integrators.path``).

Rays stop after ``max_depth`` bounces (the homework's ``maxDepth = 5``); rays that escape
see the scene's sky (the homework's background colour), or black. As in the homework, the
sky lights nothing: the rays that could find its light, leaving diffuse surfaces, are the
ones Whitted does not follow, and light sampling leaves it out (``sample_sky``).

Two differences from the homework, so that Whitted and the path tracer render the same
scenes and agree wherever they both apply:

* the lights are sampled, one light and one point on it per ray, with a shadow ray (the path
  tracer's ``direct_light``): emissive triangles give soft shadows, with noise, where the
  homework's point lights give hard ones; point lights (``ptlab.lights.PointLights``) give
  hard shadows too, but one light is picked per sample where the homework adds them all,
  and their light falls off as 1 / r^2;
* surfaces shade with their material's own BSDF (``Material.eval``) instead of the Phong
  model, and refracted radiance carries the material's 1 / eta_rel^2 factor
  (``ptlab.materials.dielectric``).

Glass splits each ray in two where the path tracer picks one of the two at random with
probability kr: the weights below are the Dielectric's ``sample_weight`` averaged over that
choice, so for light that reaches the camera through mirrors and glass only, the expected
images are the same, and Whitted's has no noise. Any other delta material (``Mirror``)
continues along the one direction its ``sample_weight`` gives. Every ray that goes on
follows a mirror or glass, so every ray counts the emission it sees (the path tracer's
``sees_emission``), which is also why the lights are not black. A split doubles the glass
rows, so the rays of a glass pixel grow up to 2^max_depth; a batch grown too big is traced
in parts (``MAX_BATCH``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.integrators.path import PathPieces, PathSettings, add_emission, add_sky, sampled_lights
from ptlab.integrators.wavefront import Paths, SurfaceHit, leave_surface, recorder, surface_hit
from ptlab.materials.dielectric import Dielectric
from ptlab.materials.mirror import Mirror
from ptlab.samplers import BounceUniforms, Sampler
from ptlab.scattering import FresnelSplit
from ptlab.scene import Scene
from ptlab.vectors import concatenate_rows, take_rows

#: Direct light by light sampling only, and emission counted where the ray may see it: the
#: path tracer's ``"nee"`` rules (Whitted has no BSDF sampling to combine them with); the
#: sky is only seen, as the homework's background colour is.
LIGHT_SAMPLING = PathSettings(strategy="nee", sample_sky=False)

#: Glass doubles its rays at every bounce. A batch that has grown beyond this many rays is
#: traced in parts, so memory stays bounded whatever ``max_depth``; it is faster too, as
#: batches of about 2^18 rays are (docs/performance.md).
MAX_BATCH = 1 << 18


def trace_whitted(
    film: np.ndarray,
    scene: Scene,
    accel: Accelerator,
    paths: Paths,
    sampler: Sampler,
    settings: PathSettings,
    first_depth: int = 0,
) -> int:
    """Trace a batch of camera rays the Whitted way, adding their radiance into ``film``.

    Args:
        film: (P, 3) float64 sums of radiance per pixel, updated in place.
        paths: the camera rays, throughput 1 (or, from ``first_depth`` on, rays that left
            mirrors and glass).
        sampler: where the random numbers come from (the light samples; mirrors and glass
            need none), in the path tracer's layout (``ptlab.samplers.BounceUniforms``).
        settings: only ``max_depth`` and the pieces (``PathPieces``: reflect, refract,
            Fresnel, direct light) are used (no Russian roulette, no strategies).

    Returns:
        the number of rays traced (closest-hit and shadow rays).
    """
    rays = 0
    light_sampling = replace(LIGHT_SAMPLING, pieces=settings.pieces)
    for depth in range(first_depth, settings.max_depth + 1):
        if len(paths.pixel) > MAX_BATCH:  # grown by glass splits: trace it in parts
            return rays + sum(
                trace_whitted(film, scene, accel, part, sampler, settings, depth)
                for part in batches(paths, MAX_BATCH)
            )
        hits = accel.intersect(paths.origins, paths.dirs)
        rays += len(hits.prim)
        if scene.sky is not None:
            add_sky(film, scene, paths, hits, light_sampling)  # the rays that escape see it
        hit = surface_hit(scene, paths, hits)  # drops the rays that missed
        if len(hit.prim) == 0:
            break
        add_emission(film, scene, hit, light_sampling)  # camera rays and mirror/glass rays
        if depth == settings.max_depth:
            break
        u = BounceUniforms(sampler, hit.sample, depth)
        if sampled_lights(scene, light_sampling).any():  # diffuse and glossy: direct light only
            rays += settings.pieces.direct_light(film, scene, accel, hit, u.light(), light_sampling)
        if not hit.delta.any():  # no mirror or glass: every ray ends
            break
        paths = reflect_and_refract(hit, u.bsdf(), settings.pieces)  # glass: two rays for one
        if len(paths.pixel) == 0:
            break
    return rays


def reflect_and_refract(hit: SurfaceHit, u: np.ndarray, pieces: PathPieces | None = None) -> Paths:
    """The rays leaving the mirrors and glass among ``hit``; the other rows end.

    Glass rows become two rays each (``fresnel_split``); a mirror reflects (``pieces.reflect``)
    with the weight of its ``sample_weight``; any other delta material gives the one
    direction and weight of its ``sample_weight`` (u: (N, 2) uniforms for one that samples).
    """
    pieces = pieces or PathPieces()
    rows, wi, weight = [], [], []
    for group_rows, material in hit.materials:
        if not material.is_delta:
            continue
        index = np.arange(len(hit.prim)) if group_rows is None else group_rows
        wo, n, front = take_rows(hit.wo, index), take_rows(hit.n, index), hit.front.take(index)
        if isinstance(material, Dielectric):
            branches = fresnel_split(material, wo, n, front, pieces)
        elif isinstance(material, Mirror):
            branches = [(pieces.reflect(wo, n), material.reflectance_at(wo, n))]
        else:
            branches = [material.sample_weight(wo, n, take_rows(u, index), front)]
        for branch_wi, branch_weight in branches:
            rows.append(index)
            wi.append(branch_wi)
            weight.append(branch_weight)
    return next_rays(hit, np.concatenate(rows), concatenate_rows(wi), concatenate_rows(weight))


def fresnel_split(
    glass: Dielectric, wo: np.ndarray, n: np.ndarray, front: np.ndarray, pieces: PathPieces | None = None
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Homework 5's ``REFLECTION_AND_REFRACTION`` case: both rays, each with its weight.

    Args:
        glass: the glass of these rows (per-row ``eta`` and ``transmittance``).
        wo: (N, 3) unit directions back along the rays.
        n: (N, 3) unit normals on the side of ``wo`` (``SurfaceHit.n``).
        front: (N,) bool, True where ``wo`` is outside the glass.
        pieces: the reflect, refract and Fresnel functions (default: the library's).

    Returns:
        [(reflected wi, kr), (refracted wi, (1 - kr) transmittance / eta_rel^2)], (N, 3) each.
        Under total internal reflection kr = 1 and the refracted weight is 0.
    """
    pieces = pieces or PathPieces()
    reflect, refract, fresnel = pieces.reflect, pieces.refract, pieces.fresnel_dielectric
    split = FresnelSplit.at(wo, n, glass.eta, front, reflect=reflect, refract=refract, fresnel=fresnel)
    return split.both(glass.transmittance)


def next_rays(hit: SurfaceHit, rows: np.ndarray, wi: np.ndarray, weight: np.ndarray) -> Paths:
    """New rays from the hits ``rows`` (repeats allowed) along ``wi``, throughput times ``weight``.

    Rays whose throughput is 0 (a refraction under total internal reflection, a black
    mirror) are dropped; the others start off the surface on the side ``wi`` goes to, as
    the path tracer's do (``scatter``), by the geometric normal.
    """
    throughput = take_rows(hit.throughput, rows) * weight
    if (rec := recorder()) is not None:
        rec.split(hit, rows, wi, weight, throughput)
    go_on = np.flatnonzero((throughput > 0).any(axis=1))
    rows, wi, throughput = rows.take(go_on), take_rows(wi, go_on), take_rows(throughput, go_on)
    origins = leave_surface(take_rows(hit.p, rows), take_rows(hit.ng, rows), hit.offset.take(rows), wi)
    return Paths(
        origins=origins,
        dirs=wi,
        throughput=throughput,
        pixel=hit.pixel.take(rows),
        sees_emission=np.ones(len(rows), dtype=bool),
        sample=hit.sample.take(rows),
        depth=_next_depth(hit.depth, rows),
    )


def _next_depth(depth: int | np.ndarray, rows: np.ndarray) -> int | np.ndarray:
    """The depth of rays leaving the hits ``rows`` of a batch at ``depth`` (one, or per row)."""
    return (depth.take(rows) if isinstance(depth, np.ndarray) else depth) + 1


def batches(paths: Paths, size: int):
    """``paths`` in consecutive parts of at most ``size`` rays (views, not copies)."""
    for start in range(0, len(paths.pixel), size):
        rows = slice(start, start + size)
        yield Paths(
            origins=paths.origins[rows],
            dirs=paths.dirs[rows],
            throughput=paths.throughput[rows],
            pixel=paths.pixel[rows],
            sees_emission=paths.sees_emission[rows],
            sample=paths.sample[rows],
            depth=paths.depth[rows] if isinstance(paths.depth, np.ndarray) else paths.depth,
        )
