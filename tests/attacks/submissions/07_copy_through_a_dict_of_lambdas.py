"""An attack: chapter 7's answer (the library's code pasted in) put through two short
scripts of a red-team student: NumPy respelt (``np.where`` as ``np.select``, ``flatnonzero`` as
``nonzero(ravel(x))[0]``, ``maximum`` as ``fmax``, ``a.take(r)`` as ``a[r]``), then every
operator called through a module-level dict of lambdas (``OPS["Mult"](a, b)``). It had full
marks (12/12) and no word of a copy."""

from __future__ import annotations

OPS = {
    'Mult': lambda a, b: a * b, 'Div': lambda a, b: a / b, 'Add': lambda a, b: a + b,
    'Sub': lambda a, b: a - b, 'BitOr': lambda a, b: a | b, 'BitAnd': lambda a, b: a & b,
    'uInvert': lambda a: ~a, 'uUSub': lambda a: -a, 'uNot': lambda a: not a,
    'Gt': lambda a, b: a > b, 'Lt': lambda a, b: a < b, 'GtE': lambda a, b: a >= b,
    'LtE': lambda a, b: a <= b, 'Eq': lambda a, b: a == b, 'NotEq': lambda a, b: a != b,
    'Pow': lambda a, b: a ** b,
}
class _Names(dict):
    def __missing__(self, key):
        return key
NAMES = _Names()
from collections.abc import Callable
from dataclasses import dataclass
import numpy as np
from ptlab.accel.base import Accelerator
from ptlab.integrators.wavefront import SHADOW_EPSILON, Paths, SurfaceHit, add_to_film, joined, kept, leave_surface, recorder, sees, shade, surface_hit
from ptlab.lights import LightPoint
from ptlab.samplers import BounceUniforms, Sampler
from ptlab.scene import Scene
from ptlab.vectors import dot, take_rows
from ptlab.integrators.path import BATCH_PATHS, PathSettings, REFILL_BELOW

def _rows_of(depth, rows):
    return depth[rows] if isinstance(depth, np.ndarray) else depth

def mis_weight(pdf, other, heuristic='power'):
    if OPS['Eq'](heuristic, 'power'):
        return OPS['Div'](OPS['Mult'](pdf, pdf), OPS['Add'](OPS['Mult'](pdf, pdf), OPS['Mult'](other, other)))
    return OPS['Div'](pdf, OPS['Add'](pdf, other))

def scatter(scene: Scene, hit: SurfaceHit, u: np.ndarray, survive: np.ndarray, with_pdf: bool=False) -> Paths:
    """The next rays of the surviving paths: directions sampled from their materials.

    ``with_pdf`` keeps the pdf of each sampled direction, which MIS weighs emission with.
    """
    pdf = None
    if with_pdf:
        wi, weight, pdf = shade(hit, 'sample_weight_pdf', hit.wo, hit.n, u, hit.front)
    else:
        wi, weight = shade(hit, 'sample_weight', hit.wo, hit.n, u, hit.front)
    throughput = OPS['Mult'](hit.throughput, weight)
    if (rec := recorder()) is not None:
        rec.bsdf(hit, wi, weight, pdf, throughput, survive)
    go_on = np.nonzero(np.ravel(OPS['BitAnd'](survive, OPS['BitOr'](OPS['BitOr'](OPS['Gt'](throughput[:, 0], 0), OPS['Gt'](throughput[:, 1], 0)), OPS['Gt'](throughput[:, 2], 0)))))[0]
    every = OPS['Eq'](len(go_on), len(survive))
    wi, n, p, offset = (kept(a, go_on, every) for a in (wi, hit.n, hit.p, hit.offset))
    depth = hit.depth
    return Paths(origins=leave_surface(p, n, offset, wi), dirs=wi, throughput=kept(throughput, go_on, every), pixel=kept(hit.pixel, go_on, every), sees_emission=kept(hit.delta, go_on, every), sample=kept(hit.sample, go_on, every), pdf=kept(pdf, go_on, every), depth=OPS['Add'](kept(depth, go_on, every) if isinstance(depth, np.ndarray) else depth, 1))

