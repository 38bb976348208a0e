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
from ptlab.course.renders import compare_renders, library_render, pass_images, replace_materials
from ptlab.grading.probes import Rotations, Turned
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
    material = _material(module)
    normals = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0]], dtype=np.float64)
    normals = np.concatenate([normals, _unit(rng.normal(size=(4, 3)))])
    count = 2000
    for normal in normals:
        n = np.tile(normal, (count, 1))
        wo = _frame(normal, np.full(count, 0.7), np.full(count, 1.0))
        u = rng.random((count, 2))
        u[:4] = [[0.0, 0.0], [0.0, 0.5], [0.5, 0.0], [1 - 2**-53, 1 - 2**-53]]
        wi, sent_n, returned = sample_on_walls(material, wo, n, u, rng)
        length = np.linalg.norm(wi, axis=1)
        if np.abs(length - 1).max() > 1e-4:
            raise CheckFailed(text("ch06.sample_unit", length=length[np.argmax(np.abs(length - 1))]))
        cos_theta = wi @ normal
        if (cos_theta < -1e-6).any():
            mistake = samples_around_z(material, grading_rng(MISTAKE_STREAM))
            raise CheckFailed(mistake or below_the_surface(sent_n, returned))
        if np.ptp(cos_theta) < 0.1 or np.ptp(wi, axis=0).max() < 0.1:
            raise CheckFailed(text("ch06.sample_constant"))
    return text("ch06.sample_ok", n=len(normals))


def sample_on_walls(material, wo: np.ndarray, n: np.ndarray, u: np.ndarray, rng: np.random.Generator):
    """``material.sample`` on the rows turned onto walls as ``Turned`` turns them (a material
    cannot tell these repeated directions from a render's): (wi turned back into the
    check's frame, the normals the material was given, the directions it returned), so that
    a message can name a row as the material saw it."""
    turn = Rotations.draw(rng, len(wo))
    sent_n = turn.apply(n)
    returned = _call(material, "sample", turn.apply(wo), sent_n, u)
    return turn.undo(returned), sent_n, returned


def vector(v: np.ndarray) -> str:
    """A direction in a message: (0.123, -0.456, 0.789)."""
    return "(" + ", ".join(f"{float(c) + 0.0:.3f}" for c in v) + ")"  # (+ 0.0: no -0.000)


def below_the_surface(sent_n: np.ndarray, returned: np.ndarray) -> str:
    """What is wrong with samples some of which are below the surface (wi . n < 0), naming
    the row farthest below (``sent_n``: the normals sample was given, ``returned``: what it
    returned): "ch06.sample_around_z" where ``around_z``, naming a row whose normal points
    down (where a wi above the xy-plane is plainly not around n), else "ch06.sample_below"."""
    cos_theta = np.sum(returned * sent_n, axis=1)
    turned_never = around_z(sent_n, returned)
    candidates = sent_n[:, 2] < 0 if turned_never else np.ones(len(cos_theta), dtype=bool)
    row = int(np.argmin(np.where(candidates, cos_theta, np.inf)))
    facts = dict(
        share=np.mean(cos_theta < 0), n=vector(sent_n[row]), wi=vector(returned[row]), cos=cos_theta[row]
    )
    return text("ch06.sample_around_z" if turned_never else "ch06.sample_below", **facts)


def around_z(sent_n: np.ndarray, returned: np.ndarray) -> bool:
    """Do the samples lie around +z whatever n is: every one above the xy-plane, though some
    normals point down (a sample around n puts some of its directions below the xy-plane
    there)? The local frame's sample, never turned to n."""
    return bool((returned[:, 2] >= -1e-6).all() and (sent_n[:, 2] < 0).any())


# -- typical mistakes, named from the values a material returns ---------------------------------

#: The stream of the grading seed that ``known_mistake``'s inputs come from.
MISTAKE_STREAM = 65
#: Rows of ``known_mistake``'s calls to pdf (``pdf_follows_wo``) and sample (``samples_around_z``).
MISTAKE_ROWS = 2000
#: ``disk_radius_uniform`` names a disk sample without its square root when the samples'
#: sin(theta) pass a Kolmogorov-Smirnov test of uniformity on [0, 1] at this level (a right
#: cosine sampler's sin(theta)^2 is uniform: its p-value with ``DENSITY_SAMPLES`` is 0).
RADIUS_P = 1e-4


