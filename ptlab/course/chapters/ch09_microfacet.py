"""Chapter 9's checks: microfacet materials (GGX ``D``, Smith ``G1``/``G2``, Fresnel-Schlick,
the ``GGXMetal`` material and its importance sampling).

Known answers come from the formulas (D is normalised: the integral of D(h) cos(theta_h) over
the hemisphere is 1, and D(n) = 1 / (pi alpha^2); G1(n) = 1 and 0 <= G1 <= 1; F(0 degrees)
= F0, F(90 degrees) = 1) and from the library's own ``ptlab.materials.microfacet``. Then
the material harness and a render of ``cornell-box-microfacet`` with the student's metal in
place of the library's, in two steps: with the cosine hemisphere sampling the exercise file
already has (it tests ``eval``), then with the student's importance sampling.
"""

from __future__ import annotations

import json
import math
import shlex
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
from ptlab.course.chapters.ch06_diffuse import _frame, probe, random_pairs, render_spp_per_pass, run_harness
from ptlab.course.finite import finite_array
from ptlab.course.messages import aside, text
from ptlab.course.renders import compare_renders, library_render, pass_images, replace_materials
from ptlab.grading.probes import Turned
from ptlab.rendering.sizes import SPP_PER_PASS
from ptlab.sampling import to_world
from ptlab.vectors import normalize

ALPHAS = (0.05, 0.2, 0.5, 1.0)
GOLD = (1.0, 0.782, 0.344)


def _values(function, *arguments, shape) -> np.ndarray:
    """``function(*arguments)`` as float64, checked for shape and finiteness (the row of the
    first NaN is named). The function gets copies: the check's arrays stay its own."""
    return finite_array(function(*(np.array(a) for a in arguments)), function.__name__, shape)


def _alphas(stream: int, alphas) -> tuple[float, ...]:
    """``alphas``, each moved by up to 5% by the grading seed (rounded to 4 decimals, to
    read well in a message): the checks' inputs are new for every grading. Never above 1:
    alpha is in (0, 1] (the exercise file, ``Microfacet``), so 1 moves down only."""
    rng = grading_rng(stream)
    return tuple(round(float(a * rng.uniform(0.95, min(1.05, 1 / a))), 4) for a in alphas)


def check_d(module) -> str:
    (D,) = require(module, "D")  # noqa: N806 (the papers' name)
    # The integral over the hemisphere of D(h) cos(theta_h) d omega is 2 pi times the one of
    # D(mu) mu over mu = cos(theta_h) in [0, 1]; D peaks at mu = 1 within about alpha^2, so
    # the trapezoids are spaced geometrically in 1 - mu.
    x = np.concatenate([[0.0], np.geomspace(1e-14, 1.0, 20001)])
    mu = 1.0 - x
    alphas = _alphas(93, ALPHAS)
    for alpha in alphas:
        at_normal = _values(D, np.array([1.0]), alpha, shape=(1,))[0]
        expected = 1 / (math.pi * alpha * alpha)
        if not math.isclose(at_normal, expected, rel_tol=1e-4):
            hint = ""
            if math.isclose(at_normal, 1 / (math.pi * alpha), rel_tol=1e-3):
                hint = aside(text("ch09.hint.alpha"))
            elif math.isclose(at_normal, 1 / (alpha * alpha), rel_tol=1e-3):
                hint = aside(text("ch09.hint.pi"))
            raise CheckFailed(text("ch09.d_normal", alpha=alpha, expected=expected, yours=at_normal) + hint)
        total = float(np.trapezoid(_values(D, mu, alpha, shape=mu.shape) * mu * 2 * math.pi, x))
        if abs(total - 1) > 1e-3:
            raise CheckFailed(text("ch09.d_integral", alpha=alpha, total=total))
    return text("ch09.d_ok", alphas=", ".join(map(str, alphas)))


def check_g(module) -> str:
    from ptlab.materials import microfacet as library

    G1, G2 = require(module, "G1", "G2")  # noqa: N806 (the papers' names)
    cos_theta = np.concatenate([[1.0, 1e-6], np.sort(grading_rng(94).uniform(0.01, 0.99, 99))])
    for alpha in _alphas(95, (0.1, 0.5, 1.0)):
        expected = library.G1(cos_theta, alpha)
        g1 = _values(G1, cos_theta, alpha, shape=cos_theta.shape)
        if not math.isclose(g1[0], 1.0, rel_tol=1e-6):
            raise CheckFailed(text("ch09.g1_normal", yours=g1[0], alpha=alpha))
        if (g1 < 0).any() or (g1 > 1 + 1e-9).any():
            raise CheckFailed(text("ch09.g1_range", high=g1.max(), low=g1.min(), alpha=alpha))
        worst = np.argmax(np.abs(g1 - expected) / expected)
        if not abs(g1[worst] - expected[worst]) <= 1e-4 * expected[worst]:
            mistake = _lambda_mistake(g1, _masking(cos_theta, alpha))
            message = "ch09.g1_lambda" if mistake else "ch09.g1"
            cause = text(mistake) if mistake else ""
            raise CheckFailed(
                text(
                    message,
                    cos=cos_theta[worst],
                    alpha=alpha,
                    yours=g1[worst],
                    expected=expected[worst],
                    cause=cause,
                )
            )
    rng = grading_rng(91)
    cos_o, cos_i = rng.uniform(0.02, 1, 200), rng.uniform(0.02, 1, 200)
    expected = library.G2(cos_o, cos_i, 0.4)
    g2 = _values(G2, cos_o, cos_i, 0.4, shape=cos_o.shape)
    if not np.allclose(g2, expected, rtol=1e-4):
        separable = library.G1(cos_o, 0.4) * library.G1(cos_i, 0.4)
        if np.allclose(g2, separable, rtol=1e-4):
            raise CheckFailed(text("ch09.g2_separable"))
        worst = np.argmax(np.abs(g2 - expected))
        mistake = _lambda_mistake(g2, _height_correlated(cos_o, cos_i, 0.4))
        raise CheckFailed(
            text(
                "ch09.g2_lambda" if mistake else "ch09.g2",
                cos_o=cos_o[worst],
                cos_i=cos_i[worst],
                yours=g2[worst],
                expected=expected[worst],
                cause=text(mistake) if mistake else "",
            )
        )
    return text("ch09.g_ok")