def sampled_lights(scene: Scene, settings: PathSettings) -> np.ndarray:
    """(K,) bool for each kind of light in ``scene.light_sampler.kinds``: does light sampling
    sample it? Point lights always (no BSDF sample can reach a delta light, so every strategy
    samples them); the triangles and the sky unless the strategy is ``"bsdf"``, and the sky
    only with ``settings.sample_sky``."""
    light_sampler = scene.light_sampler
    if light_sampler is None:
        return np.zeros(0, dtype=bool)
    return np.array([kind.is_delta or (OPS['NotEq'](settings.strategy, 'bsdf') and (kind is not light_sampler.sky or settings.sample_sky)) for kind in light_sampler.kinds])

def add_emission(film: np.ndarray, scene: Scene, hit: SurfaceHit, settings: PathSettings) -> None:
    """Add Le of the surfaces the paths see, weighted for the strategy.

    Camera rays and rays after a delta bounce always count it; other rays count it fully
    with ``"bsdf"``, not at all with ``"nee"`` and with the MIS weight with ``"mis"``.
    Lights emit from their front face only.
    """
    counted = hit.front if OPS['NotEq'](settings.strategy, 'nee') else OPS['BitAnd'](hit.front, hit.sees_emission)
    rows = np.nonzero(np.ravel(OPS['BitAnd'](counted, scene.emits[hit.prim])))[0]
    if OPS['Eq'](len(rows), 0):
        return
    emitted = take_rows(scene.emission, hit.prim[rows])
    if OPS['Eq'](settings.strategy, 'mis') and hit.pdf is not None:
        t, n, wo = (hit.t[rows], take_rows(hit.n, rows), take_rows(hit.wo, rows))
        found = LightPoint(radiance=emitted, dist2=OPS['Mult'](t, t), cos_theta_light=dot(n, wo))
        pdf_light = scene.light_sampler.pdf_li(scene.area_lights, found, sampled_lights(scene, settings))
        weight = np.select([hit.sees_emission[rows]], [1.0], mis_weight(hit.pdf[rows], pdf_light, settings.heuristic))
        emitted = OPS['Mult'](emitted, weight.astype(np.float32)[:, None])
    radiance = OPS['Mult'](take_rows(hit.throughput, rows), emitted)
    if (rec := recorder()) is not None:
        rec.emission(hit, rows, radiance)
    add_to_film(film, hit.pixel[rows], radiance, _rows_of(hit.depth, rows))

def add_sky(film: np.ndarray, scene: Scene, paths: Paths, hits, settings: PathSettings) -> None:
    """Add the sky's radiance L for the paths that escaped (``hits.prim`` < 0), weighted as
    ``add_emission`` weighs a light's: in full for camera rays and after mirrors and glass,
    and otherwise by the strategy (not at all with ``"nee"``, the MIS weight with ``"mis"``),
    unless light sampling does not sample the sky (``sampled_lights``): then in full."""
    light_sampler = scene.light_sampler
    sky = light_sampler.sky
    sampled = sampled_lights(scene, settings)
    sky_sampled = sampled[light_sampler.kinds.index(sky)]
    escaped = OPS['Lt'](hits.prim, 0)
    counted = escaped if OPS['NotEq'](settings.strategy, 'nee') or OPS['uNot'](sky_sampled) else OPS['BitAnd'](escaped, paths.sees_emission)
    rows = np.nonzero(np.ravel(counted))[0]
    if OPS['Eq'](len(rows), 0):
        return
    radiance = np.broadcast_to(sky.radiance.astype(np.float32), (len(rows), 3))
    if OPS['Eq'](settings.strategy, 'mis') and sky_sampled and (paths.pdf is not None):
        pdf_light = light_sampler.pdf_li(sky, LightPoint(radiance), sampled)
        weight = np.select([paths.sees_emission[rows]], [1.0], mis_weight(paths.pdf[rows], pdf_light, settings.heuristic)).astype(np.float32)
        radiance = OPS['Mult'](radiance, weight[:, None])
    radiance = OPS['Mult'](take_rows(paths.throughput, rows), radiance)
    if (rec := recorder()) is not None:
        rec.sky(paths, rows, radiance)
    add_to_film(film, paths.pixel[rows], radiance, _rows_of(paths.depth, rows))

