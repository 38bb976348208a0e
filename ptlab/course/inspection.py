"""``ptlab exercise inspect N FILE --pixel X,Y``: a student's functions against the library's,
vertex by vertex, on the same samples of one pixel.

Every random number is a function of (seed, pixel, sample, dimension), so two runs of one
pixel draw the same numbers: until the student's code computes something else, both trace
the same paths. Per chapter (``INSPECTED``):

* 3 (reflect, refract, fresnel) and 10 (mis_weight): the pixel is inspected twice, with the
  library's functions and with the student's as the render's pieces, as the chapter's
  render check has them; the records are compared field by field (``first_difference``): the first
  vertex where they part is the student's bug.
* 7 (the path loop): the same, with the student's ``direct_light``, ``russian_roulette`` and
  ``scatter`` in the library's loop (seen from outside: what each returns, ``Recorder``'s
  ``light_contribution`` and ``next_paths``); then, if they agree, with the student's
  ``trace_paths``, compared sample by sample.
* 9 (the GGX metal): the library's paths, and at every vertex on a metal the student's
  ``eval`` and ``pdf`` at that vertex's very wo and wi against the library's (the pdf of the
  student's "ggx" sampling is Walter et al.'s, D cos(theta_h) / (4 |wo . h|)): the two may
  sample other directions, rightly, so only values at the same directions are compared.

The student's functions run as ``check`` runs them (``ptlab.course.grader.grade``: a
process of their own, as the student user); the comparison is made here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.course.chapter import require
from ptlab.inspector import PixelInspection, inspect_pixel
from ptlab.inspector.records import Sample, Vertex
from ptlab.integrators.path import PathPieces
from ptlab.rendering.pieces import Pieces

#: Two values are the same to this relative and absolute tolerance (float32 rounding of two
#: right answers that compute alike differs by about 1e-6).
RTOL, ATOL = 1e-3, 1e-5


@dataclass
class Difference:
    """Where the student's code first computed something else than the library's.

    Attributes:
        sample: the sample of the pixel.
        depth: the vertex's depth (None: the sample as a whole).
        quantity: what differs ("bsdf.pdf", "light.contribution", ...).
        yours, expected: the student's value and the library's.
    """

    sample: int
    depth: int | None
    quantity: str
    yours: Any
    expected: Any


def same(a: Any, b: Any) -> bool:
    """Are two recorded values the same (numbers and lists to ``RTOL``, ``ATOL``)?"""
    if isinstance(a, bool | str) or isinstance(b, bool | str) or a is None or b is None:
        return a == b
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return x.shape == y.shape and bool(np.allclose(x, y, rtol=RTOL, atol=ATOL, equal_nan=True))


def vertex_fields(v: Vertex) -> Iterator[tuple[str, Any]]:
    """(quantity, value) of a vertex, in the order of the homework's castRay."""
    for name in ("position", "triangle", "material", "normal", "front", "wo", "emission"):
        yield name, getattr(v, name)
    for part in ("light", "roulette", "bsdf"):
        record = getattr(v, part)
        if record is not None:
            for f in fields(record):
                yield f"{part}.{f.name}", getattr(record, f.name)
    names = ["reflected", "refracted"] if v.material == "glass" or len(v.split) == 2 else ["next"]
    for name, ray in zip(names, v.split, strict=False):
        yield f"{name} ray wi", ray.wi
        yield f"{name} ray weight", ray.weight
    yield "sky", v.sky
    yield "throughput", v.throughput


def first_difference(yours: PixelInspection, library: PixelInspection) -> Difference | None:
    """The first field, sample by sample and vertex by vertex, where ``yours`` differs from
    ``library``; fields either run did not record (None) are not compared."""
    for mine, theirs in zip(yours.samples, library.samples, strict=True):
        found = sample_difference(mine, theirs)
        if found is not None:
            return found
    return None


def sample_difference(mine: Sample, theirs: Sample) -> Difference | None:
    """The first difference within one sample (``first_difference``)."""
    for a, b in zip(mine.vertices, theirs.vertices, strict=False):
        yours = dict(vertex_fields(a))  # (by name: a record one run lacks has no fields)
        for name, y in vertex_fields(b):
            x = yours.get(name)
            if x is not None and y is not None and not same(x, y):
                return Difference(mine.index, b.depth, name, x, y)
    if mine.vertices and theirs.vertices and len(mine.vertices) != len(theirs.vertices):
        depth = min(len(mine.vertices), len(theirs.vertices))
        return Difference(mine.index, depth, "vertices", len(mine.vertices), len(theirs.vertices))
    if not same(mine.contribution, theirs.contribution):
        return Difference(mine.index, None, "contribution", mine.contribution, theirs.contribution)
    return None


