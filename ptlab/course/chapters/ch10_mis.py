"""Chapter 10's checks: multiple importance sampling (``balance_heuristic``,
``power_heuristic``, ``mis_weight``).

Known answers come from Veach's heuristics themselves (Veach 1997, section 9.2): the weights
of the two strategies for one sample sum to 1, a strategy that cannot draw a sample (pdf 0,
as a mirror's BSDF for a light sample) leaves it all to the other, and nothing is NaN. Then
the student's ``mis_weight`` is the path tracer's piece (``PathPieces``: ``ptlab.integrators.path``
calls it for both strategies: light samples in ``direct_light``, BSDF-sampled hits of a
light in ``add_emission``) and ``veach-mis`` rendered with ``strategy="mis"`` must match
the library's picture: exactly, up to rounding, since the weights change no path.

The densities reach the range where they are hard: from 0 to 10^30, in float32 (the
renderer's) and float64. A light seen nearly edge-on has pdf_light = pdf_area |x - x'|^2 /
cos(theta') in the billions and more, and in float32 pdf^2 overflows above about 1.8e19
(``SQUARE_OVERFLOW``), where p^2 / (p^2 + q^2) is inf / inf = NaN: the known values and the
sums to 1 are tried with such densities too, and a NaN or a wrong weight among them is said
to be the overflow. So each pitfall of the page (docs/10-mis.md) is a case the checks try:
double counting and the argument order ("weights sum to 1"), 0 / 0 and a strategy that
cannot draw the sample ("zero and delta pdfs"), overflow ("power heuristic", "weights sum
to 1"). Every check is deterministic (inputs from the grading seed, answers exact up to
rounding): false-alarm rate 0 at any grading seed (tests/exercises/10_right_own_code.py
passes every check at 1000 grading seeds, the render at 100: ``python
scripts/check_seeds.py --seeds 1000 --chapter 10``).
"""

from __future__ import annotations

import math

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
from ptlab.course.finite import at_pixel, require_finite
from ptlab.course.messages import aside, check_name, text
from ptlab.integrators.path import PathPieces
from ptlab.rendering.pieces import Pieces

#: Above this density its square overflows float32 (the square root of float32's largest
#: number, 3.4e38): p^2 / (p^2 + q^2) is then inf / inf = NaN, or 0 where it should be 1.
SQUARE_OVERFLOW = math.sqrt(float(np.finfo(np.float32).max))
#: The float types the densities are tried in: the renderer's float32, and float64.
DTYPES = (np.float32, np.float64)


def _weights(function, pdf, other, *heuristic, dtype=np.float32) -> np.ndarray:
    """``function(pdf, other, *heuristic)`` on densities of ``dtype``, as float64, checked
    for shape and NaN."""
    pdf, other = np.array(pdf, dtype=dtype), np.array(other, dtype=dtype)
    with np.errstate(all="ignore"):
        weight = np.asarray(function(pdf.copy(), other.copy(), *heuristic), dtype=np.float64)
    name = function.__name__ + (f"(..., {heuristic[0]!r})" if heuristic else "")
    if weight.shape != pdf.shape:
        raise CheckFailed(text("ch10.shape", name=name, expected=pdf.shape, shape=weight.shape))
    if np.isnan(weight).any():
        bad = np.flatnonzero(np.isnan(weight))[0]
        hint = _overflow_hint(pdf[bad], other[bad])
        if pdf[bad] == 0 and other[bad] == 0:
            hint = aside(text("ch10.hint.both_zero"))
        raise CheckFailed(text("ch10.nan", name=name, pdf=pdf[bad], other=other[bad], dtype=pdf.dtype) + hint)
    if np.isinf(weight).any():
        bad = np.flatnonzero(np.isinf(weight))[0]
        raise CheckFailed(text("ch10.inf", name=name, weight=weight[bad], pdf=pdf[bad], other=other[bad]))
    return weight


def _overflow_hint(pdf: np.floating, other: np.floating) -> str:
    """The overflow pitfall, if a weight went wrong at ``pdf`` and ``other`` where a square
    overflows float32 (else "")."""
    if max(float(pdf), float(other)) <= SQUARE_OVERFLOW:
        return ""
    return aside(text("ch10.hint.overflow", limit=SQUARE_OVERFLOW))


