"""A right chapter-7 answer, written into the exercise file as a student would who follows
the homework's castRay closely: every random number of the loop comes from a generator of
its own (the homework's get_random_float), not from ``BounceUniforms``, and the roulette
keeps the paths whose u is at least 1 - p_rr (not u < p_rr). Its renders are the
library's picture with noise of their own, independent of the library's: full marks.
"""

import numpy as np

from ptlab.integrators.path import SHADOW_EPSILON, Paths, add_to_film, shade, surface_hit
from ptlab.vectors import dot, take_rows

#: The homework's get_random_float: a generator of the file's own, seeded from the system.
random = np.random.default_rng()


def direct_light(film, scene, accel, hit, u):
    light = scene.area_lights.sample(u)
    to_light = light.points - hit.p
    dist2 = dot(to_light, to_light)
    wi = to_light / np.sqrt(dist2)[:, None]
    cos_theta = np.maximum(dot(hit.n, wi), 0)
    cos_theta_light = np.maximum(-dot(light.normals, wi), 0)
    origin = hit.p + hit.offset[:, None] * hit.n
    blocked = accel.occluded(origin, light.target - origin, 1 - SHADOW_EPSILON)
    f_r = shade(hit, "eval", hit.wo, wi, hit.n)
    weight = ~blocked * cos_theta * cos_theta_light / (dist2 * light.pdf_area)
    add_to_film(film, hit.pixel, hit.throughput * f_r * light.radiance * weight[:, None])
    return len(hit.prim)


def russian_roulette(throughput, p_rr, u):
    survive = u >= 1 - p_rr
    return survive, np.where(survive[:, None], throughput / np.float32(p_rr), throughput)


def scatter(scene, hit, u, survive):
    wi = shade(hit, "sample", hit.wo, hit.n, u)
    f_r = shade(hit, "eval", hit.wo, wi, hit.n)
    pdf = shade(hit, "pdf", hit.wo, wi, hit.n)
    cos_theta = dot(wi, hit.n)
    usable = pdf > 1e-12
    weight = np.where(usable, np.abs(cos_theta) / np.where(usable, pdf, 1), 0)
    throughput = hit.throughput * f_r * weight[:, None]
    rows = np.flatnonzero(survive & (throughput.max(axis=1) > 0))
    side = np.where(cos_theta >= 0, hit.offset, -hit.offset)
    origins = hit.p + side[:, None] * hit.n
    return Paths(origins=take_rows(origins, rows), dirs=take_rows(wi, rows),
                 throughput=take_rows(throughput, rows), pixel=hit.pixel[rows],
                 sees_emission=hit.delta[rows], sample=hit.sample[rows])


def trace_paths(film, scene, accel, paths, sampler, settings):
    rays = 0
    for depth in range(settings.max_depth + 1):
        hits = accel.intersect(paths.origins, paths.dirs)
        rays += len(hits.prim)
        hit = surface_hit(scene, paths, hits)
        if len(hit.prim) == 0:
            break
        seen = (hit.sees_emission & hit.front)[:, None] * take_rows(scene.emission, hit.prim)
        add_to_film(film, hit.pixel, hit.throughput * seen)
        if depth == settings.max_depth:
            break
        count = len(hit.prim)
        rays += direct_light(film, scene, accel, hit, random.random((count, 2), dtype=np.float32))
        survive, hit.throughput = russian_roulette(hit.throughput, settings.rr,
                                                   random.random(count, dtype=np.float32))
        paths = scatter(scene, hit, random.random((count, 2), dtype=np.float32), survive)
        if len(paths.pixel) == 0:
            break
    return rays