def _tan2(cos_theta: np.ndarray) -> np.ndarray:
    """tan^2(theta) = (1 - cos^2(theta)) / cos^2(theta)."""
    cos2 = cos_theta * cos_theta
    return (1 - cos2) / cos2


#: One typical mistake at a time in Smith's Lambda = (sqrt(1 + alpha^2 tan^2(theta)) - 1) / 2
#: (Heitz 2014, eq. 72), as ``Lambda(tan^2(theta), alpha)``, with the id of the hint that
#: names it. The same wrong Lambda then spoils G1, G2 and eval alike.
WRONG_LAMBDAS: tuple[tuple[str, Callable], ...] = (
    ("ch09.lambda.alpha", lambda tan2, alpha: (np.sqrt(1 + alpha * tan2) - 1) / 2),
    ("ch09.lambda.alpha4", lambda tan2, alpha: (np.sqrt(1 + alpha**4 * tan2) - 1) / 2),
    ("ch09.lambda.no_half", lambda tan2, alpha: np.sqrt(1 + alpha**2 * tan2) - 1),
    ("ch09.lambda.tan", lambda tan2, alpha: (np.sqrt(1 + alpha**2 * np.sqrt(tan2)) - 1) / 2),
)


def _masking(cos_theta: np.ndarray, alpha: float) -> Callable:
    """``Lambda -> G1 = 1 / (1 + Lambda)`` at ``cos_theta``, for ``_lambda_mistake``."""
    return lambda lam: 1 / (1 + lam(_tan2(cos_theta), alpha))


def _height_correlated(cos_o: np.ndarray, cos_i: np.ndarray, alpha: float) -> Callable:
    """``Lambda -> G2 = 1 / (1 + Lambda(wo) + Lambda(wi))``, for ``_lambda_mistake``."""
    return lambda lam: 1 / (1 + lam(_tan2(cos_o), alpha) + lam(_tan2(cos_i), alpha))


def _lambda_mistake(values: np.ndarray, form: Callable) -> str:
    """The id of the ``WRONG_LAMBDAS`` mistake with which ``form`` (a wrong Lambda -> G)
    gives ``values``; "" if none does."""
    for message, wrong in WRONG_LAMBDAS:
        if np.allclose(values, form(wrong), rtol=1e-3, atol=1e-9):
            return message
    return ""


def check_fresnel(module) -> str:
    (fresnel_schlick,) = require(module, "fresnel_schlick")
    cos_theta = np.array([1.0, 0.0, 0.5, 0.2])
    f0 = np.array(GOLD)
    expected = f0 + (1 - f0) * (1 - cos_theta[2:, None]) ** 5
    F = _values(fresnel_schlick, cos_theta, f0, shape=(4, 3))  # noqa: N806
    if not np.allclose(F[0], f0, rtol=1e-6):
        raise CheckFailed(text("ch09.f_normal", f0=GOLD, yours=np.round(F[0], 4)))
    if not np.allclose(F[1], 1.0, rtol=1e-6):
        raise CheckFailed(text("ch09.f_grazing", yours=np.round(F[1], 4)))
    if not np.allclose(F[2:], expected, rtol=1e-6):
        raise CheckFailed(text("ch09.f_half", expected=np.round(expected[0], 5), yours=np.round(F[2], 5)))
    return text("ch09.f_ok")


def _metal(module, f0=GOLD, alpha=0.3, sampling="ggx"):
    (GGXMetal,) = require(module, "GGXMetal")  # noqa: N806 (a class)
    return GGXMetal(f0, alpha, sampling)


#: The alpha of the gold metal whose eval the eval check compares with the library's.
EVAL_ALPHA = 0.3


def check_eval(module) -> str:
    mismatch = _eval_mismatch(module)
    if mismatch is not None:
        error, hint, _ = mismatch
        raise CheckFailed(text("ch09.eval", error=error, hint=hint or text("ch09.hint.formula")))
    wo, wi, n = random_pairs(grading_rng(92), 2000)
    below = _values(_metal(module).eval, wo, -wi, n, shape=wo.shape)
    if np.abs(below).max() > 0:
        raise CheckFailed(text("ch09.eval_below"))
    return text("ch09.eval_ok")