# -- the chapters ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Inspected:
    """How a chapter's functions are inspected.

    Attributes:
        scene: () -> the scene of the chapter's render check.
        options: the render options of the pixel (those of the render check, seed 0).
        compare: (module, scene, pixel, options) -> the first ``Difference`` or None.
    """

    scene: Callable[[], Any]
    options: dict
    compare: Callable[..., Difference | None]


def _twice(pieces_of: Callable[[Any], Pieces]) -> Callable[..., Difference | None]:
    """A ``compare`` that inspects the pixel with the library's functions, then with the
    student's (``pieces_of(module)``: the render's pieces made of them)."""

    def compare(module, scene, pixel, options) -> Difference | None:
        library = inspect_pixel(scene, pixel, **options)
        yours = inspect_pixel(scene, pixel, **options, pieces=pieces_of(module))
        return first_difference(yours, library)

    return compare


def _pieces_ch03(module) -> Pieces:
    from ptlab.course.chapters.ch03_whitted import surface_pieces

    return surface_pieces(*require(module, "reflect", "refract", "fresnel"))


def _pieces_ch10(module) -> Pieces:
    (mis_weight,) = require(module, "mis_weight")

    def weights(pdf, other, heuristic="power"):
        pdf, other = np.broadcast_arrays(pdf, other)
        return np.asarray(mis_weight(pdf, other, heuristic), dtype=np.float32)

    return Pieces(path=PathPieces(mis_weight=weights))


def _pieces_ch07_steps(module) -> Pieces:
    """The student's direct_light, russian_roulette and scatter in the library's loop,
    each reporting what it returned to the recorder (the library's report their insides)."""
    from ptlab.integrators.wavefront import recorder

    direct_light, russian_roulette, scatter = require(module, "direct_light", "russian_roulette", "scatter")

    def light(film, scene, accel, hit, u, settings):
        before = film.take(hit.pixel, axis=0)
        rays = direct_light(film, scene, accel, hit, u)
        if (rec := recorder()) is not None:
            rec.light_contribution(hit, film.take(hit.pixel, axis=0) - before)
        return rays

    def roulette(hit, settings, u):
        survive, hit.throughput = russian_roulette(hit.throughput, settings.rr, u)
        survive = np.asarray(survive, dtype=bool)
        if (rec := recorder()) is not None:
            rec.roulette(hit, None, survive)
        return survive

    def bounce(scene, hit, u, survive, with_pdf=False):
        paths = scatter(scene, hit, u, survive)
        # (The exercise's Paths need not say their depth: one more than their vertex's.)
        depth_of = dict(
            zip(hit.pixel.tolist(), np.broadcast_to(hit.depth, hit.pixel.shape).tolist(), strict=True)
        )
        paths.depth = np.array([depth_of[int(p)] + 1 for p in paths.pixel], dtype=np.intp)
        if (rec := recorder()) is not None:
            rec.next_paths(hit, paths)
        return paths

    return Pieces(path=PathPieces(direct_light=light, russian_roulette=roulette, scatter=bounce))


def _pieces_ch07_loop(module) -> Pieces:
    (trace_paths,) = require(module, "trace_paths")
    return Pieces(trace_paths=trace_paths)


def _compare_ch07(module, scene, pixel, options) -> Difference | None:
    found = _twice(_pieces_ch07_steps)(module, scene, pixel, options)
    return found if found is not None else _twice(_pieces_ch07_loop)(module, scene, pixel, options)


def _compare_ch09(module, scene, pixel, options) -> Difference | None:
    """The student's GGXMetal's eval and pdf at the library's vertices on metals."""
    from ptlab.course.chapters.ch09_microfacet import _metal
    from ptlab.materials import Microfacet

    sampling = options.pop("metal_sampling")
    library = inspect_pixel(scene, pixel, **options)
    metals = {
        name: m
        for name, m in zip(scene.material_names, scene.materials, strict=True)
        if isinstance(m, Microfacet)
    }
    found: list[Difference] = []
    for name, metal in metals.items():
        at = [
            (s.index, v)
            for s in library.samples
            for v in s.vertices
            if v.material == name and v.bsdf is not None
        ]
        if not at:
            continue
        wo, wi, n = (
            np.array([getattr(v, f) if f != "wi" else v.bsdf.wi for _, v in at], np.float32)
            for f in ("wo", "wi", "normal")
        )
        student = _metal(module, metal.f0, metal.alpha, sampling)
        yours = {
            "bsdf.f": np.asarray(student.eval(wo, wi, n), np.float64),
            "bsdf.pdf": np.asarray(student.pdf(wo, wi, n), np.float64),
        }
        expected = {"bsdf.f": metal.eval(wo, wi, n), "bsdf.pdf": _reference_pdf(metal, sampling, wo, wi, n)}
        for k, (sample, v) in enumerate(at):
            for quantity in ("bsdf.f", "bsdf.pdf"):
                a, b = yours[quantity][k].tolist(), np.asarray(expected[quantity][k], np.float64).tolist()
                if not same(a, b):
                    found.append(Difference(sample, v.depth, quantity, a, b))
                    break
    return min(found, key=lambda d: (d.sample, d.depth), default=None)


