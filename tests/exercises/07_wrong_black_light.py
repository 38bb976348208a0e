"""A typical wrong chapter-7 answer: the black light. Homework 7's first castRay returns the
shading of the hit point and never the emission a camera ray sees, so the light itself (and
Le of every emitting surface) is missing from the image: the light is black, the white
furnace comes out Le too dark. Everything else here is right, written as a student would."""

import numpy as np

from ptlab.integrators.path import SHADOW_EPSILON, Paths, add_to_film, shade, surface_hit
from ptlab.samplers import BounceUniforms
from ptlab.vectors import dot, take_rows

EXPECTED_FAILURES = ("light not black", "lights one-sided", "white furnace", "Cornell box")
#: The furnace message says what is compared with what: the passes' mean against the
#: radiance of paths of at most 10 bounces (not Le / (1 - a) = 0.6).
EXPECTED_HINTS = {"white furnace": ("image averages 0.29", "8 independent passes",
                                    "Le (1 + a + ... + a^10) = 0.5997", "at most 10 bounces"),
                  "lights one-sided": ("see 'light not black'",)}


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
        if len(hit.prim) == 0 or depth == settings.max_depth:
            break
        # (the bug: no emission is added for what the camera rays see)
        u = BounceUniforms(sampler, hit.sample, depth)
        rays += direct_light(film, scene, accel, hit, u.light())
        survive, hit.throughput = russian_roulette(hit.throughput, settings.rr, u.roulette())
        paths = scatter(scene, hit, u.bsdf(), survive)
        if len(paths.pixel) == 0:
            break
    return rays