def _eval_mismatch(module) -> tuple[float, str, str] | None:
    """None if the student's eval is the GGX BRDF for gold (alpha ``EVAL_ALPHA``) on 2000
    random pairs of directions; else its largest difference from it, the hint that names
    the mistake and the id of the term it is in ("" and "" if no known mistake fits)."""
    from ptlab.materials import Microfacet

    material = _metal(module)
    rng = grading_rng(92)
    wo, wi, n = random_pairs(rng, 2000)
    expected = Microfacet(GOLD, alpha=EVAL_ALPHA).eval(wo, wi, n)
    f = _values(material.eval, wo, wi, n, shape=wo.shape)
    if np.allclose(f, expected, rtol=1e-4, atol=1e-9):
        return None
    hint, term = _eval_hint(module, f, wo, wi, n, EVAL_ALPHA)
    if not hint:
        hint = _half_vector_hint(
            material.eval, f, [_brdf_of(EVAL_ALPHA)], (wo, wi, n), rng, text("ch09.f_red")
        )
        term = "ch09.term.h" if hint else ""
    return float(np.abs(f - expected).max()), hint, term


def _eval_hint(module, f: np.ndarray, wo, wi, n, alpha: float) -> tuple[str, str]:
    """Which term of D G2 F / (4 cos_theta_o cos_theta_i) the student's ``f`` has wrong: the
    BRDF is rebuilt with one typical mistake at a time, and the one that ``f`` equals named:
    its hint and the id of its term ("" and "" if none; ``_g_term_hint`` for the G terms
    of the student's own G1 and G2, or with a wrong Lambda)."""
    from ptlab.materials import microfacet as library

    h = wo + wi
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    cos_o, cos_i, cos_h = (np.sum(a * n, axis=1) for a in (wo, wi, h))
    cos_d = np.sum(wo * h, axis=1)
    f0 = np.asarray(GOLD)
    D, G2, F = library.D(cos_h, alpha), library.G2(cos_o, cos_i, alpha), library.F_schlick(cos_d, f0)  # noqa: N806
    rest = (D * G2 / (4 * cos_o * cos_i))[:, None]
    mistakes = [
        (F * rest * cos_i[:, None], "ch09.hint.cosine", "ch09.term.cosine"),
        (4 * F * rest, "ch09.hint.four_missing", "ch09.term.four"),
        (F * rest / 4, "ch09.hint.four_more", "ch09.term.four"),
        (library.F_schlick(cos_i, f0) * rest, "ch09.hint.f_at_wi", "ch09.term.f"),
        (library.F_schlick(cos_o, f0) * rest, "ch09.hint.f_at_wo", "ch09.term.f"),
        (library.F_schlick(cos_h, f0) * rest, "ch09.hint.f_at_h", "ch09.term.f"),
        (np.broadcast_to(f0, F.shape) * rest, "ch09.hint.f_constant", "ch09.term.f"),
        (rest * np.ones(3), "ch09.hint.f_missing", "ch09.term.f"),
        (
            F * rest * (library.G1(cos_o, alpha) * library.G1(cos_i, alpha) / G2)[:, None],
            "ch09.hint.g_separable",
            "ch09.term.g",
        ),
        (F * rest * (library.G1(cos_o, alpha) / G2)[:, None], "ch09.hint.g1_alone", "ch09.term.g"),
        (F * rest / G2[:, None], "ch09.hint.g_missing", "ch09.term.g"),
        (F * rest * (library.D(cos_h, alpha * alpha) / D)[:, None], "ch09.hint.alpha4", "ch09.term.d"),
        (F * rest * (library.D(cos_h, math.sqrt(alpha)) / D)[:, None], "ch09.hint.alpha1", "ch09.term.d"),
    ]
    for value, hint, term in mistakes:
        if np.allclose(f, value, rtol=1e-3, atol=1e-9):
            return text(hint, at=text("ch09.hint.schlick_angle")), term
    hint = _g_term_hint(module, f, F * rest / G2[:, None], (cos_o, cos_i), G2, alpha)
    return hint, "ch09.term.g" if hint else ""


def _g_term_hint(module, f: np.ndarray, without_g: np.ndarray, cosines, g2: np.ndarray, alpha: float) -> str:
    """If the student's eval ``f`` is ``without_g`` (D F / (4 cos_theta_o cos_theta_i), (N,
    3)) times a G other than Smith's height-correlated ``g2`` (N,): the student's own G2,
    its G1(wo) G1(wi), or G2 with one of the ``WRONG_LAMBDAS``, the hint that names it,
    where it is furthest off and why; else ""."""
    cos_o, cos_i = cosines
    height_correlated = _height_correlated(cos_o, cos_i, alpha)
    candidates, g2_right = _own_g_terms(module, cos_o, cos_i, alpha, g2)
    # (a G2 of its own, where the student's is right: eval does not call it)
    own_lambda = "ch09.g_form.not_yours" if g2_right else "ch09.g_form.lambda"
    candidates += [(height_correlated(wrong), own_lambda, mistake) for mistake, wrong in WRONG_LAMBDAS]
    for g, form, cause in candidates:
        # (a G that is 0 would make any eval of 0 fit, whatever its D and F)
        if (g > 0).all() and np.allclose(f, without_g * g[:, None], rtol=1e-3, atol=1e-9):
            row = int(np.argmax(np.abs(g - g2) / g2))
            return text(
                "ch09.hint.g_term",
                form=text(form),
                cos_o=cos_o[row],
                cos_i=cos_i[row],
                yours=g[row],
                expected=g2[row],
                cause=text(cause),
            )
    return ""