def _scale(stream: int) -> float:
    """A factor for both pdfs of a known case, from the grading seed: the heuristics depend
    on their ratio only, so the answers stay, and the inputs are new for every grading."""
    return float(grading_rng(stream).uniform(0.25, 4))


def _known_values(function, cases, formula: str) -> str:
    pdf, other, expected = (np.array(column, dtype=np.float64) for column in zip(*cases, strict=True))
    scale = _scale(100)
    pdf, other = pdf * scale, other * scale
    for dtype in DTYPES:
        weight = _weights(function, pdf, other, dtype=dtype)
        wrong = np.flatnonzero(~(np.abs(weight - expected) <= 1e-5))
        if len(wrong):
            k = wrong[0]
            raise CheckFailed(
                text(
                    "ch10.known",
                    name=function.__name__,
                    pdf=pdf[k],
                    other=other[k],
                    dtype=np.dtype(dtype),
                    formula=formula,
                    expected=expected[k],
                    yours=weight[k],
                )
                + (
                    (dtype is np.float32 and _overflow_hint(pdf[k], other[k]))
                    or _known_epsilon_hint(function, dtype)
                )
            )
    return text("ch10.known_ok", n=len(cases), formula=formula)


def check_balance(module) -> str:
    (balance_heuristic,) = require(module, "balance_heuristic")
    cases = [
        (1, 1, 0.5),
        (3, 1, 0.75),
        (1, 3, 0.25),
        (0.2, 0.6, 0.25),
        (2, 0, 1.0),
        (1e4, 1, 1e4 / (1e4 + 1)),
        (3e29, 1e29, 0.75),
    ]
    return _known_values(balance_heuristic, cases, "pdf / (pdf + other)")


def check_power(module) -> str:
    (power_heuristic,) = require(module, "power_heuristic")
    cases = [
        (1, 1, 0.5),
        (3, 1, 0.9),
        (1, 3, 0.1),
        (2, 1, 0.8),
        (0.5, 1.5, 0.1),
        (2, 0, 1.0),
        (100, 1, 1e4 / (1e4 + 1)),
        # Past float32's square (SQUARE_OVERFLOW): a light seen nearly edge-on.
        (3e20, 1e20, 0.9),
        (1e29, 1e-3, 1.0),
    ]
    return _known_values(power_heuristic, cases, "pdf^2 / (pdf^2 + other^2)")


def check_sum_to_one(module) -> str:
    (mis_weight,) = require(module, "mis_weight")
    rng = grading_rng(101)
    pdf_light, pdf_bsdf = 10.0 ** rng.uniform(-3, 4, (2, 1000))
    # Then densities up to 10^30 (a light seen nearly edge-on), each pair within 10^3 of each
    # other, so that both weights are far from 0 and 1 where the squares overflow float32.
    large = 10.0 ** rng.uniform(4, 30, 500)
    pdf_light = np.concatenate([pdf_light, large])
    pdf_bsdf = np.concatenate([pdf_bsdf, large * 10.0 ** rng.uniform(-3, 3, 500)])
    for heuristic in ("power", "balance"):
        for dtype in DTYPES:
            _sum_to_one(mis_weight, heuristic, pdf_light, pdf_bsdf, dtype)
    return text("ch10.sum_ok", n=len(pdf_light))


