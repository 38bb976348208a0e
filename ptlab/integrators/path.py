"""The path tracer of GAMES101 Homework 7, run over a whole batch of paths at once.

The homework's ``castRay(ray)``, per path (GAMES101 lecture 16):

1. find the closest hit; a camera ray that sees a light adds its emission Le;
2. direct light: sample a point on the lights, and if the shadow ray reaches it add
   Le f_r cos(theta) cos(theta') / |x - x'|^2 / pdf_light;
3. Russian roulette: continue with probability P, dividing what follows by P;
4. indirect light: sample wi from the material, multiply the path's throughput by
   f_r cos(theta) / pdf, and trace the next ray. Light reached by that ray's *emission*
   is not added again: step 2 already counted it (no double counting).

Mirrors and glass (``Material.is_delta``) reflect into one exact direction, which a
sampled light point never hits: they get no step 2, and the emission seen right after
them is added instead (pbrt-v4's ``specularBounce``). A camera ray is treated the same way,
which is why the light itself is not black.

``strategy`` chooses how direct light is found (pbrt-v4's SimplePathIntegrator switches and
PathIntegrator; Veach's thesis, chapter 9):

* ``"nee"``: the homework's, as above: light sampling only;
* ``"bsdf"``: no step 2; every hit adds the emission it sees;
* ``"mis"``: both, each weighted by the power heuristic w = p^2 / (p_light^2 + p_bsdf^2)
  (or, with ``heuristic="balance"``, w = p / (p_light + p_bsdf)), so that each light path
  is counted once in total, mostly by the strategy that finds it more easily (sharp lobes:
  BSDF sampling; small lights: light sampling).

Point lights and a sky (``ptlab.lights``) join in: a point light is found by light sampling
only (no ray can hit a point, so its MIS weight is 1, and even ``"bsdf"`` samples it); the
sky is what a ray that escapes the scene sees, added like the emission of a surface it hits
(``add_sky``), and a light that step 2 samples like the others: every kind of light answers
the same ``sample_li`` and ``pdf_li`` (``ptlab.lights.Light``), so ``direct_light`` serves
them all, and the MIS weights of emission and of the sky take their densities from
``pdf_li``, written once, in the lights.

Here each step is a handful of whole-array operations over every live path ("wavefront"
style): ``trace_paths`` reads like the pseudo-code above, and the vectorisation details
(the batch of paths, compaction, scatter-adding into the film) live in the toolkit that
every integrator shares, ``ptlab.integrators.wavefront``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.integrators.features import features
from ptlab.integrators.wavefront import (
    # The toolkit lived in this module until it moved to wavefront.py: chapter 7's files, as
    # students have them, import SHADOW_EPSILON, Paths, add_to_film, shade and surface_hit here.
    SHADOW_EPSILON,  # noqa: F401
    Paths,
    SurfaceHit,
    add_to_film,
    joined,
    kept,
    leave_surface,
    recorder,
    sees,
    shade,  # noqa: F401
    surface_hit,
)
from ptlab.lights import LightPoint
from ptlab.samplers import BounceUniforms, Sampler
from ptlab.scattering import fresnel_dielectric, reflect, refract
from ptlab.scene import Scene
from ptlab.vectors import dot, take_rows


@dataclass
class PathSettings:
    """How paths are traced.

    Attributes:
        rr: Russian roulette: a survival probability in (0, 1] (the homework's 0.8), or
            ``"throughput"`` to survive with probability max(throughput) (pbrt-v4's rule).
        rr_depth: bounces every path makes before roulette starts; None for the usual
            choice of each rule, decided when the settings are made: 0 for a fixed
            probability (the homework's), 2 for ``"throughput"`` (pbrt-v4's).
        max_depth: the most bounces a path makes (0 = emission only, 1 = direct light).
        strategy: ``"nee"``, ``"bsdf"`` or ``"mis"`` (module docstring).
        heuristic: the MIS weights, ``"power"`` (default) or ``"balance"``.
        sample_sky: light sampling samples the sky (unless the strategy is ``"bsdf"``); if
            False, rays find it only by escaping, and count it in full. (The Whitted tracer's
            rays escape only from mirrors and glass, so there the sky lights nothing.)
        pieces: the functions the steps are made of (``PathPieces``: the library's unless
            a render is given others, ``ptlab.rendering.pieces``).
    """

    rr: float | str = "throughput"
    rr_depth: int | None = None
    max_depth: int = 100
    strategy: str = "nee"
    heuristic: str = "power"
    sample_sky: bool = True
    pieces: PathPieces = field(default_factory=lambda: PathPieces())

    def __post_init__(self) -> None:
        if self.rr_depth is None:  # (each rule's usual start: the docstring)
            self.rr_depth = 2 if self.rr == "throughput" else 0


STRATEGIES = ("nee", "bsdf", "mis")
HEURISTICS = ("power", "balance")


#: The most paths a batch holds when it takes new camera paths as old ones end (``more``).
#: Per path, a bounce costs the same from about 30k paths to 2^18 and more, and a third more
#: below 10k (``ptlab bench --tail``; docs/performance.md).
BATCH_PATHS = 2**18
#: A batch with fewer live paths than this takes new camera paths, up to ``BATCH_PATHS``.
REFILL_BELOW = BATCH_PATHS // 8


def trace_paths(
    film: np.ndarray,
    scene: Scene,
    accel: Accelerator,
    paths: Paths,
    sampler: Sampler,
    settings: PathSettings,
    more: Callable[[int], Paths | None] | None = None,
) -> int:
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
        if more is not None and len(paths) < REFILL_BELOW:
            new = more(BATCH_PATHS - len(paths))
            if new is None:
                more = None  # (no camera paths left: the batch runs dry)
            else:
                paths = joined(paths, new)
        if len(paths) == 0:
            return rays
        # 1. The closest hit (a camera ray that sees a light adds its Le, below).
        hits = accel.intersect(paths.origins, paths.dirs)
        rays += len(hits.prim)
        if scene.sky is not None:
            add_sky(film, scene, paths, hits, settings)  # the paths that escape see the sky
        hit = surface_hit(scene, paths, hits)  # drops the paths that missed
        paths = hit.paths
        if len(hit.prim) == 0:
            continue
        if settings.strategy != "nee" or hit.sees_emission.any():
            add_emission(film, scene, hit, settings)  # the fix for the black light
        ending = np.asarray(hit.depth >= settings.max_depth)  # these paths end here
        if ending.all():
            paths = hit.paths.take(np.zeros(0, dtype=np.intp))
            continue
        u = BounceUniforms(sampler, hit.sample, hit.depth)  # this bounce's random numbers
        if ending.any():  # (a batch at several depths: these find no more light)
            hit.throughput = np.where(ending[:, None], np.float32(0), hit.throughput)
        step = settings.pieces  # (the library's steps, or those a render was given)
        # 2. Direct light: L_dir = Le f_r cos(theta) cos(theta') / |x - x'|^2 / pdf_light.
        if sampled_lights(scene, settings).any():
            rays += step.direct_light(film, scene, accel, hit, u.light(), settings)
        # 3. Russian roulette: go on with probability P_RR, the throughput divided by it.
        going_on = np.ones(len(hit.prim), dtype=bool) & ~ending
        if np.any(hit.depth >= roulette_depth(settings)):
            going_on = going_on & step.russian_roulette(hit, settings, u.roulette())
        # 4. Indirect light: wi ~ pdf, throughput *= f_r cos(theta) / pdf, the next ray.
        paths = step.scatter(scene, hit, u.bsdf(), going_on, with_pdf=settings.strategy == "mis")


def add_emission(film: np.ndarray, scene: Scene, hit: SurfaceHit, settings: PathSettings) -> None:
    """Add Le of the surfaces the paths see, weighted for the strategy.

    Camera rays and rays after a delta bounce always count it; other rays count it fully
    with ``"bsdf"``, not at all with ``"nee"`` and with the MIS weight with ``"mis"``.
    Lights emit from their front face only.
    """
    counted = hit.front if settings.strategy != "nee" else hit.front & hit.sees_emission
    # Only the rows that see an emitter's front (a few percent): the rest would add 0.
    rows = np.flatnonzero(counted & scene.emits.take(hit.prim))
    if len(rows) == 0:
        return
    emitted = take_rows(scene.emission, hit.prim.take(rows))
    if settings.strategy == "mis" and hit.pdf is not None:  # (camera rays have no pdf: weight 1)
        # The density with which light sampling would have picked this point.
        # (With the geometric normal, as light sampling's density has it: ``AreaLights``.)
        t, ng, wo = hit.t.take(rows), take_rows(hit.ng, rows), take_rows(hit.wo, rows)
        found = LightPoint(radiance=emitted, dist2=t * t, cos_theta_light=dot(ng, wo))
        pdf_light = scene.light_sampler.pdf_li(scene.area_lights, found, sampled_lights(scene, settings))
        weight = np.where(
            hit.sees_emission.take(rows),
            1.0,
            settings.pieces.mis_weight(hit.pdf.take(rows), pdf_light, settings.heuristic),
        )
        emitted *= weight.astype(np.float32)[:, None]
    radiance = take_rows(hit.throughput, rows) * emitted
    if (rec := recorder()) is not None:
        rec.emission(hit, rows, radiance)
    if (aov := features()) is not None:  # (a denoiser keeps lights seen directly apart)
        aov.emission(hit.pixel.take(rows), hit.sees_emission.take(rows), radiance)
    add_to_film(film, hit.pixel.take(rows), radiance, _rows_of(hit.depth, rows))


def mis_weight(pdf: np.ndarray, other: np.ndarray | np.floating, heuristic: str = "power") -> np.ndarray:
    """The MIS weight of a sample drawn with density ``pdf`` when the other strategy would
    have drawn it with density ``other`` (Veach 1997, section 9.2): the power heuristic
    (beta = 2) p^2 / (p^2 + q^2), or the balance heuristic p / (p + q)."""
    # Written with the ratio q / p so that huge or tiny pdfs (a sharp lobe's peak, float32)
    # neither overflow nor underflow: p = 0 gives weight 0, q = 0 weight 1.
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        ratio = other / pdf
        weight = 1 / (1 + ratio) if heuristic == "balance" else 1 / (1 + ratio * ratio)
    return np.nan_to_num(weight, nan=0.0)


def direct_light(
    film: np.ndarray,
    scene: Scene,
    accel: Accelerator,
    hit: SurfaceHit,
    u: np.ndarray,
    settings: PathSettings,
) -> int:
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
    # Points that do not face their light sample exchange no light and need no shadow ray (a
    # third of them in the Cornell box: docs/performance.md; a light seen from behind has pdf
    # 0). Nor do mirrors and glass, whose f_r is 0 for any direction but the one they choose.
    usable = np.flatnonzero((cos_theta > 0) & (light.pdf > 0) & ~hit.delta)
    visible = sees(accel, hit, usable, take_rows(light.target, usable))
    weight = np.where(visible, cos_theta / np.where(visible, light.pdf, 1), 0).astype(np.float32)
    mis = None
    if settings.strategy == "mis":
        bsdf_pdf = hit.bsdf.pdf(light.wi)
        if scene.light_sampler.is_delta.any():  # no BSDF sample finds a point light: weight 1
            bsdf_pdf = np.where(scene.light_sampler.is_delta.take(kind), 0, bsdf_pdf)
        mis = settings.pieces.mis_weight(light.pdf, bsdf_pdf, settings.heuristic).astype(np.float32)
        weight *= mis
    # throughput * f_r * Li * cos(theta) / pdf (* the MIS weight), as three in-place steps.
    f_r = hit.bsdf.f(light.wi)
    radiance = hit.throughput * f_r
    radiance *= light.radiance
    radiance *= weight[:, None]
    if (rec := recorder()) is not None:
        rec.light(scene, hit, light, kind, visible, mis, radiance)
    add_to_film(film, hit.pixel, radiance, hit.depth)
    return len(usable)


def sampled_lights(scene: Scene, settings: PathSettings) -> np.ndarray:
    """(K,) bool for each kind of light in ``scene.light_sampler.kinds``: does light sampling
    sample it? Point lights always (no BSDF sample can reach a delta light, so every strategy
    samples them); the triangles and the sky unless the strategy is ``"bsdf"``, and the sky
    only with ``settings.sample_sky``."""
    light_sampler = scene.light_sampler
    if light_sampler is None:
        return np.zeros(0, dtype=bool)
    return np.array(
        [
            kind.is_delta
            or (settings.strategy != "bsdf" and (kind is not light_sampler.sky or settings.sample_sky))
            for kind in light_sampler.kinds
        ]
    )


def add_sky(film: np.ndarray, scene: Scene, paths: Paths, hits, settings: PathSettings) -> None:
    """Add the sky's radiance L for the paths that escaped (``hits.prim`` < 0), weighted as
    ``add_emission`` weighs a light's: in full for camera rays and after mirrors and glass,
    and otherwise by the strategy (not at all with ``"nee"``, the MIS weight with ``"mis"``),
    unless light sampling does not sample the sky (``sampled_lights``): then in full."""
    light_sampler = scene.light_sampler
    sky = light_sampler.sky
    sampled = sampled_lights(scene, settings)
    sky_sampled = sampled[light_sampler.kinds.index(sky)]
    escaped = hits.prim < 0
    counted = escaped if settings.strategy != "nee" or not sky_sampled else escaped & paths.sees_emission
    rows = np.flatnonzero(counted)
    if len(rows) == 0:
        return
    radiance = np.broadcast_to(sky.radiance.astype(np.float32), (len(rows), 3))
    if settings.strategy == "mis" and sky_sampled and paths.pdf is not None:
        # The density with which light sampling would have picked these directions.
        pdf_light = light_sampler.pdf_li(sky, LightPoint(radiance), sampled)
        weight = np.where(
            paths.sees_emission.take(rows),
            1.0,
            settings.pieces.mis_weight(paths.pdf.take(rows), pdf_light, settings.heuristic),
        ).astype(np.float32)
        radiance = radiance * weight[:, None]
    radiance = take_rows(paths.throughput, rows) * radiance
    if (rec := recorder()) is not None:
        rec.sky(paths, rows, radiance)
    if (aov := features()) is not None:
        aov.emission(paths.pixel.take(rows), paths.sees_emission.take(rows), radiance)
    # (A path that escapes after its vertex at depth d sees the sky at depth d + 1.)
    add_to_film(film, paths.pixel.take(rows), radiance, _rows_of(paths.depth, rows))


def russian_roulette(hit: SurfaceHit, settings: PathSettings, u: np.ndarray) -> np.ndarray:
    """(N,) bool: which paths go on. Their throughput is divided by the survival odds.

    Dividing by the probability of surviving keeps the estimate unbiased (lecture 16).
    u: (N,) uniforms. Paths not yet at ``settings.rr_depth`` all go on (survival 1).
    """
    if settings.rr == "throughput":
        t = hit.throughput
        survival = np.minimum(np.maximum(np.maximum(t[:, 0], t[:, 1]), t[:, 2]), 1.0)
    else:
        survival = np.float32(settings.rr)
    # (Paths not yet at the start survive: one depth for all, or several in one batch.)
    survival = np.where(np.asarray(hit.depth) >= roulette_depth(settings), survival, np.float32(1))
    survive = u < survival
    hit.throughput /= np.where(survive, survival, np.float32(1))[:, None]
    if (rec := recorder()) is not None:
        rec.roulette(hit, survival, survive)
    return survive


def roulette_depth(settings: PathSettings) -> int:
    """``settings.rr_depth``, which ``PathSettings`` decided when it was made."""
    assert settings.rr_depth is not None  # (``PathSettings.__post_init__``)
    return settings.rr_depth


def _rows_of(depth: int | np.ndarray, rows: np.ndarray) -> int | np.ndarray:
    """The depths of rows ``rows`` of a batch whose depth is ``depth`` (one, or one per row)."""
    return depth.take(rows) if isinstance(depth, np.ndarray) else depth


def scatter(
    scene: Scene, hit: SurfaceHit, u: np.ndarray, survive: np.ndarray, with_pdf: bool = False
) -> Paths:
    """The next rays of the surviving paths: directions sampled from their materials.

    ``with_pdf`` keeps the pdf of each sampled direction, which MIS weighs emission with.
    """
    # weight = f_r cos(theta_i) / pdf, which a material computes with its sample
    # (``Material.sample_weight``: a mirror's is its reflectance, with no pdf to divide by).
    sample = hit.bsdf.sample(u, with_pdf)
    wi, weight, pdf = sample.wi, sample.weight, sample.pdf
    throughput = hit.throughput * weight
    if (rec := recorder()) is not None:
        rec.bsdf(hit, wi, weight, pdf, throughput, survive)
    if (aov := features()) is not None:  # (a denoiser's albedo is this weight at the first hit)
        aov.first_hits(hit.pixel, hit.sees_emission, hit.delta, hit.n, weight)
    go_on = np.flatnonzero(
        survive & ((throughput[:, 0] > 0) | (throughput[:, 1] > 0) | (throughput[:, 2] > 0))
    )
    every = len(go_on) == len(survive)
    # (New rays leave by the geometric normal: on a smooth surface the shading one may point
    # below it; pbrt-v4's SpawnRay.)
    wi, ng, p, offset = (kept(a, go_on, every) for a in (wi, hit.ng, hit.p, hit.offset))
    depth = hit.depth
    return Paths(
        origins=leave_surface(p, ng, offset, wi),
        dirs=wi,
        throughput=kept(throughput, go_on, every),
        pixel=kept(hit.pixel, go_on, every),
        sees_emission=kept(hit.delta, go_on, every),
        sample=kept(hit.sample, go_on, every),
        pdf=kept(pdf, go_on, every),
        depth=(kept(depth, go_on, every) if isinstance(depth, np.ndarray) else depth) + 1,
    )


@dataclass(frozen=True)
class PathPieces:
    """The functions that tracing paths is made of, each a step a chapter of the course asks
    a student to write: the smooth surface's laws, which the Whitted tracer uses (chapter 3:
    ``reflect``, ``refract``, ``fresnel_dielectric``), the path loop's steps (chapter 7:
    ``direct_light``, ``russian_roulette``, ``scatter``) and the MIS weight (chapter 10).
    The library's by default; a render given others (``ptlab.rendering.pieces.Pieces``)
    carries them in its ``PathSettings``, so every step finds them where it finds its
    settings. Each has the signature of the library's function of its name.
    """

    reflect: Callable[..., np.ndarray] = reflect
    refract: Callable[..., np.ndarray] = refract
    fresnel_dielectric: Callable[..., np.ndarray] = fresnel_dielectric
    direct_light: Callable[..., int] = direct_light
    russian_roulette: Callable[..., np.ndarray] = russian_roulette
    scatter: Callable[..., Paths] = scatter
    mis_weight: Callable[..., np.ndarray] = mis_weight