def _own_g_terms(module, cos_o: np.ndarray, cos_i: np.ndarray, alpha: float, g2: np.ndarray):
    """The G terms that the student's own G2 and G1 give where they differ from Smith's
    (``g2``), each as (G (N,), id of its form, id of its cause) for ``_g_term_hint``, and
    whether the student's G2 is right ([] and False where they are missing or cannot
    answer)."""
    from ptlab.course.sandbox import StudentError
    from ptlab.materials import microfacet as library

    try:
        G1, G2 = require(module, "G1", "G2")  # noqa: N806 (the papers' names)
        yours = _values(G2, cos_o, cos_i, alpha, shape=cos_o.shape)
        g1_o = _values(G1, cos_o, alpha, shape=cos_o.shape)
        g1_i = _values(G1, cos_i, alpha, shape=cos_i.shape)
    except (CheckFailed, StudentError):
        return [], False
    terms = []
    if not np.allclose(yours, g2, rtol=1e-4):
        cause = _lambda_mistake(yours, _height_correlated(cos_o, cos_i, alpha)) or "ch09.lambda.yours"
        terms.append((yours, "ch09.g_form.g2", cause))
    if not np.allclose(g1_o, library.G1(cos_o, alpha), rtol=1e-4):
        cause = _lambda_mistake(g1_o, _masking(cos_o, alpha)) or "ch09.lambda.yours_g1"
        terms.append((g1_o * g1_i, "ch09.g_form.g1g1", cause))
    return terms, bool(np.allclose(yours, g2, rtol=1e-4))


def _brdf_of(alpha: float, f0=GOLD) -> Callable:
    """The GGX BRDF ``(wo, wi, n, h) -> (N, 3)`` of the chapter, with the half vector ``h``
    given (the library's terms): ``_half_vector_hint`` gives it a half vector not of unit length."""
    from ptlab.materials import microfacet as library

    def brdf(wo, wi, n, h):
        cos_o, cos_i = np.sum(wo * n, axis=1), np.sum(wi * n, axis=1)
        D, G2 = library.D(np.sum(h * n, axis=1), alpha), library.G2(cos_o, cos_i, alpha)  # noqa: N806
        return (
            library.F_schlick(np.sum(wo * h, axis=1), np.asarray(f0))
            * (D * G2 / (4 * cos_o * cos_i))[:, None]
        )

    return brdf


def _walter_pdf(alpha: float) -> Callable:
    """Walter's density of wi (h drawn with D(h) cos(theta_h), then reflected), h given."""
    from ptlab.materials import microfacet as library

    def pdf(wo, wi, n, h):
        cos_h = np.sum(h * n, axis=1)
        return library.D(cos_h, alpha) * cos_h / (4 * np.abs(np.sum(wo * h, axis=1)))

    return pdf


def _visible_normals_pdf(alpha: float) -> Callable:
    """Heitz's density of wi (h drawn from the visible normals of wo, then reflected), h given."""
    from ptlab.materials import microfacet as library

    def pdf(wo, wi, n, h):
        cos_o = np.sum(wo * n, axis=1)
        return library.G1(cos_o, alpha) * library.D(np.sum(h * n, axis=1), alpha) / (4 * cos_o)

    return pdf


#: wo and wi this far apart have |wo + wi| = 1: there a half vector left unnormalised is the
#: unit one, and a formula that uses it gives the right value.
UNIT_SUM_ANGLE = 2 * math.pi / 3


def _half_vector_hint(function, values: np.ndarray, formulas, pairs, rng, name: str) -> str:
    """The student's ``function`` (eval or pdf) gave ``values`` on ``pairs`` (wo, wi, n), not
    those of any of ``formulas`` ``(wo, wi, n, h) -> values`` with h = normalize(wo + wi). If
    they are one of them with h = wo + wi (right exactly where |wo + wi| = 1, asked on pairs
    ``UNIT_SUM_ANGLE`` apart) or with h = (wo + wi) / 2, the hint that says so, naming the
    pair of ``pairs`` that is furthest off; else ""."""
    wo, wi, n = pairs
    total = wo + wi
    unit = normalize(total)
    rights = [formula(wo, wi, n, unit) for formula in formulas]
    if any(np.allclose(values, right, rtol=1e-3, atol=1e-9) for right in rights):
        return ""
    apart = _pairs_apart(rng, 200, UNIT_SUM_ANGLE)
    at_unit_sum = _values(function, *apart, shape=(len(apart[0]), *values.shape[1:]))
    for formula, right in zip(formulas, rights, strict=True):
        if np.allclose(at_unit_sum, formula(*apart, apart[0] + apart[1]), rtol=1e-3, atol=1e-9):
            message, length = "ch09.hint.h_not_unit", np.linalg.norm(total, axis=1)
        elif np.allclose(values, formula(wo, wi, n, total / 2), rtol=1e-3, atol=1e-9):
            message, length = "ch09.hint.h_halved", np.linalg.norm(total, axis=1) / 2
        else:
            continue
        error = np.abs(values - right) / np.maximum(np.abs(right), 1e-9)
        row = np.unravel_index(np.argmax(error), error.shape)[0]
        return text(
            message,
            name=name,
            angle=math.degrees(math.acos(np.clip(np.sum(wo[row] * wi[row]), -1, 1))),
            length=length[row],
            yours=np.ravel(values[row])[0],
            expected=np.ravel(right[row])[0],
        )
    return ""


