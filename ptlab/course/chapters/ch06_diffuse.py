"""Chapter 6's checks: Monte Carlo and the diffuse material (``Lambertian``: eval, pdf, sample).

Known answers come from the Lambertian model itself (f_r = albedo / pi above the surface, 0
below; a pdf integrates to 1 over the sphere and is the density of the samples; samples lie
in the normal's hemisphere), then
the material harness (``ptlab.grading.check_material``) tests that ``sample`` is drawn from
``pdf``, and the student's material, in place of every diffuse one, must render the Cornell
box like the library's.

The render comparison is ``ptlab.course.renders``'s, shared with other chapters.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ptlab.course.chapter import (
    Chapter,
    ChapterCheck,
    ChapterRender,
    CheckFailed,
    grading_rng,
    grading_seed_for,
    require,
    student_file,
)
from ptlab.course.finite import finite_array
from ptlab.course.messages import aside, check_name, text
from ptlab.course.renders import compare_renders, pass_images, replace_materials
from ptlab.grading.probes import Turned
from ptlab.rendering.sizes import SPP_PER_PASS

ALBEDO = (0.8, 0.5, 0.2)

#: Directions per wo in the harness: 2 x 10^5 (the harness's default is 10^6: a weaker test,
#: with the same false-alarm rates, that still catches a pdf off by any constant at once).
HARNESS_SAMPLES = 200_000


# -- chapter 6 ------------------------------------------------------------------------------


def _material(module, albedo=ALBEDO):
    (Lambertian,) = require(module, "Lambertian")  # noqa: N806 (a class)
    return Lambertian(albedo)


def probe(material) -> None:
    """Call ``eval``, ``pdf`` and ``sample`` once on a few directions, so that a method not
    written yet, one that raises, or one that returns the wrong shape, is reported as itself
    (once, with the shapes) before a long check starts."""
    rows = 5  # not 3: a (3, 3) result would hide rows and colours swapped
    material = Turned(material, grading_rng(60))  # (no row repeats n: see below)
    n = np.tile([0.0, 0.0, 1.0], (rows, 1))
    wo = _unit(
        np.array([[0.6, 0.0, 0.8], [0.0, 0.28, 0.96], [-0.3, 0.4, 0.5], [0.1, 0.1, 1.0], [0.9, -0.2, 0.3]])
    )
    wi = wo[::-1]
    _call(material, "eval", wo, wi, n)
    _call(material, "pdf", wo, wi, n, width=None)
    _call(material, "sample", wo, n, np.full((rows, 2), 0.5))


def _call(material, method: str, *arrays, width: int | None = 3) -> np.ndarray:
    """``material.<method>(*arrays)`` as float64, checked for shape and finiteness (the row
    of the first NaN is named). The method gets copies: the check's arrays stay its own."""
    rows = len(arrays[0])
    return finite_array(
        getattr(material, method)(*(a.copy() for a in arrays)), method, (rows, width) if width else (rows,)
    )


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _frame(n: np.ndarray, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(N, 3) unit directions at angle theta from the unit normal(s) n ((3,) or (N, 3)), azimuth phi."""
    from ptlab.sampling import to_world

    local = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    return np.asarray(to_world(local, np.broadcast_to(n, local.shape)))


def random_pairs(rng, count: int):
    """count (wo, wi, n): random normals, wo and wi above the surface."""
    n = _unit(rng.normal(size=(count, 3)))
    wo = _frame(n, np.arccos(rng.uniform(0.05, 1, count)), rng.uniform(0, 2 * math.pi, count))
    wi = _frame(n, np.arccos(rng.uniform(0.05, 1, count)), rng.uniform(0, 2 * math.pi, count))
    return wo, wi, n


def check_eval(module) -> str:
    material = _material(module)
    rng = grading_rng(61)
    wo, wi, n = random_pairs(rng, 500)
    expected = np.asarray(ALBEDO) / math.pi
    cos_theta_i = np.sum(wi * n, axis=1)
    f = _call(material, "eval", wo, wi, n)
    ratio = f / expected
    if not np.allclose(f, expected, rtol=1e-4, atol=0):
        if np.allclose(ratio, math.pi, rtol=1e-3):
            raise CheckFailed(text("ch06.eval_albedo"))
        if np.allclose(ratio, cos_theta_i[:, None], rtol=1e-3):
            raise CheckFailed(text("ch06.eval_cosine"))
        if np.allclose(ratio, ratio[:1], rtol=1e-4):
            raise CheckFailed(
                text(
                    "ch06.eval_constant",
                    yours=np.round(f[0], 4),
                    albedo=ALBEDO,
                    expected=np.round(expected, 4),
                )
            )
        raise CheckFailed(
            text(
                "ch06.eval_varies",
                expected=np.round(expected, 4),
                low=np.round(f.min(axis=0), 4),
                high=np.round(f.max(axis=0), 4),
            )
        )
    below_i = _call(material, "eval", wo, -wi, n)
    below_o = _call(material, "eval", -wo, wi, n)
    if np.abs(below_i).max() > 0:
        raise CheckFailed(text("ch06.wi_below"))
    if np.abs(below_o).max() > 0:
        raise CheckFailed(text("ch06.wo_below"))
    return text("ch06.eval_ok")


def check_sample(module) -> str:
    rng = grading_rng(62)
    # Every row turned by a rotation of its own (and the samples turned back): a material
    # cannot tell these repeated directions from a render's.
    material = Turned(_material(module), rng)
    normals = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0]], dtype=np.float64)
    normals = np.concatenate([normals, _unit(rng.normal(size=(4, 3)))])
    count = 2000
    for normal in normals:
        n = np.tile(normal, (count, 1))
        wo = _frame(normal, np.full(count, 0.7), np.full(count, 1.0))
        u = rng.random((count, 2))
        u[:4] = [[0.0, 0.0], [0.0, 0.5], [0.5, 0.0], [1 - 2**-53, 1 - 2**-53]]
        wi = _call(material, "sample", wo, n, u)
        length = np.linalg.norm(wi, axis=1)
        if np.abs(length - 1).max() > 1e-4:
            raise CheckFailed(text("ch06.sample_unit", length=length[np.argmax(np.abs(length - 1))]))
        cos_theta = wi @ normal
        if (cos_theta < -1e-6).any():
            share = np.mean(cos_theta < 0)
            raise CheckFailed(text("ch06.sample_below", share=share, n=np.round(normal, 3)))
        if np.ptp(cos_theta) < 0.1 or np.ptp(wi, axis=0).max() < 0.1:
            raise CheckFailed(text("ch06.sample_constant"))
    return text("ch06.sample_ok", n=len(normals))


def _sphere_points(n: np.ndarray, rows: int = 400, cols: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """The midpoints (rows x cols, 3) of a (theta, phi) grid around n over the whole sphere,
    and their (rows x cols,) solid angles: the midpoint rule."""
    theta = (np.arange(rows) + 0.5) * math.pi / rows
    phi = (np.arange(cols) + 0.5) * 2 * math.pi / cols
    theta, phi = (a.ravel() for a in np.meshgrid(theta, phi, indexing="ij"))
    return _frame(n, theta, phi), np.sin(theta) * (math.pi / rows) * (2 * math.pi / cols)


#: Directions drawn from sample to compare with pdf (``density_of_samples``), and the bands of
#: cos(theta_i) above the surface they are counted in.
DENSITY_SAMPLES = 20_000
DENSITY_BANDS = 10
#: The chance that ``density_of_samples`` fails a right answer (its chi-square's level).
DENSITY_ALPHA = 1e-6


def check_pdf_normalisation(module) -> str:
    """pdf is 0 below the surface (at every point of the grid below it, and at -n), integrates
    to 1 over the sphere, and is the density of the directions sample gives
    (``density_of_samples``): a pdf that integrates to 1 (a constant 1/(2 pi) above the
    surface) with a sample that always returns n is no density of sample's."""
    rng = grading_rng(63)
    material = Turned(_material(module), rng)  # (see check_sample)
    n = _unit(np.array([0.3, -0.5, 0.8]))
    wo = _frame(n, np.array([0.6]), np.array([2.0]))[0]
    w, area = _sphere_points(n)
    rows = len(w)
    ns, wos = np.tile(n, (rows, 1)), np.tile(wo, (rows, 1))
    pdf = _call(material, "pdf", wos, w, ns, width=None)
    below = np.append(pdf[w @ n < 0], _call(material, "pdf", wos[:1], -ns[:1], ns[:1], width=None))
    if np.abs(below).max() > 0:
        raise CheckFailed(text("ch06.pdf_below"))
    total = float(np.sum(pdf * area))
    if abs(total - 1) > 2e-3:
        hint = ""
        if abs(total - 0.5) < 0.01:
            hint = aside(text("ch06.hint.half"))
        elif abs(total - 2) < 0.02:
            hint = aside(text("ch06.hint.double"))
        elif abs(total - 1 / math.pi) < 0.01 or abs(total - math.pi) < 0.03:
            hint = aside(text("ch06.hint.pi"))
        raise CheckFailed(text("ch06.pdf_total", total=total) + hint)
    density_of_samples(material, wo, n, rng)
    return text("ch06.pdf_ok", total=total, samples=DENSITY_SAMPLES)


def density_of_samples(material, wo: np.ndarray, n: np.ndarray, rng: np.random.Generator) -> None:
    """``CheckFailed`` unless the ``DENSITY_SAMPLES`` directions ``material.sample`` gives for
    wo (3,) around n (3,) fall into the ``DENSITY_BANDS`` bands of cos(theta_i) above the
    surface as often as pdf integrates to there (and where pdf is 0 as often as 1 minus its
    integral): Pearson's chi-square (``ptlab.grading.checks``), failing at p < DENSITY_ALPHA."""
    from ptlab.grading.checks import chi2_sf, pooled_chi_square

    count = DENSITY_SAMPLES
    wos, ns = np.tile(wo, (count, 1)), np.tile(n, (count, 1))
    wi = _call(material, "sample", wos, ns, rng.random((count, 2)))
    cos_theta = wi @ n
    landed = (_call(material, "pdf", wos, wi, ns, width=None) > 0) & (cos_theta > 0)
    band = np.minimum((cos_theta * DENSITY_BANDS).astype(np.intp), DENSITY_BANDS - 1)
    observed = np.append(np.bincount(band[landed], minlength=DENSITY_BANDS), (~landed).sum())
    share = _band_integrals(material, wo, n)
    expected = count * np.append(share, max(0.0, 1.0 - share.sum()))
    statistic, dof = pooled_chi_square(observed, expected)
    p = chi2_sf(statistic, dof)
    if p >= DENSITY_ALPHA:
        return
    worst = int(np.argmax(np.abs(observed - expected) / np.sqrt(np.maximum(expected, 1.0))))
    shares = dict(yours=observed[worst] / count, expected=expected[worst] / count, p=p)
    if worst == DENSITY_BANDS:
        raise CheckFailed(text("ch06.pdf_not_density_fails", **shares))
    low, high = worst / DENSITY_BANDS, (worst + 1) / DENSITY_BANDS
    raise CheckFailed(text("ch06.pdf_not_density", low=low, high=high, **shares))


def _band_integrals(material, wo: np.ndarray, n: np.ndarray, points: int = 40, cols: int = 16) -> np.ndarray:
    """(DENSITY_BANDS,) the integral of pdf over each band of cos(theta) above the surface:
    the midpoint rule in cos(theta) (the band's solid angle is d(cos theta) d(phi))."""
    cells = DENSITY_BANDS * points
    mu = (np.arange(cells) + 0.5) / cells
    phi = (np.arange(cols) + 0.5) * 2 * math.pi / cols
    mu, phi = (a.ravel() for a in np.meshgrid(mu, phi, indexing="ij"))
    w = _frame(n, np.arccos(mu), phi)
    rows = len(w)
    pdf = _call(material, "pdf", np.tile(wo, (rows, 1)), w, np.tile(n, (rows, 1)), width=None)
    return (pdf * (2 * math.pi / (cells * cols))).reshape(DENSITY_BANDS, -1).sum(axis=1)


#: Pairs of directions on which the harness's points first compare the material's eval with
#: the expected one (``reflects_as_expected``).
REFLECTANCE_ROWS = 1000


def reflects_as_expected(material, expected_eval: Callable, seed: int, what: str) -> None:
    """``CheckFailed`` unless ``material``'s eval equals ``expected_eval(wo, wi, n)`` (to a
    relative 1e-3) on random pairs above the surface, every row turned by a rotation of its
    own: the harness's points are for consistency of the material the chapter asks for, and
    a material that reflects nothing (eval 0, sample failing) is consistent too."""
    rng = np.random.default_rng([seed, 1])
    wo, wi, n = random_pairs(rng, REFLECTANCE_ROWS)
    f = _call(Turned(material, rng), "eval", wo, wi, n)
    expected = np.asarray(expected_eval(wo, wi, n), dtype=np.float64)
    if np.allclose(f, expected, rtol=1e-3, atol=1e-9):
        return
    black = aside(text("ch06.hint.black")) if not np.abs(f).max() > 0 else ""
    raise CheckFailed(
        text(
            "ch06.harness_eval",
            what=what,
            error=np.abs(f - expected).max(),
            black=black,
            check=check_name(6, "eval"),
        )
    )


def run_harness(
    material, seed: int, what: str, grade_command: str, expected_eval: Callable | None = None
) -> str:
    """``ptlab.grading.check_material`` on the student's material; a ``CheckFailed`` that
    names each failed check with its hint (checks that failed alike, said once), ``what``
    the material was (a phrase after "the reflectance", in the active language: "" for
    chapter 6's) and the ``ptlab grade`` command that prints the whole table. With
    ``expected_eval``, the material's eval must first be it (``reflects_as_expected``), and
    the harness's warning that a material reflects nothing fails too (its other warnings,
    a float64 answer to float32 arguments, are for speed: they cost no points)."""
    from ptlab.grading import check_material

    probe(material)
    if expected_eval is not None:
        reflects_as_expected(material, expected_eval, seed, what)
    report = check_material(material, seed=seed, samples=HARNESS_SAMPLES)
    black = [c for c in report.checks if c.verdict == "warn" and c.name == "reflectance"]
    if report.passed and expected_eval is not None and black:
        hints = "; ".join(c.hint for c in black)
        raise CheckFailed(text("ch06.harness_warns", names="reflectance", what=what, hints=hints))
    if report.passed:
        return text("ch06.harness_ok", what=what, samples=HARNESS_SAMPLES)
    by_hint: dict[str, list[str]] = {}
    for c in report.checks:
        if not c.passed:
            by_hint.setdefault(c.hint or c.statistic, []).append(c.name)
    failures = "; ".join(f"{', '.join(names)}: {hint}" for hint, names in by_hint.items())
    raise CheckFailed(
        text(
            "ch06.harness_failed",
            failed=", ".join(report.failed),
            what=what,
            failures=failures,
            command=grade_command,
        )
    )


def check_harness(module) -> str:
    albedo = np.asarray(ALBEDO) / math.pi

    def lambert(wo, wi, n):
        return np.broadcast_to(albedo, wo.shape)

    return run_harness(
        _material(module),
        grading_seed_for(6),
        "",
        f"ptlab grade {student_file(module)}:Lambertian",
        expected_eval=lambert,
    )


#: The stream of the grading seed that the render check's seed comes from.
RENDER_SEED = 6


#: Samples per pixel in each pass of the render check: drawn per grading in
#: this range (both renders of one check alike), so that the sizes of the material's calls
#: (the first bounce's 24 576 to 40 960 paths, shared among the scene's materials, then
#: fewer at every bounce) are a render's and cannot be known beforehand. At least 24: every
#: material of the Cornell box then gets calls of more than 10 000 rows (the white one about
#: 60% of the paths). Costs 1.5x to 2.5x the time of a render of 16 spp per pass.
RENDER_SPP_PER_PASS = (24, 40)

#: The stream of the grading seed that the render check's samples per pass come from.
SPP_STREAM = 64


def render_spp_per_pass(rng: np.random.Generator | None = None) -> int:
    """A number of samples per pass in ``RENDER_SPP_PER_PASS``, drawn from ``rng`` (the
    grading seed's, so that ``--grading-seed`` repeats it) or else from fresh entropy."""
    low, high = RENDER_SPP_PER_PASS
    return int((rng or np.random.default_rng()).integers(low, high + 1))


def render_options(seed: int, spp_per_pass: int = SPP_PER_PASS) -> dict:
    """The render both sides of chapter 6's comparison make: 32 x 32, 16 passes of
    ``spp_per_pass`` spp (the render check draws it: ``render_spp_per_pass``), in the
    render's own tiles (``pass_images``).

    max_depth 6: a wrong pdf can make the weights grow at every bounce (so that Russian
    roulette never ends a path); bounded paths keep that a finite, clearly visible
    brightening instead of a render that runs out of time.
    """
    return dict(res=32, passes=16, spp_per_pass=spp_per_pass, seed=seed, max_depth=6)


def render_passes(
    material_for: Callable | None = None, seed: int = 0, spp_per_pass: int = SPP_PER_PASS
) -> np.ndarray:
    """The ``pass_images`` of the Cornell box with ``material_for(albedo)`` in place of
    every diffuse material, or with the library's own if None."""
    import ptlab
    from ptlab.materials import Diffuse

    scene = ptlab.load_scene("cornell-box")
    if material_for is not None:
        scene = replace_materials(scene, lambda m: material_for(m.albedo) if isinstance(m, Diffuse) else None)
    return pass_images(scene, **render_options(seed, spp_per_pass))


def check_render(module) -> str:
    probe(_material(module))
    seed = grading_seed_for(RENDER_SEED)
    spp_per_pass = render_spp_per_pass(grading_rng(SPP_STREAM))
    library = render_passes(seed=seed, spp_per_pass=spp_per_pass)
    student = render_passes(lambda albedo: _material(module, albedo), seed, spp_per_pass=spp_per_pass)
    return compare_renders(
        student,
        library,
        text("ch06.yours"),
        hint=text("ch06.hint.render"),
        spp=spp_per_pass,
    )


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered with the student's ``Lambertian`` in place of every diffuse
    material of one albedo, of the same albedo (``ptlab exercise render``); a textured one
    (games101-hw5's checkerboard) stays the library's: the exercise's takes a colour."""
    from ptlab.course.side_by_side import render_with_materials
    from ptlab.materials import Diffuse

    def replaces(material) -> bool:
        return isinstance(material, Diffuse) and not material.textured

    probe(_material(module))
    missing = text("ch06.no_diffuse", scene=scene.name)
    return render_with_materials(scene, options, replaces, lambda m: _material(module, m.albedo), missing)


CHAPTER = Chapter(
    number=6,
    slug="diffuse",
    title="Monte Carlo and the diffuse material",
    functions=("Lambertian.eval", "Lambertian.pdf", "Lambertian.sample"),
    answers=("ptlab.materials.Diffuse",),
    # The microfacet material with ks = 0 is a diffuse one, and the hemisphere warps are
    # half of sample and pdf.
    also_left_out=(
        "ptlab.materials.microfacet",
        "ptlab.sampling.cosine_hemisphere",
        "ptlab.sampling.cosine_hemisphere_around",
        "ptlab.sampling.uniform_hemisphere",
        "ptlab.sampling.uniform_hemisphere_around",
        "ptlab.course.given.FlakyDiffuse",
    ),
    checks=(
        ChapterCheck("eval", 2, check_eval, timeout=30),
        ChapterCheck("sample", 1, check_sample, timeout=30),
        ChapterCheck("pdf integrates to 1", 2, check_pdf_normalisation, timeout=30),
        # A material that reflects nothing and samples one direction (pdf 0) passes every
        # check of the harness: it scores only once sample spreads its directions.
        ChapterCheck("material harness", 3, check_harness, timeout=60, requires=("sample",)),
        ChapterCheck("render", 2, check_render, timeout=60),
    ),
    render=ChapterRender(render_yours),
)