def _sum_to_one(mis_weight, heuristic: str, pdf_light: np.ndarray, pdf_bsdf: np.ndarray, dtype) -> None:
    """``mis_weight``'s two weights of each pair of densities, in ``dtype``: do they add up to
    1, and are they the ``heuristic``? Else ``CheckFailed``, naming the likely mistake."""
    expected = _heuristic(heuristic, pdf_light, pdf_bsdf)
    light = _weights(mis_weight, pdf_light, pdf_bsdf, heuristic, dtype=dtype)
    bsdf = _weights(mis_weight, pdf_bsdf, pdf_light, heuristic, dtype=dtype)
    total = light + bsdf
    worst = np.argmax(np.abs(total - 1))
    if not abs(total[worst] - 1) <= 1e-5:
        hint = _overflow_hint(pdf_light[worst], pdf_bsdf[worst]) if dtype is np.float32 else ""
        if np.allclose(total, 2, atol=1e-5):
            hint = text("ch10.hint.both_one")
        elif np.allclose(total, 0, atol=1e-5):
            hint = text("ch10.hint.both_zero_weights")
        elif not hint:
            hint = _short_of_one_hint(
                heuristic, pdf_light.astype(dtype), pdf_bsdf.astype(dtype), total, int(worst)
            )
        raise CheckFailed(
            text(
                "ch10.sum",
                heuristic=repr(heuristic),
                pdf_light=pdf_light[worst],
                pdf_bsdf=pdf_bsdf[worst],
                dtype=np.dtype(dtype),
                total=total[worst],
                hint=hint,
            )
        )
    right = np.isclose(light, expected, rtol=1e-4, atol=1e-6)
    if right.all():
        return
    other_heuristic = "balance" if heuristic == "power" else "power"
    if np.allclose(light, _heuristic(heuristic, pdf_bsdf, pdf_light), rtol=1e-4, atol=1e-6):
        hint = text("ch10.hint.order", heuristic=text(f"ch10.{heuristic}"))
    elif np.allclose(light, _heuristic(other_heuristic, pdf_light, pdf_bsdf), rtol=1e-4, atol=1e-6):
        hint = text("ch10.hint.other_heuristic", heuristic=text(f"ch10.{other_heuristic}"))
    elif dtype is np.float32 and (np.maximum(pdf_light, pdf_bsdf)[~right] > SQUARE_OVERFLOW).all():
        hint = text("ch10.hint.overflow", limit=SQUARE_OVERFLOW)
    else:
        hint = text("ch10.hint.other_values")
    raise CheckFailed(
        text("ch10.heuristic", name=repr(heuristic), heuristic=text(f"ch10.{heuristic}"), hint=hint)
    )


#: How far from 1 rounding takes the total of two float32 weights that add up to 1.
ROUNDING = 1e-6
#: Pairs whose weights fall short of 1 by less than this say little of how much they do.
MEASURABLE_SHORTFALL = 1e-5
#: Each heuristic with a constant eps added to its denominator, and its denominator without.
WITH_EPSILON = {"power": "pdf^2 / (pdf^2 + other^2 + eps)", "balance": "pdf / (pdf + other + eps)"}
DENOMINATOR = {"power": "pdf^2 + other^2", "balance": "pdf + other"}


def _short_of_one_hint(
    heuristic: str, pdf_light: np.ndarray, pdf_bsdf: np.ndarray, total: np.ndarray, shown: int
) -> str:
    """Why the two weights of each pair add up to ``total``, less than 1, if a constant
    added to the heuristic's denominator explains it (``_epsilon_fit``). The hint names eps,
    the ``shown`` pair, and beside it the pair of the largest densities whose shortfall is
    measurable; else ""."""
    fit = _epsilon_fit(heuristic, pdf_light, pdf_bsdf, total)
    if fit is None:
        return ""
    eps, scaled, large = fit
    p, q = pdf_light.astype(np.float64), pdf_bsdf.astype(np.float64)
    return text(
        "ch10.hint.epsilon_scaled" if scaled else "ch10.hint.epsilon",
        eps=eps,
        short=1 - total[shown],
        light_large=p[large],
        bsdf_large=q[large],
        short_large=1 - total[large],
        formula=WITH_EPSILON[heuristic],
        sum=DENOMINATOR[heuristic],
    )


def _epsilon_fit(
    heuristic: str, pdf_light: np.ndarray, pdf_bsdf: np.ndarray, total: np.ndarray
) -> tuple[float, bool, int] | None:
    """(eps, scaled, large) if a constant added to the heuristic's denominator explains why
    the two weights of each pair add up to ``total``, less than 1 (an epsilon against 0 / 0):
    then w = p^k / (p^k + q^k + eps) and the pair's total is S / (S + eps), S = p^k + q^k
    (k = 2 for the power heuristic, 1 for the balance), so (1 / total - 1) S is eps at every
    pair, and the shortfall is largest where the densities are small. S is tried as the
    densities are, and divided by the larger first (``scaled``, the way round overflow).
    ``large`` is the pair of the largest densities whose shortfall is measurable. Else None."""
    if not ((total <= 1 + ROUNDING) & (total > 0)).all():
        return None
    p, q = pdf_light.astype(np.float64), pdf_bsdf.astype(np.float64)
    k = 2 if heuristic == "power" else 1
    measured = 1 - total > MEASURABLE_SHORTFALL
    larger = np.maximum(p, q)
    for scaled, scale in ((False, 1.0), (True, larger)):
        sums = (p / scale) ** k + (q / scale) ** k
        eps = (1 / total - 1)[measured] * np.broadcast_to(sums, p.shape)[measured]
        if measured.sum() >= 3 and eps.max() <= 1.2 * eps.min():
            large = int(np.argmax(np.where(measured, larger, -1)))  # (the largest densities measured)
            return float(np.median(eps)), scaled, large
    return None