def _pairs_apart(rng, count: int, angle: float):
    """count (wo, wi, n) above the surface, random normals, wo and wi ``angle`` apart (drawn
    at random and kept where both are above: 1 in 20 at 120 degrees)."""
    n = normalize(rng.normal(size=(60 * count, 3)))
    wo = normalize(rng.normal(size=n.shape))
    wo *= np.sign(np.sum(wo * n, axis=1))[:, None]
    across = rng.normal(size=n.shape)
    across = normalize(across - np.sum(across * wo, axis=1)[:, None] * wo)
    wi = math.cos(angle) * wo + math.sin(angle) * across
    above = (np.sum(wo * n, axis=1) > 0.05) & (np.sum(wi * n, axis=1) > 0.05)
    chosen = np.flatnonzero(above)[:count]
    return wo[chosen], wi[chosen], n[chosen]


def _harness(module, sampling: str, alpha: float) -> str:
    from ptlab.materials import Microfacet

    return run_harness(
        _metal(module, (1.0, 1.0, 1.0), alpha, sampling),
        grading_seed_for(90),
        _white_metal(sampling, alpha),
        _grade_command(module, sampling, alpha),
        expected_eval=Microfacet((1.0, 1.0, 1.0), alpha=alpha).eval,
    )


def _white_metal(sampling: str, alpha: float) -> str:
    return text("ch09.white_metal", alpha=alpha, sampling=repr(sampling))


def _grade_command(module, sampling: str, alpha: float) -> str:
    arguments = shlex.quote(json.dumps({"f0": [1.0, 1.0, 1.0], "alpha": alpha, "sampling": sampling}))
    return f"ptlab grade {student_file(module)}:GGXMetal --args {arguments}"


def check_harness_hemisphere(module) -> str:
    return _harness(module, "hemisphere", 0.3)


#: The alpha of the white metal whose importance sampling the harness grades.
IMPORTANCE_ALPHA = 0.2


def check_harness_importance(module) -> str:
    """The harness on the student's importance sampling; where it fails, and the sampler's
    pdf or its half vectors show why (``_sampling_diagnosis``), that is the message: the
    harness's own hints are for any material (a sampler that never fails reads to them as
    one that flips its failed samples back up)."""
    try:
        return _harness(module, "ggx", IMPORTANCE_ALPHA)
    except CheckFailed:
        diagnosis, _ = _sampling_diagnosis(module, IMPORTANCE_ALPHA)
        if not diagnosis:
            raise
    raise CheckFailed(
        text(
            "ch09.harness_diagnosed",
            what=_white_metal("ggx", IMPORTANCE_ALPHA),
            diagnosis=diagnosis,
            command=_grade_command(module, "ggx", IMPORTANCE_ALPHA),
        )
    )


def _sampling_diagnosis(module, alpha: float) -> tuple[str, str]:
    """Why the student's importance sampling fails the harness, if its behaviour says: a
    sampler that returns NaN at normal incidence only (whose NaN rows then fail the harness's
    statistics too, which guess other causes), a pdf whose half vector is not of unit length,
    or a sampler whose half vectors are drawn from another lobe than D's; else "" (and where
    the student's code cannot answer, "" too: the harness's message stands). With it, which
    side is at fault (for the render's hint): "nan", "narrower" or "wider" (sample), "pdf_h"
    (pdf's half vector), "pdf"
    (also where only the pdf's lobe is not D's, which the harness says well: no hint then),
    or "" (not known)."""
    from ptlab.course.sandbox import StudentError

    rng = grading_rng(96)
    metal = _metal(module, (1.0, 1.0, 1.0), alpha, "ggx")
    material = Turned(metal, rng)
    pairs = random_pairs(rng, 2000)
    try:
        at_normal = _normal_incidence_hint(metal, grading_rng(97))
        if at_normal:
            return at_normal, "nan"
        pdf = _values(material.pdf, *pairs, shape=(len(pairs[0]),))
        formulas = [_walter_pdf(alpha), _visible_normals_pdf(alpha)]
        half_vector = _half_vector_hint(material.pdf, pdf, formulas, pairs, rng, text("ch09.name.pdf"))
        if half_vector:
            return half_vector, "pdf_h"
        return _lobe_hint(material, alpha, rng)
    except (CheckFailed, StudentError):
        return "", ""


#: The normals at which ``_normal_incidence_hint`` asks sample for wo = n: the axes, as the
#: harness's rows at wo 0 degrees (its exact rotations), where a local frame's coordinates
#: of wo are exactly (0, 0, 1).
AXES = np.concatenate([np.eye(3), -np.eye(3)])
#: Rows per axis that ``_normal_incidence_hint`` asks.
ROWS_PER_AXIS = 64
#: How far from n ``_normal_incidence_hint`` tilts wo to see sample answer there (radians).
NORMAL_TILT = math.radians(1.0)


