"""Chapter 7's checks: the path tracer of Homework 7 (``castRay``), over a batch of paths.

The student writes the pieces of the path loop (``direct_light``, ``russian_roulette``,
``scatter``) and the loop itself (``trace_paths``), which a render given it as its path
loop (``Pieces.trace_paths``, ``ptlab.rendering.pieces``) runs in place of the library's.

* The pieces first, each against the library's own on the same hits and the same random
  numbers (deterministic, so the comparisons are exact up to float rounding): light
  sampling with its shadow ray in the Cornell box (walls and boxes that cast shadows),
  Russian roulette's survival odds and 1 / P, the bounce's f_r cos / pdf, its ray offset
  and its guard against a pdf of 0.
* Then whole renders with the student's loop: the light must show its own Le (the black
  light of the homework's first attempts), and from its front face only (a sphere half of
  whose emitting faces look away from the camera); the white furnace must come out
  Le (1 + a + ... + a^max_depth) (GAMES101 lecture 16; too bright means emission counted
  twice) and the patterned furnace (``patterned_furnace_scene``) the library's picture;
  Russian roulette at the homework's 0.8 must leave the furnace unbiased, Le / (1 - a);
  and the Cornell box must match the library's region by region
  (``ptlab.course.renders.compare_renders``).

Every input comes from the grading seed (``ptlab.course.chapter.grading_rng`` and
``grading_seed_for``), new for each grading: the hits, the random numbers, the renders'
seeds, the furnace's albedo and emission (``furnace_parameters``) and the patterned
furnace's patches and materials, so that neither an image stored beforehand nor a value
computed for known settings matches. The furnace scenes have no name that tells them from
another. A render far less noisy than the library's at the same samples per pixel, and
right in the mean, fails (``renders.noise_test``): a loop that adds a converged picture, or
the furnace's analytic value, is not a render of its samples.

That alone does not tie the picture to the samples: the furnace's analytic value plus
Gaussian noise of the size of the library's is as noisy as a render, and right in the mean
(tests/exercises/07_wrong_furnace_fake.py earned the furnace check so). Comparing the
student's samples with the library's one by one would tie them, but a right loop may draw
random numbers of its own (the homework's get_random_float,
tests/exercises/07_right_own_random.py), so no sample of it matches the library's. So the
furnace check varies the scene instead, in a way the code is not told: the patterned
furnace, whose radiance differs from patch to patch and has no closed form, must match the
library's render of it too. Only a loop that traces its paths has its picture.

False alarms (a right loop that draws random numbers of its own, against the library's),
at most, for normal passes: "white furnace" 1.1e-3 (5.4e-4 + 2e-4 for the furnace of one
material, ``FURNACE_T`` and ``noise_test``; 1e-4 + 2e-4 for the patterned one,
``PATTERNED_FALSE_ALARM``), "Cornell box" 1.2e-3, "roulette unbiased" 7.4e-4; the other
checks are deterministic (0). Measured over fresh grading seeds: the patterned furnace 0
of 600 (95% interval 0 to 0.0061), the fake failing it in 600 of 600 and a converged
picture caught as too clean in 600 of 600 (``python scripts/render_false_alarm.py --seeds
600 --check "ch07 white furnace" --check "ch07 patterned furnace" --variance-ratios
--constant --wrong``); the furnace of one material and the roulette 0 of 800 each (0 to
0.0046; ``--seeds 800 --check "ch07 white furnace" --check "ch07 roulette"``), where the
furnace had failed 1 of 600 before its mean was also taken without its most extreme pass
(a firefly). At the tests' fixed grading seed (25) every right answer of tests/exercises
passes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from ptlab.course.chapter import (
    Chapter,
    ChapterCheck,
    ChapterRender,
    CheckFailed,
    grading_rng,
    grading_seed_for,
    require,
)
from ptlab.course.finite import at_pixel, at_row, channel_name, require_finite
from ptlab.course.given import FlakyDiffuse
from ptlab.course.messages import aside, check_name, text
from ptlab.integrators.path import PathPieces
from ptlab.rendering.pieces import Pieces

if TYPE_CHECKING:
    from ptlab.accel import Accelerator
    from ptlab.course.renders import PassSettings
    from ptlab.integrators.wavefront import SurfaceHit
    from ptlab.scene import Scene

#: The furnace (``furnace_scene``): a closed sphere whose inner wall emits LE and reflects
#: ALBEDO (diffuse) everywhere, by default; the checks draw both from the grading seed
#: around these values (``furnace_parameters``).
ALBEDO, LE = 0.5, 0.3


def furnace_parameters() -> tuple[float, float]:
    """(albedo, emission) of this grading's furnace: within 10% of ALBEDO and LE, from the
    grading seed (a right answer's noise, which the tolerances were measured with, barely
    changes; a stored furnace value does not match)."""
    rng = grading_rng(76)
    return float(ALBEDO * rng.uniform(0.9, 1.1)), float(LE * rng.uniform(0.9, 1.1))


# -- scenes and hits --------------------------------------------------------------------------


def furnace_scene(albedo: float = ALBEDO, emission: float = LE, half_turned_out: bool = False) -> Scene:
    """A closed sphere whose inner wall emits ``emission`` and reflects ``albedo`` everywhere.

    Seen from anywhere inside a closed surface like that, the radiance is
    Le (1 + a + a^2 + ...) = Le / (1 - a): the "white furnace". A sphere rather than the box
    of tests/conftest.py (``closed_box_scene``) because inside a sphere light sampling is
    all but noise-free (cos(theta) cos(theta') / |x - x'|^2 = 1 / (4 R^2) for any two points
    of it), while in a box's corners its samples have a heavy tail that makes a correct
    render's mean and standard error both come out low: measured, a 6-standard-error test
    on the box failed a correct answer in 1 of 40 seeds. The sphere is an icosahedron
    subdivided four times (5120 triangles), built with NumPy alone (no mesh files to read).
    Its flat faces keep a heavy tail too, smaller: a light sample on a face next to the
    shading point, near their shared edge, has cos(theta) cos(theta') / |x - x'|^2 without
    bound (infinite variance), and the chance of a given excess falls with the square of
    the subdivisions. Measured over 320 passes of ``furnace_images`` (``python
    scripts/render_false_alarm.py --variance-ratios --check "ch07 white furnace"``), the
    brightest pass was 16% above the mean with 2 subdivisions, 0.8% with 4 (2.2% for a loop
    with random numbers of its own), and its brightest region 2.6 times the region's mean,
    1.12 times with 4 (1.34): with 4 a firefly moves the furnace's mean by less than the
    check's floor, ``FURNACE_FLOOR``.

    With ``half_turned_out`` the triangles on the camera's left (x > 0) are wound the other
    way, so that their front faces look out of the sphere: from inside, the camera sees
    those emitters from behind, where a light does not glow.
    """
    from ptlab.camera import Camera
    from ptlab.course.chapters.ch03_whitted import icosphere
    from ptlab.materials import Diffuse
    from ptlab.scene import Scene

    triangles = icosphere(4)[:, ::-1]  # wound inward: the front (emitting) faces look in
    if half_turned_out:
        out = triangles.mean(axis=1)[:, 0] > 0
        triangles[out] = triangles[out, ::-1]
    material = Diffuse(albedo=[albedo] * 3, emission=[emission] * 3)
    camera = Camera.look_at((0.1, -0.2, -0.3), (0.4, 0.1, 1.0), fov_y=100.0)
    return Scene(
        triangles=triangles,
        material_ids=np.zeros(len(triangles), dtype=np.intp),
        materials=[material],
        camera=camera,
        name="scene",  # (the default: nothing that tells the student's code it is a furnace)
    )


#: The patterned furnace (``patterned_furnace_scene``): the sphere's wall cut into PATCHES
#: patches, an inner sphere of INNER_RADIUS at INNER_CENTRE; their materials come from
#: stream PATTERN_STREAM of the grading seed.
PATCHES = 12
INNER_CENTRE, INNER_RADIUS = (0.25, -0.05, 0.35), 0.25
PATTERN_STREAM = 79


def patterned_furnace_scene(rng: np.random.Generator) -> Scene:
    """A furnace whose radiance only tracing can tell: ``furnace_scene``'s sphere with its
    wall cut into PATCHES patches (the triangles nearest each of PATCHES random directions)
    and a smaller sphere floating inside, in the camera's view; each patch and the inner
    sphere is a diffuse material of its own albedo (0.25 to 0.75) and emission (0.05 to 0.5),
    per colour, drawn from ``rng``.

    Why: in the furnace of one albedo and one emission the radiance is one number,
    Le (1 + a + ... + a^max_depth), which a loop could read off the scene's materials and add
    to its paths with noise of a render's size instead of tracing them; no test of noise
    tells such noise from a render's. Here the radiance differs from patch to patch, and the
    inner sphere hides part of the wall from each point and is lit unevenly itself, so the
    constant form factor of a sphere, 1 / (4 R^2) between any two of its points, which would
    give each patch's radiance in closed form from its first hit, does not hold: the picture
    is known only by tracing its paths (or from the library's render of it, which the check
    compares with). The inner sphere keeps 0.3 from the wall, so that no light sample has a
    short distance to a point it faces (no firefly beyond the wall's own,
    ``furnace_scene``).
    """
    from ptlab.course.chapters.ch03_whitted import icosphere
    from ptlab.materials import Diffuse, Material
    from ptlab.scene import Scene

    wall = icosphere(4)[:, ::-1]  # wound inward, as furnace_scene's
    directions = rng.normal(size=(PATCHES, 3))
    patch = np.argmax(wall.mean(axis=1) @ directions.T / np.linalg.norm(directions, axis=1), axis=1)
    inner = icosphere(2) * INNER_RADIUS + np.asarray(INNER_CENTRE)  # wound outward: seen from outside
    materials: list[Material] = [
        Diffuse(albedo=rng.uniform(0.25, 0.75, 3), emission=rng.uniform(0.05, 0.5, 3))
        for _ in range(PATCHES + 1)
    ]
    return Scene(
        triangles=np.concatenate([wall, inner]),
        material_ids=np.concatenate([patch, np.full(len(inner), PATCHES)]).astype(np.intp),
        materials=materials,
        camera=furnace_scene().camera,
        name="scene",  # (as furnace_scene's)
    )


def first_hits(scene: Scene, count: int = 20_000, stream: int = 70) -> tuple[Accelerator, SurfaceHit]:
    """(accel, hit): the first hits of ``count`` random camera rays in ``scene``, from stream
    ``stream`` of the grading seed.

    ``hit.pixel`` is 0, 1, 2, ... so that a film of one row per path shows each path's own
    contribution.
    """
    from ptlab.accel import make_accelerator
    from ptlab.camera import generate_rays
    from ptlab.integrators.wavefront import Paths, surface_hit

    accel = make_accelerator(scene.triangles)
    rng = grading_rng(stream)
    size = 64
    origins, dirs = generate_rays(
        scene.camera,
        size,
        size,
        rng.integers(0, size, count),
        rng.integers(0, size, count),
        rng.random((count, 2), dtype=np.float32),
    )
    paths = Paths.camera(origins, dirs, np.arange(count), np.arange(count, dtype=np.uint64))
    hit = surface_hit(scene, paths, accel.intersect(origins, dirs))
    hit.pixel = np.arange(len(hit.prim))
    return accel, hit


# -- the pieces -----------------------------------------------------------------------------


def check_direct_light(module) -> str:
    import ptlab
    from ptlab.integrators.path import PathSettings
    from ptlab.integrators.path import direct_light as library_direct_light
    from ptlab.integrators.wavefront import counting_nonfinite

    (direct_light,) = require(module, "direct_light")
    scene = ptlab.load_scene("cornell-box")  # walls, boxes that cast shadows, a small light
    accel, hit = first_hits(scene)
    count = len(hit.prim)
    u = grading_rng(71).random((count, 2), dtype=np.float32)
    expected = np.zeros((count, 3))
    library_direct_light(expected, scene, accel, hit, u, PathSettings(strategy="nee"))
    film = np.zeros((count, 3))
    with counting_nonfinite() as nonfinite:  # (what add_to_film leaves out, in its process too)
        rays = direct_light(film, scene, accel, hit, u.copy())
    if nonfinite.count:
        raise CheckFailed(text("ch07.direct_nonfinite", count=nonfinite.count, row=nonfinite.first_row))
    if not isinstance(rays, int | np.integer) or not 0 <= rays <= count:
        raise CheckFailed(text("ch07.rays_count", count=count, rays=repr(rays)))
    require_finite(film, text("ch07.direct_added"), _at_path, hint=text("ch07.hint.direct_nan"))
    if (film < 0).any():
        raise CheckFailed(text("ch07.negative"))
    lit = expected.max(axis=1) > 0
    dark = lit & (film.max(axis=1) == 0)
    if not dark.mean() <= 0.5 * lit.mean():
        raise CheckFailed(text("ch07.blocked", dark=dark.sum(), lit=lit.sum()))
    close = np.isclose(film, expected, rtol=2e-3, atol=1e-6).all(axis=1)
    if close.mean() < 0.99:
        ratio = film[lit].sum(axis=0) / expected[lit].sum(axis=0)
        hint = _ratio_hint(float(np.mean(ratio)))
        raise CheckFailed(text("ch07.direct", wrong=(~close).sum(), n=count, ratio=np.mean(ratio), hint=hint))
    return text("ch07.direct_ok", right=close.sum(), n=count)


def _at_path(index: tuple[int, ...], shape: tuple[int, ...]) -> str:
    """Where in a film of one row per path (``first_hits``) a value is: "path 17 (red)"."""
    return text("ch07.at_path", path=index[0], paths=shape[0], channel=channel_name(index[1]))


def _ratio_hint(ratio: float) -> str:
    """A likely cause of a constant factor between the student's light and the library's."""
    for factor, cause in [
        (math.pi, "ch07.hint.albedo"),
        (1 / math.pi, "ch07.hint.stray_pi"),
        (2.0, "ch07.hint.factor_2"),
        (0.5, "ch07.hint.factor_half"),
    ]:
        if abs(ratio / factor - 1) < 0.02:
            return text("ch07.cause", cause=text(cause))
    if ratio > 1.5:
        return text("ch07.cause", cause=text("ch07.hint.division"))
    if ratio < 0.7:
        return text("ch07.cause", cause=text("ch07.hint.blocked"))
    return ""


def check_russian_roulette(module) -> str:
    """The survival odds and the 1 / p_rr on known numbers, then the furnace with the
    student's roulette in the library's loop: unbiased at the homework's p_rr = 0.8."""
    (russian_roulette,) = require(module, "russian_roulette")
    _check_roulette_rule(russian_roulette)
    albedo, le = furnace_parameters()
    mean, error = _furnace_with_roulette(russian_roulette, albedo, le)
    return text("ch07.roulette_ok", mean=mean, error=error, radiance=furnace_radiance(None, albedo, le)[1])


def _check_roulette_rule(russian_roulette) -> None:
    rng = grading_rng(72)
    count = 200_000
    throughput = np.asfortranarray(rng.random((count, 3), dtype=np.float32) + 0.1)
    u = rng.random(count, dtype=np.float32)
    for p_rr in (0.8, 0.3):
        result = russian_roulette(throughput.copy(order="F"), p_rr, u.copy())
        if not (isinstance(result, tuple) and len(result) == 2):
            raise CheckFailed(text("ch07.roulette_arrays"))
        survive, new = np.asarray(result[0]), np.asarray(result[1], dtype=np.float64)
        if survive.shape != (count,) or survive.dtype != bool:
            raise CheckFailed(text("ch07.survive", count=count, dtype=survive.dtype, shape=survive.shape))
        if new.shape != (count, 3):
            raise CheckFailed(text("ch07.throughput_shape", count=count, shape=new.shape))
        again = np.asarray(russian_roulette(throughput.copy(order="F"), p_rr, u.copy())[0])
        if not np.array_equal(again, survive):
            raise CheckFailed(text("ch07.same_u"))
        # Binomial: 6 standard deviations, a false alarm of 2e-9.
        spread = 6 * math.sqrt(p_rr * (1 - p_rr) / count)
        if not abs(survive.mean() - p_rr) <= spread:
            raise CheckFailed(text("ch07.survivors", p_rr=p_rr, share=survive.mean()))
        kept = new[survive]
        expected = throughput[survive].astype(np.float64) / p_rr
        if not np.allclose(kept, expected, rtol=1e-5):
            factor = float(np.median(kept / throughput[survive]))
            hint = (
                text("ch07.hint.unchanged")
                if abs(factor - 1) < 1e-4
                else text("ch07.hint.factor", factor=factor)
            )
            raise CheckFailed(text("ch07.divide", p_rr=p_rr) + aside(hint))


def check_scatter(module) -> str:
    from ptlab.integrators.path import scatter as library_scatter

    (scatter,) = require(module, "scatter")
    scene = furnace_scene(albedo=0.7)
    accel, hit = first_hits(scene, stream=73)
    library_hit = first_hits(scene, stream=73)[1]  # the same hits, untouched by the student's code
    rng = grading_rng(74)
    u = rng.random((len(hit.prim), 2), dtype=np.float32)
    survive = rng.random(len(hit.prim)) < 0.8
    # The library's answer first, from the grader's own arrays; the student's code gets copies.
    expected = library_scatter(scene, library_hit, u, survive)
    own = library_hit.prim.take(expected.pixel)
    paths = _check_paths(scatter(scene, hit, u.copy(), survive.copy()), len(hit.prim))
    missing = np.setdiff1d(expected.pixel, paths.pixel)
    if len(missing):
        raise CheckFailed(text("ch07.missing", count=len(missing)))
    extra = np.setdiff1d(paths.pixel, expected.pixel)
    if len(extra) and (paths.throughput[np.isin(paths.pixel, extra)] > 0).any():
        raise CheckFailed(text("ch07.extra", count=len(extra)))
    order = np.argsort(paths.pixel)
    rows = order[np.isin(paths.pixel[order], expected.pixel)]
    dirs, throughput = paths.dirs[rows], paths.throughput[rows]
    origins = paths.origins[rows]
    if not np.allclose(dirs, expected.dirs, atol=1e-4):
        raise CheckFailed(text("ch07.directions"))
    if not np.allclose(throughput, expected.throughput, rtol=2e-3, atol=1e-6):
        ratio = float(np.median(throughput / expected.throughput))
        hint = _ratio_hint(ratio) if abs(ratio - 1) > 0.02 else ""
        raise CheckFailed(text("ch07.throughput", ratio=ratio, hint=hint))
    if paths.sees_emission[rows].any():
        raise CheckFailed(text("ch07.sees_emission"))
    again = accel.intersect(origins, dirs).prim
    acne = np.mean(again == own)
    if not acne <= 1e-3:
        raise CheckFailed(text("ch07.acne", share=acne))
    _check_pdf_near_zero(scatter)
    return text("ch07.scatter_ok", n=len(rows))


def _check_paths(paths, count: int):
    """The student's next paths, checked for the fields and shapes the loop relies on."""
    fields = ("origins", "dirs", "throughput", "pixel", "sees_emission")
    missing = [name for name in fields if not hasattr(paths, name)]
    if missing:
        raise CheckFailed(text("ch07.paths_missing", missing=", ".join(missing)))
    rows = len(paths.pixel)
    if rows > count:
        raise CheckFailed(text("ch07.paths_count", rows=rows, count=count))
    for name in ("origins", "dirs", "throughput"):
        value = np.asarray(getattr(paths, name))
        if value.shape != (rows, 3):
            raise CheckFailed(text("ch07.paths_shape", name=name, rows=rows, shape=value.shape))
        require_finite(value, f"Paths.{name}", at_row, hint=text("ch07.hint.pdf_zero"))
    return paths


def _check_pdf_near_zero(scatter) -> None:
    from ptlab.integrators.wavefront import Paths, SurfaceHit

    rng = grading_rng(75)
    count = 4000
    n = rng.normal(size=(count, 3))  # a normal of its own on every row, like hits
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    wo = rng.normal(size=(count, 3))
    wo *= np.sign(np.sum(wo * n, axis=1))[:, None]  # on n's side, not grazing:
    wo += 0.05 * n
    n, wo = (
        np.asfortranarray((a / np.linalg.norm(a, axis=1, keepdims=True)).astype(np.float32)) for a in (n, wo)
    )
    p = np.asfortranarray(rng.random((count, 3), dtype=np.float32))
    hit = SurfaceHit(
        prim=np.zeros(count, dtype=np.intp),
        p=p,
        n=n,
        wo=wo,
        front=np.ones(count, dtype=bool),
        offset=np.full(count, 1e-4, np.float32),
        materials=[(None, FlakyDiffuse())],
        delta=np.zeros(count, dtype=bool),
        t=np.ones(count, np.float32),
        paths=Paths(
            origins=p - wo,
            dirs=wo,
            throughput=np.ones((count, 3), np.float32, order="F"),
            pixel=np.arange(count),
            sees_emission=np.zeros(count, dtype=bool),
            sample=np.arange(count, dtype=np.uint64),
        ),
    )
    u = rng.random((count, 2), dtype=np.float32)
    failed = u[:, 0] >= 0.75
    with np.errstate(all="ignore"):  # the student's 0 / 0 is judged below, not warned about
        paths = scatter(furnace_scene(), hit, u.copy(), np.ones(count, dtype=bool))
    fields = ("origins", "dirs", "throughput", "pixel")
    if any(not hasattr(paths, name) for name in fields):
        raise CheckFailed(text("ch07.paths"))
    throughput = np.asarray(paths.throughput, dtype=np.float64)
    bad = ~np.isfinite(throughput).all(axis=1)
    if bad.any():
        raise CheckFailed(text("ch07.pdf_zero_nan", count=bad.sum()))
    going_on = np.isin(np.asarray(paths.pixel), np.flatnonzero(failed))
    if (throughput[going_on] > 0).any():
        raise CheckFailed(text("ch07.pdf_zero_light"))
    if not (throughput[~going_on] > 0).all():
        raise CheckFailed(text("ch07.pdf_lost"))


# -- whole renders ------------------------------------------------------------------------


def _student_loop(module):
    (trace_paths,) = require(module, "trace_paths")
    return trace_paths


def _loop(trace_paths=None) -> Pieces:
    """A render's pieces with ``trace_paths`` as its path loop (the library's own if None)."""
    return Pieces(trace_paths=trace_paths)


def _render(scene, trace_paths=None, **options) -> np.ndarray:
    """``ptlab.render`` in this process, with the student's loop if given."""
    import ptlab

    options.setdefault("workers", 1)
    return ptlab.render(scene, **options, pieces=_loop(trace_paths))


def check_light_not_black(module) -> str:
    import ptlab

    trace_paths = _student_loop(module)
    albedo, le = furnace_parameters()
    # First the furnace, where every pixel sees an emitter: emission only is Le everywhere.
    furnace = _render(
        furnace_scene(albedo, le), trace_paths, spp=1, res=8, max_depth=0, rr=0.8, seed=grading_seed_for(77)
    )
    require_finite(furnace, text("ch07.furnace_depth_0"), at_pixel)
    if np.abs(furnace).max() == 0:
        raise CheckFailed(text("ch07.black_furnace", le=le) + text("ch07.add_the_emission"))
    if not np.allclose(furnace, le, rtol=1e-5):
        raise CheckFailed(text("ch07.emission_only", le=le, low=furnace.min(), high=furnace.max()))
    scene = ptlab.load_scene("cornell-box")
    light = scene.materials[scene.material_names.index("light")].emission
    if light is None:  # (the scene file's light emits: a Cornell box without one is broken)
        raise RuntimeError("the Cornell box's light does not emit")
    options = dict(spp=4, res=64, seed=grading_seed_for(7), rr=0.8)
    expected = _render(scene, max_depth=0, **options)
    image = _render(scene, trace_paths, max_depth=0, **options)
    require_finite(image, text("ch07.cornell_depth_0"), at_pixel)
    on_light = np.all(np.abs(expected - light) <= 1e-5 * light, axis=2)  # every sample saw Le
    sees = expected.max(axis=2) > 0
    seen = image[on_light]
    if np.abs(seen).max() == 0:
        raise CheckFailed(text("ch07.black_light", le=np.round(light, 2)) + text("ch07.add_the_emission"))
    if not np.allclose(image[sees], expected[sees], rtol=1e-4, atol=1e-4):
        ratio = float(np.median(seen / light, axis=0).mean())
        raise CheckFailed(text("ch07.light_pixels", le=np.round(light, 2), ratio=ratio))
    full = _render(scene, trace_paths, **options)
    require_finite(full, text("ch07.cornell_all"), at_pixel)
    if not (full[on_light] >= light * (1 - 1e-4)).all():
        raise CheckFailed(text("ch07.light_below", le=np.round(light, 2)))
    return text("ch07.light_ok", n=on_light.sum())


def check_one_sided_lights(module) -> str:
    """Emission only, in a furnace half of whose emitting faces look away from the camera:
    the pixels that see emitters from behind must stay black, the others show Le."""
    trace_paths = _student_loop(module)
    albedo, le = furnace_parameters()
    scene = furnace_scene(albedo, le, half_turned_out=True)
    options = dict(spp=2, res=24, seed=grading_seed_for(78), max_depth=0, rr=0.8)
    expected = _render(scene, **options)
    image = _render(scene, trace_paths, **options)
    require_finite(image, text("ch07.furnace_depth_0"), at_pixel)
    behind = expected.max(axis=2) == 0  # every sample of the pixel saw a back face
    in_front = np.all(expected == np.float32(le), axis=2)
    if np.abs(image[behind]).max(initial=0) > 0:
        glowing = np.count_nonzero(image[behind].max(axis=1) > 0)
        raise CheckFailed(text("ch07.behind_glow", glowing=glowing, n=behind.sum(), most=image[behind].max()))
    if not np.allclose(image, expected, rtol=1e-5, atol=1e-7):
        seen = float(image[in_front].mean()) if in_front.any() else 0.0
        raise CheckFailed(
            text("ch07.front_le", le=le, seen=seen)
            + (
                aside(text("ch07.hint.no_emission", check=check_name(7, "light not black")))
                if seen == 0
                else ""
            )
        )
    return text("ch07.one_sided_ok", behind=behind.sum(), front=in_front.sum())


#: The furnace renders (``furnace_images``): 16 x 16, 8 independent passes of 8 samples
#: per pixel; the checks' seed is stream FURNACE_SEED of the grading seed
#: (scripts/render_false_alarm.py renders with many).
FURNACE_RENDER: PassSettings = dict(res=16, passes=8, spp_per_pass=8)
FURNACE_SEED = 8


def furnace_images(
    pieces: Pieces | None = None, seed: int = 0, albedo: float = ALBEDO, emission: float = LE, **options
) -> np.ndarray:
    """(passes, 16, 16, 3): the independent passes of one render of the furnace of
    ``albedo`` and ``emission`` (``ptlab.course.renders.pass_images``), made of ``pieces``
    (the library's if None)."""
    from ptlab.course.renders import pass_images

    scene = furnace_scene(albedo, emission)
    return pass_images(scene, **{**FURNACE_RENDER, **options}, seed=seed, pieces=pieces)


def furnace_radiance(
    max_depth: int | None = None, albedo: float = ALBEDO, emission: float = LE
) -> tuple[float, str]:
    """(value, formula): the radiance everywhere in the furnace of ``albedo`` and
    ``emission`` for paths of at most ``max_depth`` bounces (None: no limit),
    Le (1 + a + ... + a^max_depth). The formula is in the active language."""
    a, le = albedo, emission
    if max_depth is None:
        value = le / (1 - a)
        return value, text("ch07.radiance", value=value, le=le, a=a)
    value = le * (1 - a ** (max_depth + 1)) / (1 - a)
    return value, text("ch07.radiance_depth", depth=max_depth, value=value, le=le, a=a, limit=le / (1 - a))


#: The furnace test passes within FURNACE_T standard errors of the library's passes' mean,
#: widened by sqrt(NOISE_RATIO) (``ptlab.course.renders``: a right answer may be that
#: much noisier), plus FURNACE_FLOOR of the expected value: Student's t with 7 degrees of
#: freedom exceeds 6.0 with probability 5.4e-4 (two-sided), and the floor absorbs the
#: skew of the estimate (rare bright passes); a mean off only with its most extreme pass
#: passes too (``furnace_verdict``). Measured with a right loop that
#: draws random numbers of its own: no false alarm in 40 fresh grading seeds, furnace and
#: roulette (``python scripts/render_false_alarm.py --seeds 40 --check "ch07 white furnace"
#: --check "ch07 roulette"``), and none in 800 of each (the module's docstring).
FURNACE_T = 6.0
FURNACE_FLOOR = 0.01


def furnace_verdict(
    student: np.ndarray,
    library: np.ndarray,
    expected: tuple[float, str],
    what: str,
    emission_only: Callable[[], np.ndarray] | None = None,
) -> tuple[float, float]:
    """(mean, standard error) of the student's furnace passes (``furnace_images``, red)
    if they agree with ``expected``, a ``furnace_radiance``, else a ``CheckFailed`` that
    says how they differ. The tolerance comes from the ``library``'s passes at the same
    settings; passes noisier than a right answer's, or far less noisy (a picture that is
    not a render of these samples), fail (``renders.noise_test``, per region); a furnace
    too bright or too dark says so first, and its noise after (other light, other noise).
    ``emission_only``, if given, renders the student's furnace once more with emission only,
    to tell a black light from lost direct light."""
    from ptlab.course.renders import NOISE_RATIO, noise_test, regions_of

    value, formula = expected
    require_finite(student, text("ch07.your_furnace", what=what), at_pixel)
    means, library_means = (images[..., 0].mean(axis=(1, 2)) for images in (student, library))
    passes = len(means)
    mean = float(means.mean())
    standard_error = float(means.std(ddof=1) / math.sqrt(passes))
    spread = math.sqrt(NOISE_RATIO) * float(library_means.std(ddof=1))
    averages = text("ch07.averages", mean=mean, error=standard_error, passes=passes, formula=formula)
    # A rare firefly moves one pass by many standard errors (a right loop's furnace once came
    # out 2% too bright so); a wrong loop is off in every pass. So the mean is off only if it
    # is with and without the pass farthest from the median (as ``renders.mean_verdict``):
    # a right answer fails both with probability at most the first's.
    kept = np.delete(means, np.argmax(np.abs(means - np.median(means))))
    within = any(
        abs(float(some.mean()) - value) <= FURNACE_T * spread / math.sqrt(len(some)) + FURNACE_FLOOR * value
        for some in (means, kept)
    )
    noise = noise_test(regions_of(student)[..., 0], regions_of(library)[..., 0])
    said = noise.verdict(FURNACE_RENDER["spp_per_pass"], differs=not within)
    if said is not None and (within or not noise.too_clean):  # (too noisy, or too clean and right)
        raise CheckFailed(text("ch07.furnace_noise", what=what, noise=said, averages=averages))
    if within:
        return mean, standard_error
    if mean > value:
        hint = text("ch07.hint.too_bright")
    elif emission_only is not None and np.abs(emission_only()).max() == 0:
        hint = text("ch07.hint.black_light")
    else:
        hint = text("ch07.hint.too_dark")
    also = text("render.and", difference=said) if said else ""
    raise CheckFailed(text("ch07.furnace", what=what, averages=averages, hint=hint) + also)


#: The furnace without roulette: every path makes FURNACE_DEPTH bounces (rr 1), where the
#: sum Le (1 + a + ... + a^max_depth) stops.
FURNACE_DEPTH = 10


#: The patterned furnace's render (``patterned_furnace_passes``): the furnace's settings
#: (``FURNACE_RENDER``, no roulette, FURNACE_DEPTH bounces) in 12 passes, which give the
#: paired test of ``compare_renders`` its power; its seed is stream PATTERNED_SEED.
PATTERNED_RENDER: PassSettings = {**FURNACE_RENDER, "passes": 12, "rr": 1.0, "max_depth": FURNACE_DEPTH}
PATTERNED_SEED = 80
#: The false-alarm rate of the patterned furnace's mean test (``compare_renders``), below
#: the Cornell box's: the check looks for pictures that are not the furnace's at all (a
#: fake differs by tens of standard errors in most regions), and a right loop failed the
#: test of 1e-3 in 1 of 800 fresh grading seeds (a region 3% darker, 8 standard errors);
#: with 1e-4, in none of 600.
PATTERNED_FALSE_ALARM = 1e-4


def patterned_furnace_passes(trace_paths=None, seed: int = 0) -> np.ndarray:
    """The ``pass_images`` of this grading's ``patterned_furnace_scene``, with
    ``trace_paths`` as the path loop if given (a scene of its own for each render: the code that
    renders it may change what it is given)."""
    from ptlab.course.renders import pass_images

    scene = patterned_furnace_scene(grading_rng(PATTERN_STREAM))
    return pass_images(scene, **PATTERNED_RENDER, seed=seed, pieces=_loop(trace_paths))


def check_furnace(module) -> str:
    """The furnace of one albedo and one emission against its analytic value, then the
    patterned furnace against the library's render of it: a loop that adds the analytic
    value instead of tracing (``patterned_furnace_scene``) has no picture of the second."""
    from ptlab.course.renders import compare_renders, library_render

    trace_paths = _student_loop(module)
    albedo, le = furnace_parameters()
    expected = furnace_radiance(FURNACE_DEPTH, albedo, le)
    furnace = partial(furnace_images, seed=grading_seed_for(FURNACE_SEED), albedo=albedo, emission=le)
    library = library_render(
        ("ch07 furnace", albedo, le, FURNACE_DEPTH), lambda: furnace(rr=1.0, max_depth=FURNACE_DEPTH)
    )
    student = furnace(_loop(trace_paths), rr=1.0, max_depth=FURNACE_DEPTH)
    mean, error = furnace_verdict(
        student,
        library,
        expected,
        text("ch07.no_roulette", depth=FURNACE_DEPTH),
        lambda: furnace(_loop(trace_paths), passes=2, max_depth=0),
    )
    seed = grading_seed_for(PATTERNED_SEED)
    library = library_render(("ch07 patterned furnace", seed), lambda: patterned_furnace_passes(seed=seed))
    patterned = compare_renders(
        patterned_furnace_passes(trace_paths, seed),
        library,
        text("ch07.patterned", patches=PATCHES),
        text("ch07.hint.patterned"),
        PATTERNED_RENDER["spp_per_pass"],
        PATTERNED_FALSE_ALARM,
    )
    return text("ch07.furnace_ok", mean=mean, error=error, radiance=expected[1], patterned=patterned)


def roulette_furnace_images(
    russian_roulette=None, seed: int = 0, albedo: float = ALBEDO, emission: float = LE
) -> np.ndarray:
    """``furnace_images`` of the library's loop at the homework's p_rr = 0.8, with
    ``russian_roulette(throughput, p_rr, u)`` (the exercise's signature) in place of the
    library's roulette if given."""

    def roulette(hit, settings, u):  # the library's signature, the student's rule
        survive, hit.throughput = russian_roulette(hit.throughput, settings.rr, u)
        return np.asarray(survive, dtype=bool)

    pieces = None if russian_roulette is None else Pieces(path=PathPieces(russian_roulette=roulette))
    return furnace_images(seed=seed, albedo=albedo, emission=emission, rr=0.8, pieces=pieces)


def _furnace_with_roulette(russian_roulette, albedo: float, le: float) -> tuple[float, float]:
    from ptlab.course.renders import library_render

    seed = grading_seed_for(FURNACE_SEED + 100)  # (not the furnace check's)
    library = library_render(
        ("ch07 roulette furnace", seed, albedo, le),
        lambda: roulette_furnace_images(seed=seed, albedo=albedo, emission=le),
    )
    student = roulette_furnace_images(russian_roulette, seed, albedo, le)
    expected = furnace_radiance(None, albedo, le)
    return furnace_verdict(student, library, expected, text("ch07.your_roulette"))


#: The Cornell box render (``cornell_passes``): 32 x 32, 12 passes of 8 samples per pixel
#: at the homework's p_rr = 0.8; the check's seed is stream CORNELL_SEED of the grading seed,
#: its colours (``graded_cornell_box``) stream CORNELL_COLOURS.
CORNELL_RENDER: PassSettings = dict(res=32, passes=12, spp_per_pass=8, rr=0.8)
CORNELL_SEED = 9
CORNELL_COLOURS = 80
#: How far this grading's Cornell box strays from the homework's: each albedo channel times
#: a factor in ALBEDO_SCALE, the light's radiance per channel times one in EMISSION_SCALE.
ALBEDO_SCALE = (0.6, 1.0)
EMISSION_SCALE = (0.75, 1.25)


def graded_cornell_box(rng: np.random.Generator) -> Scene:
    """The homework's Cornell box in colours of this grading: each material's albedo and
    the light's radiance scaled per colour channel by factors drawn from ``rng``.

    Why: the picture of one fixed scene can be rendered at home, stored, and added back with
    noise of a render's size in place of tracing paths; no test of noise tells such noise from
    a render's, and the comparison of means finds the right picture. Its colours drawn anew for
    each grading, the scene's picture is a sum over every path length of products of its
    albedos, known only by tracing it (or from the library's render of it, which the check
    compares with).
    """
    import ptlab
    from ptlab.materials import Diffuse, Material

    scene = ptlab.load_scene("cornell-box")
    materials: list[Material] = []
    for material in scene.materials:
        # (the shipped scene's materials: diffuse, of one colour each)
        assert isinstance(material, Diffuse)
        assert isinstance(material.albedo, np.ndarray)
        albedo = material.albedo * rng.uniform(*ALBEDO_SCALE, 3)
        emission = material.emission
        if emission is not None:
            emission = emission * rng.uniform(*EMISSION_SCALE, 3)
        materials.append(Diffuse(albedo=albedo, sampling=material.sampling, emission=emission))
    return scene.with_materials(materials)


def cornell_passes(trace_paths=None, seed: int = 0, scene: Scene | None = None) -> np.ndarray:
    """The ``pass_images`` of ``scene`` (default: this grading's Cornell box,
    ``graded_cornell_box``), with ``trace_paths`` as the path loop if given (a scene of its
    own for each render: the code that renders it may change what it is given)."""
    from ptlab.course.renders import pass_images

    if scene is None:
        scene = graded_cornell_box(grading_rng(CORNELL_COLOURS))
    return pass_images(scene, seed=seed, **CORNELL_RENDER, pieces=_loop(trace_paths))


def check_cornell(module) -> str:
    from ptlab.course.renders import compare_renders, library_render

    trace_paths = _student_loop(module)
    seed = grading_seed_for(CORNELL_SEED)
    library = library_render(("ch07 cornell box", seed), lambda: cornell_passes(seed=seed))
    student = cornell_passes(trace_paths, seed)
    try:
        return compare_renders(student, library, text("ch07.yours"), spp=CORNELL_RENDER["spp_per_pass"])
    except CheckFailed as failure:
        from ptlab.course.inspect_command import suggestion

        raise CheckFailed(str(failure) + suggestion(7, student, library, seed)) from None


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered by the student's ``trace_paths`` (``ptlab exercise render``)."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, _loop(_student_loop(module)))


CHAPTER = Chapter(
    number=7,
    slug="path_tracing",
    title="Path tracing: the homework's castRay",
    functions=("direct_light", "russian_roulette", "scatter", "trace_paths"),
    answers=tuple(
        f"ptlab.integrators.path.{name}"
        for name in ("direct_light", "russian_roulette", "scatter", "trace_paths")
    ),
    # The rest of the library's path loop, Whitted's direct light, and the inspector's
    # replay of the loop.
    also_left_out=(
        "ptlab.integrators.path.add_emission",
        "ptlab.integrators.path.sampled_lights",
        "ptlab.integrators.path.add_sky",
        "ptlab.integrators.whitted",
        "ptlab.inspector",
    ),
    writes={"direct_light": ("film",), "trace_paths": ("film",)},
    scratch={"russian_roulette": ("throughput",), "scatter": ("hit",), "trace_paths": ("paths",)},
    checks=(
        ChapterCheck("direct light", 2, check_direct_light, timeout=30),
        ChapterCheck("roulette unbiased", 2, check_russian_roulette, timeout=45),
        ChapterCheck("indirect bounce", 2, check_scatter, timeout=30),
        ChapterCheck("light not black", 1, check_light_not_black, timeout=45),
        ChapterCheck("lights one-sided", 1, check_one_sided_lights, timeout=30),
        ChapterCheck("white furnace", 2, check_furnace, timeout=60),
        ChapterCheck("Cornell box", 2, check_cornell, timeout=60),
    ),
    render=ChapterRender(render_yours, options=dict(rr=CORNELL_RENDER["rr"])),  # (the homework's p_rr)
)