#: Densities at which a heuristic whose known values are wrong is tried with both orders of
#: its arguments, to see whether an epsilon in its denominator explains them: from 10^-4
#: (where even eps = 10^-9 in the power heuristic's denominator shows) to 10^4, unequal pairs.
PROBES = 10.0 ** np.linspace(-4, 4, 33)
PROBE_RATIOS = np.resize([1.0, 0.3, 3.0], len(PROBES))


def _known_epsilon_hint(function, dtype) -> str:
    """The hint for a heuristic whose known values are wrong, if it is the heuristic with a
    constant added to its denominator: f(p, q) + f(q, p) then falls short of 1 as
    ``_epsilon_fit`` says (else "")."""
    heuristic = "power" if function.__name__ == "power_heuristic" else "balance"
    pdf, other = PROBES, PROBES * PROBE_RATIOS
    try:
        total = _weights(function, pdf, other, dtype=dtype) + _weights(function, other, pdf, dtype=dtype)
    except CheckFailed:  # (a NaN here: no epsilon, then)
        return ""
    fit = _epsilon_fit(heuristic, pdf.astype(dtype), other.astype(dtype), total)
    if fit is None:
        return ""
    eps, scaled, _ = fit
    return aside(
        text(
            "ch10.hint.known_epsilon_scaled" if scaled else "ch10.hint.known_epsilon",
            name=function.__name__,
            eps=eps,
            formula=WITH_EPSILON[heuristic],
            sum=DENOMINATOR[heuristic],
        )
    )