def known_mistake(material) -> str | None:
    """The message that names a typical mistake the material shows on inputs of the check's
    own (stream ``MISTAKE_STREAM`` of the grading seed), or None: a pdf that is a density of
    wo (``pdf_follows_wo``), samples never turned to n (``samples_around_z``), or flipped
    into n's hemisphere in place of it (``samples_flipped``), a disk sample without its
    square root (``disk_radius_uniform``). The checks that fail say it in place
    of a guess from their own statistic."""
    rng = grading_rng(MISTAKE_STREAM)
    # (values far from a right answer's may overflow or divide 0 by 0 here: that is no
    # mistake of theirs to warn of, the diagnosis then names none)
    with np.errstate(all="ignore"):
        for diagnosis in (pdf_follows_wo, samples_around_z, samples_flipped, disk_radius_uniform):
            found = diagnosis(material, rng)
            if found is not None:
                return found
    return None


def pdf_follows_wo(material, rng: np.random.Generator) -> str | None:
    """The message "ch06.pdf_follows_wo" if pdf(wo, wi, n) is proportional to cos(theta_o) =
    wo . n on pairs above the surface (each turned onto a wall) and not to cos(theta_i): a
    density of wo, where sample picks wi. The row named is the one whose two cosines differ
    most."""
    wo, wi, n = random_pairs(rng, MISTAKE_ROWS)
    turn = Rotations.draw(rng, MISTAKE_ROWS)
    wo, wi, n = turn.apply(wo), turn.apply(wi), turn.apply(n)
    pdf = _call(material, "pdf", wo, wi, n, width=None)
    cos_o, cos_i = np.sum(wo * n, axis=1), np.sum(wi * n, axis=1)
    if not _proportional(pdf, cos_o) or _proportional(pdf, cos_i):
        return None
    row = int(np.argmax(np.abs(cos_o - cos_i)))
    return text(
        "ch06.pdf_follows_wo",
        n=vector(n[row]),
        wo=vector(wo[row]),
        wi=vector(wi[row]),
        cos_o=cos_o[row],
        cos_i=cos_i[row],
        yours=pdf[row],
        cosine=cos_i[row] / math.pi,
    )


def _proportional(a: np.ndarray, b: np.ndarray) -> bool:
    """Is ``a`` a positive multiple of ``b`` (> 0), to a relative 1e-3 (float32's rounding
    and pi rounded to float32 included)?"""
    ratio = a / b
    return bool(ratio[0] > 0 and np.allclose(ratio, ratio[0], rtol=1e-3, atol=0))


def samples_around_z(material, rng: np.random.Generator) -> str | None:
    """The message "ch06.sample_around_z" (``below_the_surface``) if sample's directions lie
    around +z whatever n is (``around_z``), some of them below the surface. Half the rows
    have the check's n = -z, so that some normals the material gets point down, whatever the
    walls."""
    n = np.tile([0.0, 0.0, 1.0], (MISTAKE_ROWS, 1))
    n[1::2] *= -1
    theta, phi = np.full(MISTAKE_ROWS, 0.7), rng.uniform(0, 2 * math.pi, MISTAKE_ROWS)
    wo = _frame(n, theta, phi)
    _, sent_n, returned = sample_on_walls(material, wo, n, rng.random((MISTAKE_ROWS, 2)), rng)
    below = np.sum(returned * sent_n, axis=1) < -1e-6
    if not (below.any() and around_z(sent_n, returned)):
        return None
    return below_the_surface(sent_n, returned)


#: ``samples_flipped``'s normal off the z axis has |n_z| at most this (its lobe around n then
#: differs most from one around +z), and the band by the horizon it names is this many degrees.
FLIP_SIDE_Z = 0.2
FLIP_HORIZON_DEGREES = 6.0
#: ``samples_flipped`` sees a lobe around +z where |wi_z| of the samples for the normal off z
#: and for n = +z pass a two-sample Kolmogorov-Smirnov test of one distribution at this level
#: (a right sampler's, around n, fails it with p = 0).
FLIP_P = 1e-4


def samples_flipped(material, rng: np.random.Generator) -> str | None:
    """The message "ch06.sample_flipped" if sample's directions follow pdf for n = +z but not
    for a normal n well off the z axis (``density_misfit``), where their angles to the z axis
    (|wi_z|) are spread as for n = +z (``FLIP_P``): a lobe that stays around +z, each
    direction below the surface flipped into n's hemisphere (wi = -wi) rather than the whole
    sample turned to n (to_world). The message compares the share of the samples within
    ``FLIP_HORIZON_DEGREES`` of n's horizon with the integral of pdf there."""
    from scipy.stats import ks_2samp

    up = np.array([0.0, 0.0, 1.0])
    z, phi = rng.uniform(-FLIP_SIDE_Z, FLIP_SIDE_Z), rng.uniform(0, 2 * math.pi)
    side = np.array([math.sqrt(1 - z * z) * math.cos(phi), math.sqrt(1 - z * z) * math.sin(phi), z])
    wo_up, wo_side = (_frame(n, np.array([0.6]), rng.uniform(0, 2 * math.pi, 1))[0] for n in (up, side))
    wi_up, wi_side = draw_samples(material, wo_up, up, rng), draw_samples(material, wo_side, side, rng)
    if density_misfit(material, wo_up, up, wi_up) is not None:
        return None
    if density_misfit(material, wo_side, side, wi_side) is None:
        return None
    if ks_2samp(np.abs(wi_up[:, 2]), np.abs(wi_side[:, 2])).pvalue < FLIP_P:
        return None
    edge = math.sin(math.radians(FLIP_HORIZON_DEGREES))  # cos(theta_i) at that angle from the horizon
    cos_theta = wi_side @ side
    expected = _pdf_over_bands(material, wo_side, side, np.array([0.0, edge]))[0]
    return text(
        "ch06.sample_flipped",
        n=vector(side),
        share=np.mean((cos_theta > 0) & (cos_theta < edge)),
        degrees=FLIP_HORIZON_DEGREES,
        expected=expected,
    )


