"""Chapter 7: path tracing, the homework's castRay.

The chapter's page: ``ptlab exercise docs 7`` (中文: ``--zh``).

Write the path tracer of GAMES101 Homework 7 for a whole batch of paths at once: the
direct light by sampling the lights with a shadow ray, Russian roulette, the indirect
bounce, and the loop that puts them together with the light that camera rays see. The
renderer then runs your ``trace_paths`` in place of its own. Check your work with

    ptlab exercise check 7 07_path_tracing.py

The homework's ``castRay`` follows one path by recursion. Here every step is done for all
live paths at once, as whole-array NumPy operations ("wavefront"): ``hit.p`` holds the hit
points of thousands of paths, and so on. Never loop over paths in Python (a loop would be
thousands of times slower, and the checks have time limits); Python loops over bounces only.

The library gives you (``ptlab.integrators.wavefront``; read it, and ``ptlab.integrators.path``,
whose answer this is):

* ``Paths``: the rays of the live paths (origins, dirs, throughput, pixel, sees_emission,
  sample: each path's key to its random numbers);
* ``surface_hit(scene, paths, hits)``: a ``SurfaceHit`` for the paths that hit something
  (the others are dropped): hit point ``p``, normal ``n`` turned toward ``wo``, ``wo``
  (back along the ray), ``front`` (the ray hit the triangle's front face), ``offset``,
  ``throughput``, ``pixel``, ``sees_emission``, ``sample``, ``prim`` (the triangle), ``delta``;
* ``shade(hit, "eval" | "pdf" | "sample", *arrays)``: each hit's own material's method;
* ``add_to_film(film, pixel, radiance)``: film[pixel[k]] += radiance[k] for every k;
* ``scene.area_lights.sample(u)``: points on the lights (``ptlab.lights.ShapeSample``);
* ``BounceUniforms(sampler, hit.sample, depth)``: the random numbers of one bounce
  (``ptlab.samplers``: ``.light()``, ``.roulette()``, ``.bsdf()``);
* ``accel.intersect(origins, dirs)`` and ``accel.occluded(origins, dirs, tmax)``.

Directions are unit vectors pointing *away* from the surface: ``wo`` toward the viewer,
``wi`` toward the light (the homework's ``ray.direction`` is our ``-wo``). Arrays of
vectors are (N, 3), float32 in the renderer.
"""

import numpy as np

from ptlab.integrators.wavefront import SHADOW_EPSILON, Paths, add_to_film, shade, surface_hit
from ptlab.samplers import BounceUniforms
from ptlab.vectors import dot, take_rows


def direct_light(film, scene, accel, hit, u):
    """Direct light at every hit by sampling one point on the lights (next-event estimation).

    For each row: pick a point x' on the lights with ``scene.area_lights.sample(u)``, and if
    the shadow ray from the hit point x to x' is not blocked, add to the path's pixel

        throughput * Le * f_r(wo, wi) * cos(theta) * cos(theta') / |x' - x|^2 / pdf_area

    where wi = (x' - x) / |x' - x|, cos(theta) = n . wi at the hit, cos(theta') = -n' . wi at
    the light (GAMES101 lecture 16, "sampling the light"; pbrt-v4 section 13.2).

    Args:
        film: (rows, 3) float64 sums, a row per pixel (or, in a render, per path); add to it
            with ``add_to_film(film, hit.pixel, ...)``: ``hit.pixel`` are its rows.
        scene: the ``ptlab.scene.Scene`` (``scene.area_lights`` samples the lights).
        accel: the ray-query structure (``accel.occluded`` traces shadow rays).
        hit: the ``SurfaceHit`` of N paths.
        u: (N, 2) uniforms in [0, 1) for the light samples (pass them to
            ``scene.area_lights.sample`` as they are).

    Returns:
        the number of shadow rays traced (an int).

    Hints:
        * ``light = scene.area_lights.sample(u)`` gives ``light.points``, ``light.normals``,
          ``light.radiance`` (Le), ``light.pdf_area`` ((N,)) and ``light.offset``, all (N, 3)
          or (N,) arrays, one row per hit.
        * f_r is ``shade(hit, "eval", hit.wo, wi, hit.n)``: (N, 3).
        * Clamp both cosines at 0: points that do not face each other exchange no light.
        * The shadow ray: ``accel.occluded(origin, target - origin, 1 - SHADOW_EPSILON)`` is
          True where something lies between. Start it *off* the surface, at
          ``hit.p + hit.offset[:, None] * hit.n``, and aim it at the light point moved off
          the light, ``light.points + light.offset * light.normals`` (``light.target``
          holds it): a ray that starts exactly on its surface hits that surface again
          ("shadow acne") and one that ends exactly on the light hits the light.
    """
    raise NotImplementedError("direct_light")


