"""A typical wrong chapter-7 answer: double counting. The loop adds the emission of every
surface a path hits, after diffuse bounces too, while direct_light has already counted the
light that reaches each hit point from the lights: light that arrives in one bounce is
counted twice, and the image is too bright. (The fix: only camera rays, and rays after a
mirror or glass, add the emission they see: ``hit.sees_emission``.)"""

import numpy as np

from ptlab.integrators import path
from ptlab.integrators.path import PathSettings, add_to_film, surface_hit
from ptlab.integrators.path import direct_light as library_direct_light
from ptlab.samplers import BounceUniforms
from ptlab.vectors import take_rows

EXPECTED_FAILURES = ("white furnace", "Cornell box")


def direct_light(film, scene, accel, hit, u):
    rays = library_direct_light(film, scene, accel, hit, u, PathSettings(strategy="nee"))
    return rays


def russian_roulette(throughput, p_rr, u):
    return u < p_rr, throughput / np.float32(p_rr)


def scatter(scene, hit, u, survive):
    """The library's indirect bounce (this file is about another mistake)."""
    paths = path.scatter(scene, hit, u, survive)
    return paths


def trace_paths(film, scene, accel, paths, sampler, settings):
    rays = 0
    for depth in range(settings.max_depth + 1):
        hits = accel.intersect(paths.origins, paths.dirs)
        rays += len(hits.prim)
        hit = surface_hit(scene, paths, hits)
        if len(hit.prim) == 0:
            break
        emitted = take_rows(scene.emission, hit.prim) * hit.front[:, None]   # every hit: the bug
        add_to_film(film, hit.pixel, hit.throughput * emitted)
        if depth == settings.max_depth:
            break
        u = BounceUniforms(sampler, hit.sample, depth)
        rays += direct_light(film, scene, accel, hit, u.light())
        survive, hit.throughput = russian_roulette(hit.throughput, settings.rr, u.roulette())
        paths = scatter(scene, hit, u.bsdf(), survive)
        if len(paths.pixel) == 0:
            break
    return rays