def disk_radius_uniform(material, rng: np.random.Generator) -> str | None:
    """The message "ch06.disk_radius_uniform" if the ``DENSITY_SAMPLES`` directions sample
    gives all lie above the surface with sin(theta_i) spread evenly over [0, 1]
    (``RADIUS_P``): sin(theta_i) is the radius r of the disk point that Malley's method lifts
    onto the hemisphere, drawn as r = u0 where a point uniform in the disk's area has
    r = sqrt(u0). The samples then bunch toward the normal: the message compares their share
    with sin(theta_i) < 0.5 with the integral of pdf there."""
    from scipy.stats import kstest

    n = _unit(np.array([0.3, -0.5, 0.8]))
    wo = _frame(n, np.array([0.6]), np.array([2.0]))[0]
    count = DENSITY_SAMPLES
    wos, ns = np.tile(wo, (count, 1)), np.tile(n, (count, 1))
    wi, _, _ = sample_on_walls(material, wos, ns, rng.random((count, 2)), rng)
    cos_theta = wi @ n
    if not (cos_theta > 0).all():
        return None
    sin_theta = np.sqrt(np.maximum(0.0, 1.0 - cos_theta * cos_theta))
    if kstest(sin_theta, "uniform").pvalue < RADIUS_P:
        return None
    edge = math.sqrt(3) / 2  # cos(theta_i) where sin(theta_i) = 0.5
    expected = _pdf_over_bands(Turned(material, rng), wo, n, np.array([edge, 1.0]))[0]
    return text("ch06.disk_radius_uniform", share=np.mean(cos_theta > edge), expected=expected)


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
    """``pdf_normalisation``, failing with the typical mistake the material shows
    (``known_mistake``) in place of the statistic's message where it shows one."""
    material = _material(module)
    try:
        return pdf_normalisation(material)
    except CheckFailed as failure:
        raise CheckFailed(known_mistake(material) or str(failure)) from None


def pdf_normalisation(material) -> str:
    """pdf is 0 below the surface (at every point of the grid below it, and at -n), integrates
    to 1 over the sphere, and is the density of the directions sample gives
    (``density_of_samples``): a pdf that integrates to 1 (a constant 1/(2 pi) above the
    surface) with a sample that always returns n is no density of sample's."""
    rng = grading_rng(63)
    material = Turned(material, rng)  # (see sample_on_walls)
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
    failure = density_misfit(material, wo, n, draw_samples(material, wo, n, rng))
    if failure is not None:
        raise CheckFailed(failure)