def _heuristic(name: str, pdf: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Veach's power (beta = 2) or balance heuristic, for float64 densities that are not
    both 0 (and below 10^150, whose squares float64 holds)."""
    if name == "power":
        return pdf**2 / (pdf**2 + other**2)
    return pdf / (pdf + other)


def check_zero_pdfs(module) -> str:
    (mis_weight,) = require(module, "mis_weight")
    pdf = np.array([2.0, 0.0, 0.0, 5000.0, 0.0]) * _scale(102)
    other = np.array([0.0, 3.0, 0.0, 0.0, 5000.0]) * _scale(102)
    expected = np.array([1.0, 0.0, 0.0, 1.0, 0.0])
    for heuristic in ("power", "balance"):
        for dtype in DTYPES:
            weight = _weights(mis_weight, pdf, other, heuristic, dtype=dtype)
            wrong = np.flatnonzero(~(np.abs(weight - expected) <= 1e-6))
            if len(wrong):
                k = wrong[0]
                raise CheckFailed(
                    text(
                        "ch10.zero",
                        pdf=pdf[k],
                        other=other[k],
                        heuristic=repr(heuristic),
                        dtype=np.dtype(dtype),
                        expected=expected[k],
                        yours=weight[k],
                        why=_zero_why(pdf[k], other[k], weight[:2], expected[1::-1])
                        + _zero_short(weight[k], expected[k]),
                    )
                )
    return text("ch10.zero_ok")


def _zero_why(pdf: float, other: float, first_two: np.ndarray, swapped: np.ndarray) -> str:
    """Why the weight at ``pdf`` and ``other`` (one of them 0, or both) is what it must be;
    with a hint if the first two weights are each other's (``swapped``)."""
    why = text(
        "ch10.why.other_zero"
        if other == 0 and pdf > 0
        else "ch10.why.this_zero"
        if pdf == 0 and other > 0
        else "ch10.why.both_zero"
    )
    if np.array_equal(first_two, swapped):
        why += aside(text("ch10.hint.swapped"))
    return why


def _zero_short(weight: float, expected: float) -> str:
    """The hint for a weight that should be 1 and falls a little short (a constant added to
    the heuristic's denominator, as "weights sum to 1" shows), else ""."""
    if expected == 1 and 0 < 1 - weight < 0.01:
        return aside(text("ch10.hint.zero_short", short=1 - weight))
    return ""


def render_options(seed: int) -> dict:
    """The render both sides of chapter 10's comparison make: 32 x 32, 32 spp, paths of up
    to 3 bounces (MIS acts on every bounce alike; more bounces only cost time)."""
    return dict(res=32, spp=32, seed=seed, max_depth=3, strategy="mis", workers=1)


def veach_scene():
    """``veach-mis``, the scene MIS was made for (Veach 1997, figure 9.2)."""
    import ptlab

    return ptlab.load_scene("veach-mis")


#: The MIS weights change what each path adds, never where it goes, so with the same seed
#: the student's render and the library's trace the very same paths: a right answer differs
#: by rounding only (measured: below 1e-6). Each region must agree to this relative tolerance
#: (of its value plus a tenth of the image's mean): a deterministic check, false-alarm rate 0.
TOLERANCE = 1e-3


def _checked_mis_weight(module):
    """The student's ``mis_weight``, as the path tracer looks it up, its weights checked."""
    (mis_weight,) = require(module, "mis_weight")
    _weights(mis_weight, np.array([1.0, 2.0]), np.array([1.0, 0.5]), "power")  # fail fast

    def checked_mis_weight(pdf, other, heuristic="power"):
        """The student's weights, failing on NaN or inf with the pdfs that gave them (the
        film would drop such samples without a word, and the picture come out darker)."""
        pdf, other = np.broadcast_arrays(pdf, other)
        return _weights(mis_weight, pdf, other, heuristic).astype(np.float32)

    return checked_mis_weight


def check_render(module) -> str:
    import ptlab
    from ptlab.course.renders import describe_region, library_render, regions_of

    checked_mis_weight = _checked_mis_weight(module)
    scene = veach_scene()
    options = render_options(grading_seed_for(10))
    library_image = library_render(
        ("ch10 render", *sorted(options.items())), lambda: ptlab.render(scene, **options)
    )
    library = regions_of(library_image.astype(np.float64))
    image = ptlab.render(scene, **options, pieces=_with_weights(checked_mis_weight))
    require_finite(image, text("ch10.yours"), at_pixel)
    student = regions_of(image.astype(np.float64))
    difference = np.abs(student - library)
    allowed = TOLERANCE * (library + 0.1 * library.mean())
    overall = student.mean() / library.mean()
    if not (difference <= allowed).all():
        from ptlab.course.inspect_command import suggestion

        worst = np.unravel_index(np.argmax(difference / allowed), difference.shape)
        ratio = student[worst] / max(library[worst], 1e-12)
        raise CheckFailed(
            text(
                "ch10.render",
                region=describe_region(*map(int, worst)),
                ratio=ratio,
                overall=overall,
                check=check_name(10, "weights sum to 1"),
            )
            + suggestion(10, image, library_image, options["seed"])
        )
    return text("ch10.render_ok", overall=overall)


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered with MIS weighted by the student's ``mis_weight`` (``ptlab
    exercise render``)."""
    from ptlab.course.side_by_side import render_with_pieces

    return render_with_pieces(scene, options, _with_weights(_checked_mis_weight(module)))


def _with_weights(mis_weight) -> Pieces:
    """A render's pieces with ``mis_weight`` weighing the path tracer's two strategies."""
    return Pieces(path=PathPieces(mis_weight=mis_weight))


CHAPTER = Chapter(
    number=10,
    slug="mis",
    title="Multiple importance sampling",
    functions=("balance_heuristic", "power_heuristic", "mis_weight"),
    answers=("ptlab.integrators.path.mis_weight",),
    # The path tracer weighs its light and BSDF samples with the same heuristics.
    also_left_out=(
        "ptlab.integrators.path.direct_light",
        "ptlab.integrators.path.add_emission",
        "ptlab.inspector",
    ),
    checks=(
        ChapterCheck("balance heuristic", 2, check_balance, timeout=30),
        ChapterCheck("power heuristic", 2, check_power, timeout=30),
        ChapterCheck("weights sum to 1", 2, check_sum_to_one, timeout=30),
        ChapterCheck("zero and delta pdfs", 2, check_zero_pdfs, timeout=30),
        ChapterCheck("render", 2, check_render, timeout=60),
    ),
    render=ChapterRender(render_yours, scene="veach-mis", options=dict(strategy="mis")),
)
