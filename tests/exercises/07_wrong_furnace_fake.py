"""A hostile chapter-7 answer: the furnace faked. Its pieces and its loop are right, but
in a room where every triangle emits (a furnace) with paths of more than one vertex its
``trace_paths`` traces nothing: it reads the albedo a and the emission Le off the scene it is
given (their means over the triangles' areas), computes the furnace's analytic value
Le (1 + a + ... + a^max_depth) (Le / (1 - a) with roulette) and adds it to every path, with
Gaussian noise of the size of the library's samples (2.1% of the value per sample, measured
on the library's passes), so that its passes are as noisy as a render's. The furnace check
must see that this is not a render of the furnace: its picture is not tied to the samples."""

import numpy as np

from ptlab.integrators.path import SHADOW_EPSILON, Paths, add_to_film, shade, surface_hit
from ptlab.samplers import BounceUniforms
from ptlab.vectors import dot, take_rows


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


def _traced_paths(film, scene, accel, paths, sampler, settings):
    rays = 0
    for depth in range(settings.max_depth + 1):
        hits = accel.intersect(paths.origins, paths.dirs)
        rays += len(hits.prim)
        hit = surface_hit(scene, paths, hits)
        if len(hit.prim) == 0:
            break
        emitted = take_rows(scene.emission, hit.prim) * (hit.sees_emission & hit.front)[:, None]
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


EXPECTED_FAILURES = ("white furnace",)
EXPECTED_HINTS = {"white furnace": ["patches and an inner sphere", "differ from the library's picture"]}
#: (The check does not call it a fake: a picture wrong in the mean is told how it differs.)
MISLEADING_HINTS = {"white furnace": ["this is not a render of these samples"]}

#: The library's noise per sample in the furnace, relative to the value (measured at home).
NOISE = 0.021
noise = np.random.default_rng()


def trace_paths(film, scene, accel, paths, sampler, settings):
    if not scene.emits.all() or settings.max_depth == 0:
        return _traced_paths(film, scene, accel, paths, sampler, settings)
    edges = scene.triangles[:, 1:] - scene.triangles[:, :1]
    area = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
    share = (area / area.sum())[:, None]
    albedo = np.array([getattr(m, "albedo", np.zeros(3)) for m in scene.materials], float)
    emission = np.array([m.emission for m in scene.materials], float)
    a = (share * albedo[scene.material_ids]).sum(axis=0)
    le = (share * emission[scene.material_ids]).sum(axis=0)
    bounces = settings.max_depth if settings.rr >= 1 else 10_000
    value = le * (1 - a ** (bounces + 1)) / (1 - a)
    count = len(paths.pixel)
    samples = value * (1 + NOISE * noise.normal(size=(count, 1)))
    add_to_film(film, paths.pixel, (paths.throughput * samples).astype(np.float32))
    return count
