"""The integrators: what the radiance along a camera ray is, each registered by its name.

``INTEGRATORS`` maps the names that ``ptlab.render(integrator=...)`` and ``ptlab render
--integrator`` take to what runs them (Nori's plugins, registered by name):

* ``path``: the path tracer of Homework 7 (``path.py``): light sampling, BSDF sampling, or
  both with multiple importance sampling;
* ``whitted``: Homework 5's Whitted ray tracer (``whitted.py``): mirrors, glass and direct
  light, no diffuse interreflection;
* ``normals``, ``albedo``, ``depth``: debug views of what the camera rays hit (``debug.py``).

Every integrator is called alike, ``trace(film, scene, accel, paths, sampler, settings)``:
it adds the radiance of the camera rays ``paths`` into ``film``, (pixels, 3) float64, and
returns the number of rays it traced. One that ``refills`` also takes ``more``, where it
finds new camera paths as old ones end (``ptlab.integrators.path.trace_paths``), and is
called once for a whole group of jobs; the others are called a job at a time.
``ptlab.rendering.jobs`` looks them up here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from ptlab.integrators.debug import albedo, depth, normals, trace_debug
from ptlab.integrators.path import PathSettings, trace_paths
from ptlab.integrators.whitted import trace_whitted


@dataclass(frozen=True)
class Integrator:
    """An integrator of the registry.

    Attributes:
        trace: the function that renders with it (the module docstring's signature).
        max_depth: the most bounces of a path, unless the scene file or the user says.
        refills: ``trace`` takes ``more`` (the module docstring).
    """

    trace: Callable[..., int]
    max_depth: int
    refills: bool = False


#: Every integrator, by name.
INTEGRATORS: dict[str, Integrator] = {
    "path": Integrator(trace_paths, max_depth=PathSettings.max_depth, refills=True),
    # The homework's maxDepth = 5: a Whitted ray bounces only off mirrors and glass.
    "whitted": Integrator(trace_whitted, max_depth=5),
    # (A debug view stops at the first hit: its max depth is only recorded with the image.)
    **{
        view.__name__: Integrator(partial(trace_debug, view=view), max_depth=PathSettings.max_depth)
        for view in (normals, albedo, depth)
    },
}