def library_direct_light(film: np.ndarray, scene: Scene, accel: Accelerator, hit: SurfaceHit, u: np.ndarray, settings: PathSettings) -> int:
    """Next-event estimation: one light sample and one shadow ray per path.

    The scene's light sampler picks a kind of light among those that ``sampled_lights``
    names, and that kind a light and a point or direction on it (``LightSampler.sample_li``,
    from the uniforms u: (N, 2)): the direction wi to it, the radiance Li arriving along wi,
    and the density of the choice per solid angle, pdf. Adds throughput * f_r Li cos(theta)
    / pdf (times the MIS weight with ``"mis"``; 1 for a point light, which BSDF sampling
    cannot find). For a point on a light triangle, Li = Le and pdf = pdf_area |x - x'|^2 /
    cos(theta'): the homework's Le f_r cos(theta) cos(theta') / |x - x'|^2 / pdf_area.
    Returns the shadow rays.
    """
    sampled = sampled_lights(scene, settings)
    light, kind = scene.light_sampler.sample_li(hit.p, u, sampled)
    cos_theta = dot(hit.n, light.wi)
    usable = np.nonzero(np.ravel(OPS['BitAnd'](OPS['BitAnd'](OPS['Gt'](cos_theta, 0), OPS['Gt'](light.pdf, 0)), OPS['uInvert'](hit.delta))))[0]
    visible = sees(accel, hit, usable, take_rows(light.target, usable))
    weight = np.select([visible], [OPS['Div'](cos_theta, np.select([visible], [light.pdf], 1))], 0).astype(np.float32)
    mis = None
    if OPS['Eq'](settings.strategy, 'mis'):
        bsdf_pdf = shade(hit, 'pdf', hit.wo, light.wi, hit.n)
        if scene.light_sampler.is_delta.any():
            bsdf_pdf = np.select([scene.light_sampler.is_delta[kind]], [0], bsdf_pdf)
        mis = mis_weight(light.pdf, bsdf_pdf, settings.heuristic).astype(np.float32)
        weight = OPS['Mult'](weight, mis)
    radiance = OPS['Mult'](hit.throughput, shade(hit, 'eval', hit.wo, light.wi, hit.n))
    radiance = OPS['Mult'](radiance, light.radiance)
    radiance = OPS['Mult'](radiance, weight[:, None])
    if (rec := recorder()) is not None:
        rec.light(scene, hit, light, kind, visible, mis, radiance)
    add_to_film(film, hit.pixel, radiance, hit.depth)
    return len(usable)

def library_russian_roulette(hit: SurfaceHit, settings: PathSettings, u: np.ndarray) -> np.ndarray:
    """(N,) bool: which paths go on. Their throughput is divided by the survival odds.

    Dividing by the probability of surviving keeps the estimate unbiased (lecture 16).
    u: (N,) uniforms. Paths not yet at ``settings.roulette_starts`` all go on (survival 1).
    """
    if OPS['Eq'](settings.rr, 'throughput'):
        t = hit.throughput
        survival = np.fmin(np.fmax(np.fmax(t[:, 0], t[:, 1]), t[:, 2]), 1.0)
    else:
        survival = np.float32(settings.rr)
    survival = np.select([OPS['GtE'](np.asarray(hit.depth), settings.roulette_starts)], [survival], np.float32(1))
    survive = OPS['Lt'](u, survival)
    hit.throughput = OPS['Div'](hit.throughput, np.select([survive], [survival], np.float32(1))[:, None])
    if (rec := recorder()) is not None:
        rec.roulette(hit, survival, survive)
    return survive