def _reference_pdf(metal, sampling: str, wo, wi, n) -> np.ndarray:
    """The density of the student's sampling: the cosine hemisphere, or Walter et al.'s GGX
    sampling of normals, D(h) cos(theta_h) / (4 |wo . h|) (2007, eq. 14 and 38)."""
    from ptlab.materials.microfacet import D
    from ptlab.vectors import dot, normalize

    cos_i = dot(wi, n)
    if sampling == "hemisphere":
        return np.where(cos_i > 0, cos_i / math.pi, 0.0)
    h = normalize(wo + wi)
    cos_h = dot(h, n)
    with np.errstate(all="ignore"):
        pdf = D(cos_h, metal.alpha) * cos_h / (4 * np.abs(dot(wo, h)))
    return np.where((cos_i > 0) & (dot(wo, n) > 0), np.nan_to_num(pdf), 0.0)


def _glass_block():
    from ptlab.course.chapters.ch03_whitted import check_scene

    return check_scene()


def _cornell():
    import ptlab

    return ptlab.load_scene("cornell-box")


def _metals():
    from ptlab.course.chapters.ch09_microfacet import metals_scene

    return metals_scene()


def _veach():
    import ptlab

    return ptlab.load_scene("veach-mis")


#: The chapters ``ptlab exercise inspect`` knows, with their render checks' scenes and sizes
#: (so that the pixel a failing render check names is the same pixel here).
INSPECTED: dict[int, Inspected] = {
    3: Inspected(_glass_block, dict(res=48, spp=2, integrator="whitted"), _twice(_pieces_ch03)),
    7: Inspected(_cornell, dict(res=32, spp=8, rr=0.8, sampler="independent"), _compare_ch07),
    9: Inspected(_metals, dict(res=32, spp=8, max_depth=6, sampler="independent"), _compare_ch09),
    10: Inspected(_veach, dict(res=32, spp=8, max_depth=3, strategy="mis"), _twice(_pieces_ch10)),
}


@contextmanager
def _quiet() -> Iterator[None]:
    with np.errstate(all="ignore"):
        yield


def compare_pixel(
    number: int, module, pixel: tuple[int, int], seed: int = 0, sampling: str = "ggx"
) -> Difference | None:
    """The first difference between the student's ``module`` (a ``Submission``'s stand-in)
    and the library at ``pixel`` of chapter ``number``'s render (``INSPECTED``)."""
    inspected = INSPECTED[number]
    options = dict(inspected.options, seed=seed, workers=1)
    if number == 9:
        options["metal_sampling"] = sampling
    with _quiet():
        return inspected.compare(module, inspected.scene(), pixel, options)


def difference_dict(found: Difference | None) -> dict | None:
    """``first_difference`` as the JSON has it (null when they agree)."""
    return None if found is None else asdict(found)


def shown_value(value: Any) -> str:
    """A recorded value in a message: numbers in 4 significant digits."""
    if isinstance(value, bool | str) or value is None:
        return str(value)
    array = np.asarray(value, dtype=np.float64)
    if array.ndim == 0:
        return f"{float(array):.4g}"
    return "(" + ", ".join(f"{x:.4g}" for x in array.ravel()) + ")"


def message(found: Difference | None, pixel: tuple[int, int], samples: int) -> str:
    """The one line ``ptlab exercise inspect`` prints, in the active language."""
    from ptlab.course.messages import text

    x, y = pixel
    if found is None:
        return text("inspect.agree", x=x, y=y, samples=samples)
    values = dict(
        sample=found.sample,
        quantity=found.quantity,
        yours=shown_value(found.yours),
        expected=shown_value(found.expected),
    )
    if found.depth is None:
        return text("inspect.differs_sample", **values)
    return text("inspect.differs", depth=found.depth, **values)


def inspect_file(
    number: int,
    path: str | Path,
    pixel: tuple[int, int],
    seed: int = 0,
    sampling: str = "ggx",
    user: str | None = None,
    timeout: float = 120.0,
) -> tuple[Difference | None, str | None]:
    """Run ``compare_pixel`` on the student's file ``path``, isolated as ``check`` runs it.

    Returns (the first difference or None, None), or (None, what went wrong: the student's
    code raised, hung, or is not written yet).
    """
    from ptlab.course import chapter
    from ptlab.course.chapter import ChapterCheck
    from ptlab.course.grader import grade

    found_chapter = chapter(str(number))
    result: dict[str, Difference | None] = {}

    def run(module) -> str:
        result["found"] = compare_pixel(number, module, pixel, seed, sampling)
        return "done"

    only = replace(found_chapter, checks=(ChapterCheck("inspect", 1, run, timeout=timeout),))
    graded = grade(only, path, user=user, seed=0)
    if not graded.results[0].passed:
        return None, graded.results[0].message
    return result.get("found"), None