def _normal_incidence_hint(material, rng) -> str:
    """The hint for a sampler that returns NaN or inf for wo = n and finite directions for wo
    ``NORMAL_TILT`` from n (a length that is 0 only at wo = n: the tangent of Heitz's Listing
    1 without its special case); else ""."""
    n = np.repeat(AXES, ROWS_PER_AXIS, axis=0)
    u = rng.random((len(n), 2))
    at_normal = np.asarray(material.sample(n.copy(), n.copy(), u.copy()))
    if at_normal.shape != n.shape or np.isfinite(at_normal).all():
        return ""
    tilt = np.stack(
        [np.full(len(n), math.sin(NORMAL_TILT)), np.zeros(len(n)), np.full(len(n), math.cos(NORMAL_TILT))]
    )
    wo = np.asarray(to_world(tilt.T, n))
    tilted = np.asarray(material.sample(wo, n.copy(), u))
    if tilted.shape != n.shape or not np.isfinite(tilted).all():
        return ""
    bad = int(np.sum(~np.isfinite(at_normal).all(axis=1)))
    return text("ch09.hint.nan_at_normal", bad=bad, rows=len(n), tilt=math.degrees(NORMAL_TILT))


#: The sampler's half vectors are drawn at a wo this close to n (radians): there every right
#: sampler draws theta_h with the density D(h) cos(theta_h): Walter's at any wo, and the
#: visible normals' (G1(wo) max(0, wo . h) D(h) / cos(theta_o), Heitz 2018, eq. 1) too, as
#: max(0, wo . h) averages to cos(theta_o) cos(theta_h) over phi_h wherever no h of that
#: theta_h faces away from wo (theta_h < 87 degrees here).
LOBE_WO_THETA = 0.05
#: Directions drawn from the sampler to measure its lobe.
LOBE_SAMPLES = 100_000
#: The shares of the half vectors compared with D's: those within the angles within which
#: D(h) cos(theta_h) puts these shares of them.
LOBE_SHARES = np.array([0.1, 0.25, 0.5, 0.75, 0.9])
#: A lobe is called narrower only if the shares of the first three say so: a sampler that
#: flips its failed samples back up (beyond 45 degrees at alpha 0.2) moves them within D's
#: 75th and 90th percentiles (by 5.7 and 17 standard errors at most over 20 seeds), never
#: within its median (2.2), and it makes no share smaller (the harness names the flip).
NARROWER_BY = 3
#: Standard errors (binomial) a share must be off, from D's and from the pdf's alike, for the
#: lobe to be called wrong: a right sampler is this far off with probability below 1e-14
#: (measured: at most 2.2 for Walter's and the visible normals over 20 seeds).
LOBE_Z = 8.0
#: Likely slips in drawing theta_h, each as its theta_h at the quantile q of u0 (for the
#: message id that names it): tan(theta_h) = alpha u0, alpha where alpha^2 belongs, and
#: Beckmann's sampling (Walter et al. 2007, eq. 28) in place of GGX's.
LOBE_SLIPS = {
    "ch09.slip.alpha_u": lambda alpha, q: np.arctan(alpha * q),
    "ch09.slip.alpha_not_squared": lambda alpha, q: np.arctan(np.sqrt(alpha * q / (1 - q))),
    "ch09.slip.beckmann": lambda alpha, q: np.arctan(alpha * np.sqrt(-np.log(1 - q))),
}
#: How close (degrees) the median and 90th percentile of theta_h must both be to a slip's for
#: the hint to name it: their standard errors at ``LOBE_SAMPLES`` are below 0.1 degrees, and
#: the slips' medians are 4 degrees apart or more at ``IMPORTANCE_ALPHA``.
SLIP_TOLERANCE = 0.5


def _lobe_hint(material, alpha: float, rng) -> tuple[str, str]:
    """Whether the half vectors h = normalize(wo + wi) of ``material``'s samples at a wo
    ``LOBE_WO_THETA`` from n spread in theta_h as D(h) cos(theta_h) does (tan^2(theta_h) /
    alpha^2 = u / (1 - u) for u uniform: ``LOBE_SHARES`` of them within D's percentiles),
    and as the material's pdf says: the hint that the sampler's lobe is narrower or wider
    than D's, with its median and 90th percentile and D's (and the slip that draws them, if
    one of ``LOBE_SLIPS`` does), and "narrower" or "wider"; ("", "pdf") where the samples
    follow D at its median and the pdf does not; else ("", "")."""
    count = LOBE_SAMPLES
    normal = np.array([0.0, 0.0, 1.0])
    n = np.tile(normal, (count, 1))
    wo = _frame(normal, np.full(count, LOBE_WO_THETA), rng.uniform(0, 2 * math.pi, count))
    wi = _values(material.sample, wo, n, rng.random((count, 2)), shape=(count, 3))
    if not np.allclose(np.linalg.norm(wi, axis=1), 1, rtol=0, atol=1e-3):
        return "", ""  # (not directions: the harness says so, "normalise them", better than a lobe)
    theta_h = _theta_h(wo, wi, n)
    if len(theta_h) < count // 2:
        return "", ""  # (most samples are wi = -wo, which has no half vector: no lobe to speak of)
    angles = np.arctan(alpha * np.sqrt(LOBE_SHARES / (1 - LOBE_SHARES)))
    shares = np.mean(theta_h[:, None] <= angles, axis=0)
    with np.errstate(all="ignore"):  # (a pdf of NaN or 0 there: no lobe hint, not a warning)
        pdf_shares = _pdf_lobe(material, wo[0], normal, angles)
    # Signed standard errors: > 0 where more h lie within the angle than D (or pdf) puts there.
    off_d = (shares - LOBE_SHARES) / np.sqrt(LOBE_SHARES * (1 - LOBE_SHARES) / count)
    off_pdf = (shares - pdf_shares) / np.sqrt(np.clip(pdf_shares * (1 - pdf_shares), 1e-12, None) / count)
    narrower = ((off_d > LOBE_Z) & (off_pdf > LOBE_Z))[:NARROWER_BY].any()
    wider = ((off_d < -LOBE_Z) & (off_pdf < -LOBE_Z)).any()
    if not (narrower or wider):
        median_share = LOBE_SHARES == 0.5
        pdf_off = (np.abs(off_d[:NARROWER_BY]) < LOBE_Z).all() and np.abs(off_pdf[median_share][0]) > LOBE_Z
        return "", "pdf" if pdf_off else ""
    median, ninetieth = np.degrees(np.quantile(theta_h, [0.5, 0.9]))
    lobe = "narrower" if narrower else "wider"
    hint = text(
        "ch09.hint.lobe",
        theta_o=math.degrees(LOBE_WO_THETA),
        alpha=alpha,
        median=median,
        ninetieth=ninetieth,
        expected=math.degrees(math.atan(alpha)),
        expected_ninetieth=math.degrees(math.atan(3 * alpha)),
        pdf=pdf_shares[LOBE_SHARES == 0.5][0],
        lobe=text(f"ch09.{lobe}"),
        slip=_lobe_slip(alpha, median, ninetieth),
    )
    return hint, lobe


