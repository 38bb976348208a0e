"""A typical wrong chapter-7 answer: double counting. The loop adds the emission of every
surface a path hits, after diffuse bounces too, while direct_light has already counted the
light that reaches each hit point from the lights: light that arrives in one bounce is
counted twice, and the image is too bright. (The fix: only camera rays, and rays after a
mirror or glass, add the emission they see: ``hit.sees_emission``.)"""

import numpy as np

from ptlab.integrators.path import SHADOW_EPSILON, Paths, add_to_film, shade, surface_hit
from ptlab.samplers import BounceUniforms
from ptlab.vectors import dot, take_rows

EXPECTED_FAILURES = ("white furnace", "Cornell box")


def direct_light(film, scene, accel, hit, u):
    light = scene.area_lights.sample(u)
    to_light = light.points - hit.p
    dist2 = dot(to_light, to_light)
    wi = to_light / np.sqrt(dist2)[:, None]
    cos_theta = np.maximum(dot(hit.n, wi), 0)
    cos_theta_light = np.maximum(-dot(light.normals, wi), 0)
    origin = hit.p + hit.offset[:, None] * hit.n
    target = light.points + light.offset * light.normals
    visible = ~accel.occluded(origin, target - origin, 1 - SHADOW_EPSILON)
    f = shade(hit, "eval", hit.wo, wi, hit.n)
    scale = visible * cos_theta * cos_theta_light / (dist2 * light.pdf_area)
    add_to_film(film, hit.pixel, hit.throughput * f * light.radiance * scale[:, None])
    return len(wi)


def russian_roulette(throughput, p_rr, u):
    return u < p_rr, throughput / np.float32(p_rr)


def scatter(scene, hit, u, survive):
    wi = shade(hit, "sample", hit.wo, hit.n, u)
    f = shade(hit, "eval", hit.wo, wi, hit.n)
    pdf = shade(hit, "pdf", hit.wo, wi, hit.n)
    cos_theta = np.abs(dot(wi, hit.n))
    weight = np.where(pdf > 1e-8, cos_theta / np.maximum(pdf, 1e-8), 0).astype(np.float32)
    throughput = hit.throughput * f * weight[:, None]
    side = np.where(dot(wi, hit.n) >= 0, hit.offset, -hit.offset)
    origins = hit.p + side[:, None] * hit.n
    rows = np.flatnonzero(survive)
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