def trace_paths(film: np.ndarray, scene: Scene, accel: Accelerator, paths: Paths, sampler: Sampler, settings: PathSettings, more: OPS['BitOr'](Callable[[int], OPS['BitOr'](Paths, None)], None)=None) -> int:
    """Trace a batch of camera paths to the end, adding their radiance into ``film``.

    Args:
        film: (rows, 3) float64 sums of radiance, per pixel or per path (``paths.pixel`` are
            its rows), updated in place.
        paths: the camera rays, throughput 1.
        sampler: where each path's random numbers come from (``ptlab.samplers``: one
            dimension layout, ``BounceUniforms``, for every integrator).
        more: where more camera paths come from, ``more(count)`` giving at most ``count``
            of them, or None when there are none left. The batch then stays full ("path
            regeneration": Laine, Karras and Aila 2013): whenever fewer than
            ``REFILL_BELOW`` paths live, new camera paths fill it up to ``BATCH_PATHS``,
            and each path goes on at its own depth (``Paths.depth``). Without it the batch
            dwindles to its last path, each of those bounces paying NumPy's fixed costs.

    Returns:
        the number of rays traced (closest-hit and shadow rays).
    """
    rays = 0
    while True:
        if more is not None and OPS['Lt'](len(paths), REFILL_BELOW):
            new = more(OPS['Sub'](BATCH_PATHS, len(paths)))
            if new is None:
                more = None
            else:
                paths = joined(paths, new)
        if OPS['Eq'](len(paths), 0):
            return rays
        hits = accel.intersect(paths.origins, paths.dirs)
        rays = OPS['Add'](rays, len(hits.prim))
        if scene.sky is not None:
            add_sky(film, scene, paths, hits, settings)
        hit = surface_hit(scene, paths, hits)
        paths = hit.paths
        if OPS['Eq'](len(hit.prim), 0):
            continue
        if OPS['NotEq'](settings.strategy, 'nee') or hit.sees_emission.any():
            add_emission(film, scene, hit, settings)
        ending = np.asarray(OPS['GtE'](hit.depth, settings.max_depth))
        if ending.all():
            paths = hit.paths.take(np.zeros(0, dtype=np.intp))
            continue
        u = BounceUniforms(sampler, hit.sample, hit.depth)
        if ending.any():
            hit.throughput = np.select([ending[:, None]], [np.float32(0)], hit.throughput)
        if sampled_lights(scene, settings).any():
            rays = OPS['Add'](rays, library_direct_light(film, scene, accel, hit, u.light(), settings))
        going_on = OPS['BitAnd'](np.ones(len(hit.prim), dtype=bool), OPS['uInvert'](ending))
        if np.any(OPS['GtE'](hit.depth, settings.roulette_starts)):
            going_on = OPS['BitAnd'](going_on, library_russian_roulette(hit, settings, u.roulette()))
        paths = scatter(scene, hit, u.bsdf(), going_on, with_pdf=OPS['Eq'](settings.strategy, 'mis'))
from types import SimpleNamespace
import numpy as np
from ptlab.integrators.path import PathSettings
__all__ = ['direct_light', 'russian_roulette', 'scatter', 'trace_paths']

def direct_light(film, scene, accel, hit, u) -> int:
    """``ptlab.integrators.path.direct_light`` with light sampling only (the homework's)."""
    return library_direct_light(film, scene, accel, hit, u, PathSettings(strategy='nee'))

def russian_roulette(throughput, p_rr, u) -> tuple[np.ndarray, np.ndarray]:
    """``ptlab.integrators.path.russian_roulette`` with a fixed survival probability."""
    hit = SimpleNamespace(throughput=throughput.copy(order='F'), depth=0)
    survive = library_russian_roulette(hit, PathSettings(rr=float(p_rr)), u)
    return (survive, hit.throughput)