def draw_samples(material, wo: np.ndarray, n: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(DENSITY_SAMPLES, 3): ``material.sample`` for wo (3,) around n (3,), every row alike."""
    count = DENSITY_SAMPLES
    return _call(material, "sample", np.tile(wo, (count, 1)), np.tile(n, (count, 1)), rng.random((count, 2)))


def density_misfit(material, wo: np.ndarray, n: np.ndarray, wi: np.ndarray) -> str | None:
    """What ``density_of_samples`` says of the samples ``wi`` (``draw_samples``) of wo
    around n, or None where they follow pdf."""
    from ptlab.grading.checks import chi2_sf, pooled_chi_square

    count = len(wi)
    wos, ns = np.tile(wo, (count, 1)), np.tile(n, (count, 1))
    cos_theta = wi @ n
    landed = (_call(material, "pdf", wos, wi, ns, width=None) > 0) & (cos_theta > 0)
    band = np.minimum((cos_theta * DENSITY_BANDS).astype(np.intp), DENSITY_BANDS - 1)
    observed = np.append(np.bincount(band[landed], minlength=DENSITY_BANDS), (~landed).sum())
    share = _band_integrals(material, wo, n)
    expected = count * np.append(share, max(0.0, 1.0 - share.sum()))
    statistic, dof = pooled_chi_square(observed, expected)
    p = chi2_sf(statistic, dof)
    if p >= DENSITY_ALPHA:
        return None
    worst = int(np.argmax(np.abs(observed - expected) / np.sqrt(np.maximum(expected, 1.0))))
    shares = dict(yours=observed[worst] / count, expected=expected[worst] / count, p=p)
    if worst == DENSITY_BANDS:
        return text("ch06.pdf_not_density_fails", **shares)
    low, high = worst / DENSITY_BANDS, (worst + 1) / DENSITY_BANDS
    return text("ch06.pdf_not_density", low=low, high=high, **shares)


def _band_integrals(material, wo: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(DENSITY_BANDS,) the integral of pdf over each band of cos(theta) above the surface."""
    return _pdf_over_bands(material, wo, n, np.linspace(0, 1, DENSITY_BANDS + 1))


def _pdf_over_bands(
    material, wo: np.ndarray, n: np.ndarray, edges: np.ndarray, points: int = 40, cols: int = 16
) -> np.ndarray:
    """(len(edges) - 1,) the integral of pdf over each band edges[k] <= cos(theta) <
    edges[k + 1]: the midpoint rule in cos(theta) (the band's solid angle is
    d(cos theta) d(phi)), ``points`` x ``cols`` points a band."""
    low, width = edges[:-1, None], np.diff(edges)[:, None]
    mu = low + width * (np.arange(points) + 0.5) / points  # (bands, points)
    phi = (np.arange(cols) + 0.5) * 2 * math.pi / cols
    mu, phi = (a.ravel() for a in np.broadcast_arrays(mu[..., None], phi))
    w = _frame(n, np.arccos(mu), phi)
    rows = len(w)
    pdf = _call(material, "pdf", np.tile(wo, (rows, 1)), w, np.tile(n, (rows, 1)), width=None)
    cell = width * (2 * math.pi / (points * cols))  # (bands, 1): each point's solid angle
    return (pdf.reshape(len(low), -1) * cell).sum(axis=1)


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
    material,
    seed: int,
    what: str,
    grade_command: str,
    expected_eval: Callable | None = None,
    mistake: Callable[[], str | None] | None = None,
) -> str:
    """``ptlab.grading.check_material`` on the student's material; a ``CheckFailed`` that
    names each failed check with its hint (checks that failed alike, said once), ``what``
    the material was (a phrase after "the reflectance", in the active language: "" for
    chapter 6's) and the ``ptlab grade`` command that prints the whole table. With
    ``expected_eval``, the material's eval must first be it (``reflects_as_expected``), and
    the harness's warning that a material reflects nothing fails too (its other warnings,
    a float64 answer to float32 arguments, are for speed: they cost no points). Where the
    harness fails, ``mistake()`` (if given) may name the mistake from values of the
    chapter's own inputs: said in place of the harness's hints, which guess from its
    statistics."""
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
    failed, named = ", ".join(report.failed), mistake() if mistake is not None else None
    if named is not None:
        raise CheckFailed(
            text("ch06.harness_mistake", failed=failed, what=what, mistake=named, command=grade_command)
        )
    failures = _harness_hints(report)
    raise CheckFailed(
        text("ch06.harness_failed", failed=failed, what=what, failures=failures, command=grade_command)
    )


def _harness_hints(report) -> str:
    """The hints of the harness's failed checks, each said once with the checks that gave it."""
    by_hint: dict[str, list[str]] = {}
    for c in report.checks:
        if not c.passed:
            by_hint.setdefault(c.hint or c.statistic, []).append(c.name)
    return "; ".join(f"{', '.join(names)}: {hint}" for hint, names in by_hint.items())


def check_harness(module) -> str:
    albedo = np.asarray(ALBEDO) / math.pi

    def lambert(wo, wi, n):
        return np.broadcast_to(albedo, wo.shape)

    material = _material(module)
    return run_harness(
        material,
        grading_seed_for(6),
        "",
        f"ptlab grade {student_file(module)}:Lambertian",
        expected_eval=lambert,
        mistake=lambda: known_mistake(material),
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
    material = _material(module)
    probe(material)

    def hint() -> str:  # (what a brighter or darker picture means: asked only of one)
        return known_mistake(material) or text("ch06.hint.render")

    seed = grading_seed_for(RENDER_SEED)
    spp_per_pass = render_spp_per_pass(grading_rng(SPP_STREAM))
    library = library_render(
        ("ch06 render", seed, spp_per_pass), lambda: render_passes(seed=seed, spp_per_pass=spp_per_pass)
    )
    student = render_passes(lambda albedo: _material(module, albedo), seed, spp_per_pass=spp_per_pass)
    return compare_renders(student, library, text("ch06.yours"), hint=hint, spp=spp_per_pass)


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
