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
from ptlab.course.chapters.ch06_diffuse import probe, random_pairs, render_spp_per_pass, run_harness
from ptlab.course.finite import finite_array
from ptlab.course.messages import aside, text
from ptlab.course.renders import compare_renders, pass_images, replace_materials
from ptlab.rendering.sizes import SPP_PER_PASS

ALPHAS = (0.05, 0.2, 0.5, 1.0)
GOLD = (1.0, 0.782, 0.344)


def _values(function, *arguments, shape) -> np.ndarray:
    """``function(*arguments)`` as float64, checked for shape and finiteness (the row of the
    first NaN is named). The function gets copies: the check's arrays stay its own."""
    return finite_array(function(*(np.array(a) for a in arguments)), function.__name__, shape)


def _alphas(stream: int, alphas) -> tuple[float, ...]:
    """``alphas``, each moved by up to 5% by the grading seed (rounded to 4 decimals, to
    read well in a message): the checks' inputs are new for every grading."""
    rng = grading_rng(stream)
    return tuple(round(float(a * rng.uniform(0.95, 1.05)), 4) for a in alphas)


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
            raise CheckFailed(
                text("ch09.g1", cos=cos_theta[worst], alpha=alpha, yours=g1[worst], expected=expected[worst])
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
        raise CheckFailed(
            text("ch09.g2", cos_o=cos_o[worst], cos_i=cos_i[worst], yours=g2[worst], expected=expected[worst])
        )
    return text("ch09.g_ok")


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


def check_eval(module) -> str:
    from ptlab.materials import Microfacet

    material = _metal(module)
    rng = grading_rng(92)
    wo, wi, n = random_pairs(rng, 2000)
    expected = Microfacet(GOLD, alpha=0.3).eval(wo, wi, n)
    f = _values(material.eval, wo, wi, n, shape=wo.shape)
    if not np.allclose(f, expected, rtol=1e-4, atol=1e-9):
        raise CheckFailed(
            text("ch09.eval", error=np.abs(f - expected).max(), hint=_eval_hint(f, wo, wi, n, 0.3))
        )
    below = _values(material.eval, wo, -wi, n, shape=wo.shape)
    if np.abs(below).max() > 0:
        raise CheckFailed(text("ch09.eval_below"))
    return text("ch09.eval_ok")


def _eval_hint(f: np.ndarray, wo, wi, n, alpha: float) -> str:
    """Which term of D G2 F / (4 cos_theta_o cos_theta_i) the student's ``f`` has wrong: the
    BRDF is rebuilt with one typical mistake at a time, and the one that ``f`` equals named."""
    from ptlab.materials import microfacet as library

    h = wo + wi
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    cos_o, cos_i, cos_h = (np.sum(a * n, axis=1) for a in (wo, wi, h))
    cos_d = np.sum(wo * h, axis=1)
    f0 = np.asarray(GOLD)
    D, G2, F = library.D(cos_h, alpha), library.G2(cos_o, cos_i, alpha), library.F_schlick(cos_d, f0)  # noqa: N806
    rest = (D * G2 / (4 * cos_o * cos_i))[:, None]
    mistakes = [
        (F * rest * cos_i[:, None], "ch09.hint.cosine"),
        (4 * F * rest, "ch09.hint.four_missing"),
        (F * rest / 4, "ch09.hint.four_more"),
        (library.F_schlick(cos_i, f0) * rest, "ch09.hint.f_at_wi"),
        (library.F_schlick(cos_o, f0) * rest, "ch09.hint.f_at_wo"),
        (library.F_schlick(cos_h, f0) * rest, "ch09.hint.f_at_h"),
        (np.broadcast_to(f0, F.shape) * rest, "ch09.hint.f_constant"),
        (rest * np.ones(3), "ch09.hint.f_missing"),
        (
            F * rest * (library.G1(cos_o, alpha) * library.G1(cos_i, alpha) / G2)[:, None],
            "ch09.hint.g_separable",
        ),
        (F * rest * (library.G1(cos_o, alpha) / G2)[:, None], "ch09.hint.g1_alone"),
        (F * rest / G2[:, None], "ch09.hint.g_missing"),
        (F * rest * (library.D(cos_h, alpha * alpha) / D)[:, None], "ch09.hint.alpha4"),
        (F * rest * (library.D(cos_h, math.sqrt(alpha)) / D)[:, None], "ch09.hint.alpha1"),
    ]
    for value, hint in mistakes:
        if np.allclose(f, value, rtol=1e-3, atol=1e-9):
            return text(hint, at=text("ch09.hint.schlick_angle"))
    return text("ch09.hint.formula")


def _harness(module, sampling: str, alpha: float) -> str:
    from ptlab.materials import Microfacet

    material = _metal(module, (1.0, 1.0, 1.0), alpha, sampling)
    arguments = shlex.quote(json.dumps({"f0": [1.0, 1.0, 1.0], "alpha": alpha, "sampling": sampling}))
    return run_harness(
        material,
        grading_seed_for(90),
        text("ch09.white_metal", alpha=alpha, sampling=repr(sampling)),
        f"ptlab grade {student_file(module)}:GGXMetal --args {arguments}",
        expected_eval=Microfacet((1.0, 1.0, 1.0), alpha=alpha).eval,
    )


def check_harness_hemisphere(module) -> str:
    return _harness(module, "hemisphere", 0.3)


def check_harness_importance(module) -> str:
    return _harness(module, "ggx", 0.2)


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
    library = render_passes(sampling, seed=seed, spp_per_pass=spp_per_pass)
    student = render_passes(
        sampling, lambda f0, alpha: _metal(module, f0, alpha, sampling), seed, spp_per_pass=spp_per_pass
    )
    hemisphere = sampling == "hemisphere"
    what = text("ch09.hemisphere_sampling" if hemisphere else "ch09.importance_sampling")
    hint = text("ch09.hint.eval_angles" if hemisphere else "ch09.hint.jacobian")
    try:
        return compare_renders(
            student,
            library,
            text("ch09.yours", what=what),
            hint,
            spp_per_pass,
        )
    except CheckFailed as failure:
        from ptlab.course.inspect_command import suggestion

        raise CheckFailed(str(failure) + suggestion(9, student, library, seed)) from None


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