def _lobe_slip(alpha: float, median: float, ninetieth: float) -> str:
    """The words that name the slip of ``LOBE_SLIPS`` whose theta_h has this median and 90th
    percentile (degrees), with its median; else ""."""
    for message, theta_h in LOBE_SLIPS.items():
        expected = np.degrees([theta_h(alpha, 0.5), theta_h(alpha, 0.9)])
        if np.all(np.abs(expected - [median, ninetieth]) < SLIP_TOLERANCE):
            return text(message, median=expected[0])
    return ""


def _theta_h(wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(N,) the angle from n of h = normalize(wo + wi): the microfacet normal that reflects
    wo to wi, whether wi landed above the surface or not (none where wi = -wo)."""
    h = wo + wi
    length = np.linalg.norm(h, axis=1)
    cos_h = np.sum(h * n, axis=1)[length > 1e-9] / length[length > 1e-9]
    return np.arccos(np.clip(np.abs(cos_h), 0, 1))


def _pdf_lobe(material, wo: np.ndarray, n: np.ndarray, angles: np.ndarray, rows: int = 1500) -> np.ndarray:
    """The share of the directions that ``material``'s pdf at wo (3,) gives to half vectors
    within each of ``angles`` of n (3,): pdf(wi) 4 |wo . h| is the density of h (wi =
    reflect(wo, h); Walter et al. 2007, eq. 14), integrated over a (theta_h, phi_h) grid by
    the midpoint rule."""
    cols = 24
    theta = (np.arange(rows) + 0.5) * (math.pi / 2) / rows
    phi = (np.arange(cols) + 0.5) * 2 * math.pi / cols
    theta_grid, phi_grid = (a.ravel() for a in np.meshgrid(theta, phi, indexing="ij"))
    h = _frame(n, theta_grid, phi_grid)
    wos = np.tile(wo, (len(h), 1))
    cos_d = np.sum(wos * h, axis=1)
    wi = 2 * cos_d[:, None] * h - wos
    pdf = _values(material.pdf, wos, wi, np.tile(n, (len(h), 1)), shape=(len(h),))
    mass = pdf * 4 * np.abs(cos_d) * np.sin(theta_grid) * (math.pi / 2 / rows) * (2 * math.pi / cols)
    within = np.cumsum(mass.reshape(rows, cols).sum(axis=1))
    return np.interp(angles, theta + 0.5 * (math.pi / 2) / rows, within, left=0.0)


#: The stream of the grading seed that the render checks' seed comes from.
RENDER_SEED = 9

#: The stream of the grading seed that the render checks' samples per pass come from.
SPP_STREAM = 95

#: The library's sampling that each of the student's is compared with.
LIBRARY_SAMPLING = {"ggx": "vndf", "hemisphere": "hemisphere"}


def render_options(seed: int, spp_per_pass: int = SPP_PER_PASS) -> dict:
    """The render both sides of chapter 9's comparisons make: 32 x 32, 16 passes of
    ``spp_per_pass`` spp (drawn per run by the render checks, as chapter 6's:
    ``render_spp_per_pass``)."""
    return dict(res=32, passes=16, spp_per_pass=spp_per_pass, seed=seed, max_depth=6)


def metals_scene():
    """``cornell-box-microfacet`` seen from closer, so that its two metal spheres fill the
    picture (from the whole box's camera they are a few pixels of a 32 x 32 image)."""
    import ptlab
    from ptlab.camera import Camera

    scene = ptlab.load_scene("cornell-box-microfacet")
    scene.camera = Camera.look_at((282, 200, -250), (282, 80, 155), fov_y=42)
    return scene


def render_passes(
    sampling: str,
    metal_for: Callable | None = None,
    seed: int = 0,
    spp_per_pass: int = SPP_PER_PASS,
) -> np.ndarray:
    """The ``pass_images`` of ``metals_scene`` with ``metal_for(f0, alpha)`` in place of its
    metals, or with the library's own sampling in the way of ``sampling`` if None."""
    from ptlab.materials import Microfacet

    def replace(m):
        if not isinstance(m, Microfacet):
            return None
        if metal_for is None:
            return m.with_sampling(LIBRARY_SAMPLING[sampling])
        return metal_for(m.f0, m.alpha)

    return pass_images(replace_materials(metals_scene(), replace), **render_options(seed, spp_per_pass))


def _render(module, sampling: str) -> str:
    probe(_metal(module, sampling=sampling))
    seed = grading_seed_for(RENDER_SEED)
    spp_per_pass = render_spp_per_pass(grading_rng(SPP_STREAM))
    library = library_render(
        ("ch09 render", sampling, seed, spp_per_pass),
        lambda: render_passes(sampling, seed=seed, spp_per_pass=spp_per_pass),
    )
    student = render_passes(
        sampling, lambda f0, alpha: _metal(module, f0, alpha, sampling), seed, spp_per_pass=spp_per_pass
    )
    hemisphere = sampling == "hemisphere"
    what = text("ch09.hemisphere_sampling" if hemisphere else "ch09.importance_sampling")

    def hint() -> str:  # (asks the student's code thousands of rows: only for a failed mean)
        return _render_hint(module) or (
            text("ch09.hint.eval_angles") if hemisphere else _importance_render_hint(module)
        )

    try:
        return compare_renders(student, library, text("ch09.yours", what=what), hint, spp_per_pass)
    except CheckFailed as failure:
        from ptlab.course.inspect_command import suggestion

        raise CheckFailed(str(failure) + suggestion(9, student, library, seed)) from None


def _importance_render_hint(module) -> str:
    """What a failing importance-sampled render says of sample and pdf: the side that the
    harness (importance) check's diagnosis finds at fault (``_sampling_diagnosis``), or
    neutrally that they disagree."""
    _, fault = _sampling_diagnosis(module, IMPORTANCE_ALPHA)
    if fault in ("narrower", "wider"):
        return text("ch09.hint.render_lobe", lobe=text(f"ch09.{fault}"))
    if fault in ("nan", "pdf_h"):
        return text("ch09.hint.render_sample" if fault == "nan" else "ch09.hint.render_pdf")
    return text("ch09.hint.jacobian" if fault == "pdf" else "ch09.hint.sample_pdf")


def _render_hint(module) -> str:
    """Where the student's eval is not the GGX BRDF (``_eval_mismatch``), what a render that
    differs says: eval, and its wrong term if known, not the sampling (a wrong eval changes
    the picture whatever the sampling); else "" (or where eval cannot answer: the render
    check's own failure says why)."""
    from ptlab.course.sandbox import StudentError

    try:
        mismatch = _eval_mismatch(module)
    except (CheckFailed, StudentError):
        return ""
    if mismatch is None:
        return ""
    error, _, term = mismatch
    if term:
        return text("ch09.hint.render_eval_term", term=text(term))
    return text("ch09.hint.render_eval", error=error)


def check_render_hemisphere(module) -> str:
    return _render(module, "hemisphere")


def check_render_importance(module) -> str:
    return _render(module, "ggx")


def render_yours(module, scene, options: dict) -> np.ndarray:
    """``scene`` rendered with the student's ``GGXMetal`` (importance sampled) in place of
    every microfacet material, of the same f0 and alpha (``ptlab exercise render``)."""
    from ptlab.course.side_by_side import render_with_materials
    from ptlab.materials import Microfacet

    probe(_metal(module))
    missing = text("ch09.no_metal", scene=scene.name)
    return render_with_materials(
        scene,
        options,
        lambda m: isinstance(m, Microfacet),
        lambda m: _metal(module, m.f0, m.alpha, "ggx"),
        missing,
    )


CHAPTER = Chapter(
    number=9,
    slug="microfacet",
    title="Microfacet materials",
    functions=("D", "G1", "G2", "fresnel_schlick", "GGXMetal.eval", "GGXMetal.sample", "GGXMetal.pdf"),
    answers=(
        *tuple(f"ptlab.materials.microfacet.{name}" for name in ("D", "G1", "G2", "Lambda", "Microfacet")),
        "ptlab.scattering.F_schlick",
        "ptlab.sampling.ggx_visible_normals",
    ),
    also_left_out=("ptlab.materials.microfacet",),
    checks=(
        ChapterCheck("D normalisation", 2, check_d, timeout=30),
        ChapterCheck("Smith G", 1, check_g, timeout=30),
        ChapterCheck("Fresnel-Schlick", 1, check_fresnel, timeout=30),
        ChapterCheck("eval", 1, check_eval, timeout=30),
        # A metal whose eval and pdf are 0 passes every check of the harness: these score
        # only once the GGX lobe itself is right.
        ChapterCheck(
            "harness (hemisphere)", 1, check_harness_hemisphere, timeout=60, requires=("D normalisation",)
        ),
        ChapterCheck("render (hemisphere)", 1, check_render_hemisphere, timeout=60),
        ChapterCheck(
            "harness (importance)", 2, check_harness_importance, timeout=60, requires=("D normalisation",)
        ),
        ChapterCheck("render (importance)", 1, check_render_importance, timeout=60),
    ),
    render=ChapterRender(render_yours, scene="cornell-box-microfacet"),
)
