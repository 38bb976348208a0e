"""``ptlab exercise inspect N FILE --pixel X,Y``: a student's functions against the library's,
vertex by vertex, on the same samples of one pixel.

Every random number is a function of (seed, pixel, sample, dimension), so two runs of one
pixel draw the same numbers: until the student's code computes something else, both trace
the same paths. Per chapter (``INSPECTED``):

* 3 (reflect, refract, fresnel) and 10 (mis_weight): the pixel is inspected twice, with the
  library's functions and with the student's as the render's pieces, as the chapter's
  render check has them; the records are compared field by field (``first_difference``): the first
  vertex where they part is the student's bug. In 10, every call of the student's
  ``mis_weight`` is kept, and the one behind the difference is shown with its arguments
  (``MisCall``): the two densities and the heuristic.
* 7 (the path loop): the same, with the student's ``direct_light``, ``russian_roulette`` and
  ``scatter`` in the library's loop (seen from outside: what each returns, ``Recorder``'s
  ``light_contribution`` and ``next_paths``); then, if they agree, with the student's
  ``trace_paths``, compared sample by sample.
* 9 (the GGX metal): the library's paths, and at every vertex on a metal the student's
  ``eval`` and ``pdf`` at that vertex's very wo and wi against the library's: the two may
  sample other directions, rightly, so only values at the same directions are compared. A
  "ggx" pdf is right if it is the density of either of the library's samplings there
  (Walter et al.'s or the visible normals'). Where eval differs, the terms of f_r from the
  student's own D, G1, G2 and fresnel_schlick are shown beside the library's; where pdf
  differs, or if nothing does, what the student's ``sample`` draws is set against its pdf
  (``ptlab.course.inspect_microfacet``): a sampler whose directions its pdf does not
  describe is a difference too.

The student's functions run as ``check`` runs them (``ptlab.course.grader.grade``: a
process of their own, as the student user); the comparison is made here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.course import inspect_microfacet
from ptlab.course.chapter import require
from ptlab.course.inspect_microfacet import Drawn, Terms
from ptlab.course.inspect_values import ATOL, RTOL, same, shown_value
from ptlab.course.messages import text
from ptlab.inspector import PixelInspection, inspect_pixel
from ptlab.inspector.records import Sample, Vertex
from ptlab.integrators.path import PathPieces
from ptlab.rendering.pieces import Pieces


@dataclass
class MisCall:
    """A call of the student's ``mis_weight`` in the render (chapter 10).

    Attributes:
        pdf, other: its densities: of the strategy whose sample it weighs, and of the other.
        heuristic: "power" or "balance".
        yours: what the student's returned; expected: the library's for the same arguments.
        drawn_by: which strategy drew the sample ("light", "bsdf"; None: not known).
    """

    pdf: float
    other: float
    heuristic: str
    yours: float
    expected: float
    drawn_by: str | None = None


@dataclass
class Difference:
    """Where the student's code first computed something else than the library's.

    Attributes:
        sample: the sample of the pixel.
        depth: the vertex's depth (None: the sample as a whole).
        quantity: what differs ("bsdf.pdf", "light.contribution", ...; chapter 9's
            "sample": the directions the student's sample draws).
        yours, expected: the student's value and the library's.
        terms: chapter 9, "bsdf.f": the BRDF's terms there, the student's and the library's.
        references: chapter 9, "bsdf.pdf": the density of each of the library's samplings.
        drawn: chapter 9, "bsdf.pdf" and "sample": what the student's sample draws there.
        call: chapter 10: the call of ``mis_weight`` that gave the value, with its arguments.
    """

    sample: int
    depth: int | None
    quantity: str
    yours: Any
    expected: Any
    terms: Terms | None = None
    references: dict[str, float] | None = None
    drawn: Drawn | None = None
    call: MisCall | None = None


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


def _pieces_ch10(module, calls: list | None = None) -> Pieces:
    """The student's ``mis_weight`` as the render's; ``calls`` receives (pdf, other,
    heuristic, result) of every call, arrays row for row."""
    (mis_weight,) = require(module, "mis_weight")

    def weights(pdf, other, heuristic="power"):
        pdf, other = np.broadcast_arrays(pdf, other)
        result = np.asarray(mis_weight(pdf, other, heuristic), dtype=np.float32)
        if calls is not None:
            calls.append((np.array(pdf), np.array(other), heuristic, np.broadcast_to(result, pdf.shape)))
        return result

    return Pieces(path=PathPieces(mis_weight=weights))


def _compare_ch10(module, scene, pixel, options) -> Difference | None:
    """``_twice`` with the student's ``mis_weight``, and the call of it behind the first
    difference, with its arguments (``_call_behind``)."""
    calls: list = []
    library = inspect_pixel(scene, pixel, **options)
    yours = inspect_pixel(scene, pixel, **options, pieces=_pieces_ch10(module, calls))
    found = first_difference(yours, library)
    if found is not None:
        found.call = _call_behind(found, yours, calls)
    return found


def _density_behind(found: Difference, yours: PixelInspection) -> tuple[str | None, float | None]:
    """Which strategy drew the sample whose weight made ``found``, and its density as
    recorded: a light sample's (``light.*``), or the BSDF sample's of the bounce before for
    the emission a path sees (or the sky it escapes to); (None, None) if not known."""
    sample = next(s for s in yours.samples if s.index == found.sample)
    at = {v.depth: v for v in sample.vertices}
    if found.depth is None or found.depth not in at:
        return None, None
    light = at[found.depth].light
    if found.quantity.startswith("light.") and light is not None:
        return "light", light.pdf
    before = at.get(found.depth - 1 if found.quantity == "emission" else found.depth)
    if found.quantity in ("emission", "sky") and before is not None and before.bsdf is not None:
        return "bsdf", before.bsdf.pdf
    return None, None


def _call_behind(found: Difference, yours: PixelInspection, calls: list) -> MisCall | None:
    """The first of ``calls`` (the student's ``mis_weight``'s) whose result is not the library's
    for the same arguments, among those whose pdf is ``_density_behind``'s: the renderer
    weighs all the pixel's samples of a bounce in one call, so the row is told by its density."""
    from ptlab.integrators.path import mis_weight

    drawn_by, density = _density_behind(found, yours)
    for pdf, other, heuristic, result in calls:
        with np.errstate(all="ignore"):
            expected = mis_weight(pdf, other, heuristic)
            differ = ~np.isclose(result, expected, rtol=RTOL, atol=ATOL)
            if density is not None:
                differ &= np.isclose(pdf, density, rtol=1e-6, atol=0)
        if differ.any():
            k = int(np.argmax(differ))
            values = (float(pdf[k]), float(other[k]), heuristic, float(result[k]), float(expected[k]))
            return MisCall(*values, drawn_by=drawn_by)
    return None


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


@dataclass
class _Visits:
    """The library's vertices on one metal of the pixel, and the student's metal in its place.

    Attributes:
        module: the student's module (a stand-in).
        metal: the library's ``Microfacet``.
        student: the student's ``GGXMetal`` with the metal's f0 and alpha (a stand-in).
        at: (sample, vertex) of each vertex on the metal, in order.
        wo, wi, n: (R, 3) float32 arrays of the vertices' directions (wi: the library's).
    """

    module: Any
    metal: Any
    student: Any
    at: list[tuple[int, Vertex]]
    wo: np.ndarray
    wi: np.ndarray
    n: np.ndarray


def _metal_visits(module, scene, library: PixelInspection, sampling: str) -> list[_Visits]:
    """``_Visits`` for each metal of ``scene`` that the pixel's paths meet."""
    from ptlab.course.chapters.ch09_microfacet import _metal
    from ptlab.materials import Microfacet

    visits = []
    for name, metal in zip(scene.material_names, scene.materials, strict=True):
        if not isinstance(metal, Microfacet):
            continue
        on = [
            (s.index, v, v.bsdf.wi)
            for s in library.samples
            for v in s.vertices
            if v.material == name and v.bsdf is not None
        ]
        if on:
            wo, wi, n = (
                np.array(a, np.float32) for a in zip(*((v.wo, w, v.normal) for _, v, w in on), strict=True)
            )
            student = _metal(module, metal.f0, metal.alpha, sampling)
            visits.append(_Visits(module, metal, student, [(i, v) for i, v, _ in on], wo, wi, n))
    return visits


def _values_differ(visits: _Visits, sampling: str) -> tuple[Difference, int] | None:
    """The first vertex of ``visits`` where the student's eval or pdf is not the library's, and
    its row. The pdf is set against the density of each of the library's samplings that the
    student's may rightly be (``reference_pdfs``): against the one that most rows match."""
    wo, wi, n = visits.wo, visits.wi, visits.n
    yours = {
        "bsdf.f": np.asarray(visits.student.eval(wo, wi, n), np.float64),
        "bsdf.pdf": np.asarray(visits.student.pdf(wo, wi, n), np.float64),
    }
    references = inspect_microfacet.reference_pdfs(visits.metal.alpha, sampling, wo, wi, n)
    matches = {k: sum(map(same, yours["bsdf.pdf"], v)) for k, v in references.items()}
    expected = {
        "bsdf.f": visits.metal.eval(wo, wi, n),
        "bsdf.pdf": references[max(matches, key=matches.__getitem__)],
    }
    for k, (sample, v) in enumerate(visits.at):
        for quantity in ("bsdf.f", "bsdf.pdf"):
            a, b = yours[quantity][k].tolist(), np.asarray(expected[quantity][k], np.float64).tolist()
            if not same(a, b):
                found = Difference(sample, v.depth, quantity, a, b)
                if quantity == "bsdf.f":
                    found.terms = _terms(visits, yours["bsdf.f"], expected["bsdf.f"], k)
                else:
                    found.references = {name: float(values[k]) for name, values in references.items()}
                return found, k
    return None


def _terms(visits: _Visits, yours_f: np.ndarray, expected_f: np.ndarray, k: int) -> Terms | None:
    """``inspect_microfacet.terms`` at row ``k`` of ``visits``, with the rows where eval
    differs; None where wo or wi is below the surface (f_r is 0 there: it has no terms)."""
    from ptlab.vectors import dot

    wo, wi, n = visits.wo, visits.wi, visits.n
    if dot(wo[k], n[k]) <= 0 or dot(wi[k], n[k]) <= 0:
        return None
    differ = np.array([not same(a, b) for a, b in zip(yours_f, expected_f, strict=True)])
    metal = visits.metal
    differing = (wo[differ], wi[differ], n[differ], yours_f[differ])
    return inspect_microfacet.terms(visits.module, metal.f0, metal.alpha, (wo[k], wi[k], n[k]), differing)


def _drawn_at(visits: _Visits, k: int, sampling: str, seed: int) -> Drawn:
    """``inspect_microfacet.drawn`` at row ``k`` of ``visits``, its uniforms a function of the
    seed and the vertex (the same at every run)."""
    sample, vertex = visits.at[k]
    rng = np.random.default_rng([seed, sample, vertex.depth])
    return inspect_microfacet.drawn(
        visits.student, visits.wo[k], visits.n[k], visits.metal.alpha, sampling, rng
    )


def _compare_ch09(module, scene, pixel, options) -> Difference | None:
    """The student's GGXMetal at the library's vertices on metals: its eval and pdf at each
    vertex's very wo and wi (with the terms of f_r where eval differs, and what its sample
    draws where pdf does), then what its sample draws at the first vertex on each metal."""
    sampling = options.pop("metal_sampling")
    library = inspect_pixel(scene, pixel, **options)
    visits = _metal_visits(module, scene, library, sampling)
    found = [(*d, v) for v in visits if (d := _values_differ(v, sampling)) is not None]
    if found:
        first, k, at = min(found, key=lambda x: (x[0].sample, x[0].depth))
        if first.quantity == "bsdf.pdf":
            first.drawn = drawn = _drawn_at(at, k, sampling, options["seed"])
            # The library's density to show is that of the sampling the student's draws like.
            if drawn.like is not None and first.references is not None:
                first.expected = first.references[drawn.like]
        return first
    for at in sorted(visits, key=lambda v: (v.at[0][0], v.at[0][1].depth)):
        drawn = _drawn_at(at, 0, sampling, options["seed"])
        if not drawn.agrees:
            sample, vertex = at.at[0]
            return Difference(sample, vertex.depth, "sample", drawn.drawn, drawn.pdf, drawn=drawn)
    return None


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
    10: Inspected(_veach, dict(res=32, spp=8, max_depth=3, strategy="mis"), _compare_ch10),
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


def message(found: Difference | None, pixel: tuple[int, int], samples: int) -> str:
    """What ``ptlab exercise inspect`` prints, in the active language: a line, and under it
    what the difference is made of (``details``)."""
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
    if found.quantity == "sample" and found.drawn is not None:
        drawn = inspect_microfacet.drawn_line(found.drawn)
        return text("inspect.at", sample=found.sample, depth=found.depth, what=drawn)
    return "\n".join([text("inspect.differs", depth=found.depth, **values), *details(found)])


def details(found: Difference) -> list[str]:
    """The lines under a difference: what it is made of (chapters 9 and 10)."""
    lines = []
    if found.terms is not None:
        lines += inspect_microfacet.terms_lines(found.terms)
    if found.references is not None:
        lines.append(inspect_microfacet.references_line(found.references))
    if found.drawn is not None:
        lines.append("  " + inspect_microfacet.drawn_line(found.drawn))
    if found.call is not None:
        call = found.call
        kind = {"light": "inspect.mis_light", "bsdf": "inspect.mis_bsdf"}.get(
            call.drawn_by or "", "inspect.mis_call"
        )
        values = {k: shown_value(getattr(call, k)) for k in ("pdf", "other", "yours", "expected")}
        lines.append("  " + text(kind, heuristic=call.heuristic, **values))
    return lines


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