def russian_roulette(throughput, p_rr, u):
    """Russian roulette: each path goes on with probability p_rr.

    The survivors' throughput is divided by p_rr, so that the expected value stays the same
    (GAMES101 lecture 16: "with probability P shoot a ray and return L / P, otherwise 0").

    Args:
        throughput: (N, 3) float32 throughput of each path.
        p_rr: the survival probability, a float in (0, 1] (the homework's 0.8).
        u: (N,) uniforms in [0, 1), one per path.

    Returns:
        survive: (N,) bool, True for the paths that go on (decide with ``u``, not with random
            numbers of your own, so that the same seed gives the same image);
        throughput: (N, 3) float32, divided by p_rr (at least in the surviving rows).
    """
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    """The indirect bounce: the next ray of every surviving path, sampled from its material.

    The homework's way: wi = sample(wo, n), and the throughput is multiplied by
    f_r(wo, wi) cos(theta_i) / pdf(wo, wi), the Monte Carlo weight of that direction.

    Args:
        scene: the scene (not needed by the homework's way, there for other ways).
        hit: the ``SurfaceHit`` of N paths; ``hit.throughput`` already has the roulette's 1 / p_rr.
        u: (N, 2) uniforms in [0, 1) for sampling the directions.
        survive: (N,) bool, the paths that survived the roulette.

    Returns:
        ``Paths(origins, dirs, throughput, pixel, sees_emission, sample)`` of the surviving
        paths only: origins (M, 3) float32, dirs (M, 3) float32 unit, throughput (M, 3)
        float32, pixel (M,) and sample (M,) from ``hit.pixel`` and ``hit.sample``,
        sees_emission (M,) bool = ``hit.delta`` of those rows
        (the next ray counts the emission it hits only after a mirror or glass, whose light
        ``direct_light`` cannot find; after a diffuse bounce ``direct_light`` has counted it).

    Hints:
        * ``shade(hit, "sample", hit.wo, hit.n, u)``, ``shade(hit, "eval", hit.wo, wi, hit.n)``
          and ``shade(hit, "pdf", hit.wo, wi, hit.n)`` call each hit's material.
        * The pdf can be 0 (a material that could not sample a direction returns one with
          pdf 0, and f_r 0 too): 0 / 0 is NaN. Where the pdf is 0 (or tiny) the weight is 0.
        * Start the new ray off the surface on the side it leaves to:
          ``hit.p + side[:, None] * hit.n`` with side = +hit.offset where wi . n >= 0, else
          -hit.offset.
        * ``rows = np.flatnonzero(survive)`` and ``take_rows(a, rows)`` (or ``a[rows]``)
          keep the surviving rows.
    """
    raise NotImplementedError("scatter")


def trace_paths(film, scene, accel, paths, sampler, settings):
    """Trace a batch of camera paths to the end, adding their radiance into ``film``.

    The homework's castRay for every path at once. For depth = 0, 1, ..., settings.max_depth:

    1. ``hits = accel.intersect(paths.origins, paths.dirs)``; ``hit = surface_hit(scene,
       paths, hits)`` (drops the paths that missed); stop when none is left;
    2. the emission the rays see: add throughput * Le of the hit triangle
       (``take_rows(scene.emission, hit.prim)``) where ``hit.sees_emission`` (camera rays,
       and rays after a mirror) and ``hit.front`` (lights emit from their front face).
       Forget it and the light is black;
    3. stop at depth == settings.max_depth (max_depth 0: emission only);
    4. ``u = BounceUniforms(sampler, hit.sample, depth)``: the random numbers of this
       bounce, one set per use: ``u.light()`` for ``direct_light``, ``u.roulette()`` for
       ``russian_roulette`` (with ``settings.rr``, a float here), ``u.bsdf()`` for
       ``scatter``;
    5. direct light, roulette (put the new throughput back into ``hit.throughput``), then
       ``paths = scatter(...)``; stop when no path is left.

    Args:
        film: (P, 3) float64 sums of radiance per pixel, updated in place.
        scene, accel: the scene and its ray-query structure.
        paths: the camera rays (``Paths``), throughput 1, sees_emission True.
        sampler: the render's sampler (``ptlab.samplers``): each path's numbers depend on
            its pixel, its sample number and the bounce only.
        settings: ``ptlab.integrators.path.PathSettings``: ``max_depth`` and ``rr``.

    Returns:
        the number of rays traced (closest-hit rays plus shadow rays), an int.

    Hint: with ``BounceUniforms`` each path gets the library's random numbers, so your image
    is the library's, sample for sample (the checks do not need that, but it makes comparing
    easy).
    """
    raise NotImplementedError("trace_paths")
