"""Debug views: what the camera rays hit, one picture per question (pbrt's "aov" images).

* ``normals``: the shading normal facing the camera (smooth where a mesh has vertex normals,
  ``SurfaceHit.n``), mapped from [-1, 1] to [0, 1] per axis (x red, y green, z blue), the
  usual false-colour picture of geometry;
* ``albedo``: each surface's directional albedo toward the camera, the fraction of light
  it reflects: the mean of the material's bounce weight f cos / pdf over samples, so it
  works for any material without asking it for a colour;
* ``depth``: the distance from the eye to the hit (0 where the ray escapes).

Each camera sample adds its value to the film, so the views are antialiased like renders.
The views are registered, under their functions' names, in ``ptlab.integrators``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.integrators.path import PathSettings
from ptlab.integrators.wavefront import Paths, SurfaceHit, add_to_film, surface_hit
from ptlab.samplers import BounceUniforms, Sampler
from ptlab.scene import Scene


def normals(hit: SurfaceHit, sampler: Sampler) -> np.ndarray:
    """(N, 3) the shading normal facing the camera, each axis from [-1, 1] to [0, 1]."""
    return (hit.n + 1.0) * 0.5


def albedo(hit: SurfaceHit, sampler: Sampler) -> np.ndarray:
    """(N, 3) one sample of the directional albedo: the bounce weight f cos / pdf."""
    u = BounceUniforms(sampler, hit.sample, 0).bsdf()
    weight = hit.bsdf.sample(u).weight
    return weight


def depth(hit: SurfaceHit, sampler: Sampler) -> np.ndarray:
    """(N, 3) the distance from the eye to the hit, in every channel."""
    return np.repeat(hit.t[:, None], 3, axis=1)


def trace_debug(
    film: np.ndarray,
    scene: Scene,
    accel: Accelerator,
    paths: Paths,
    sampler: Sampler,
    settings: PathSettings,
    view: Callable[[SurfaceHit, Sampler], np.ndarray],
) -> int:
    """Add one ``view`` value per camera ray into ``film``; return the rays traced.
    (``settings``, which no view needs, keeps the call the same as every integrator's.)"""
    hits = accel.intersect(paths.origins, paths.dirs)
    hit = surface_hit(scene, paths, hits)
    if len(hit.prim) == 0:
        return len(hits.prim)
    add_to_film(film, hit.pixel, view(hit, sampler))
    return len(hits.prim)
