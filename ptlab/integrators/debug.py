"""Debug views: what the camera rays hit, one picture per question (pbrt's "aov" images).

* ``normals``: the surface normal facing the camera, mapped from [-1, 1] to [0, 1] per
  axis (x red, y green, z blue), the usual false-colour picture of geometry;
* ``albedo``: each surface's directional albedo toward the camera, the fraction of light
  it reflects: the mean of the material's bounce weight f cos / pdf over samples, so it
  works for any material without asking it for a colour;
* ``depth``: the distance from the eye to the hit (0 where the ray escapes).

Each camera sample adds its value to the film, so the views are antialiased like renders.
"""

from __future__ import annotations

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.integrators.path import Paths, add_to_film, shade, surface_hit
from ptlab.samplers import BounceUniforms, Sampler
from ptlab.scene import Scene

VIEWS = ("normals", "albedo", "depth")


def trace_debug(film: np.ndarray, scene: Scene, accel: Accelerator, paths: Paths,
                sampler: Sampler, view: str) -> int:
    """Add one debug value per camera ray into ``film``; return the rays traced."""
    hits = accel.intersect(paths.origins, paths.dirs)
    hit = surface_hit(scene, paths, hits)
    if len(hit.prim) == 0:
        return len(hits.prim)
    if view == "normals":
        value = (hit.n + 1.0) * 0.5
    elif view == "depth":
        value = np.repeat(hit.t[:, None], 3, axis=1)
    else:
        u = BounceUniforms(sampler, hit.sample, 0).bsdf()
        _, value = shade(hit, "sample_weight", hit.wo, hit.n, u, hit.front)
    add_to_film(film, hit.pixel, value)
    return len(hits.prim)
