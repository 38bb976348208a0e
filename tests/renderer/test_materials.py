"""The materials (``ptlab.materials``): every one of them against the contract of
``Material`` (docs: DESIGN.md, "Directions and materials") and its one signature, and the
diffuse one against its closed forms. The closed forms of the others: ``renderer/test_microfacet.py``
(GGX) and ``renderer/test_delta_materials.py`` (mirror and glass); the statistical graders' verdicts
on them: ``renderer/test_grading.py``.

The contract tests are exact, but for the energy bound: a mean of 2^16 weights per
direction against 1 + 5 standard errors, which a material that keeps energy fails (over
the choice of the fixed seeds) with probability below 3e-7 per direction (the one-sided
normal tail beyond 5 sigma).
"""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from ptlab.materials import Dielectric, Diffuse, Material, Microfacet, Mirror
from ptlab.sampling import to_world, uniform_hemisphere

N = 200_000
ALBEDO = np.array([0.8, 0.5, 0.2])

# -- every material's contract -------------------------------------------------------------

#: Every material and each of its samplings, plain and coloured, smooth and rough.
MATERIALS = [
    Diffuse(ALBEDO),
    Diffuse(ALBEDO, sampling="uniform"),
    Microfacet("gold", roughness=0.4),
    Microfacet("copper", alpha=0.1, kd=(0.4, 0.4, 0.4), ks=0.6),
    Microfacet((1, 1, 1), alpha=0.05),
    Microfacet((1, 1, 1), alpha=1.0, sampling="hemisphere"),
    Mirror(),
    Mirror((0.9, 0.6, 0.3), fresnel=True),
    Dielectric(1.5),
    Dielectric(1.33, transmittance=(0.9, 0.8, 0.7)),
]
#: The materials that only reflect (all but glass): nothing below the surface.
REFLECTIVE = [m for m in MATERIALS if not isinstance(m, Dielectric)]
SMOOTH = [m for m in MATERIALS if not m.is_delta]
#: White versions: each keeps at most the energy it receives.
WHITE = [
    Diffuse((1, 1, 1)),
    Diffuse((1, 1, 1), sampling="uniform"),
    Microfacet((1, 1, 1), alpha=0.05),
    Microfacet((1, 1, 1), alpha=0.3),
    Microfacet((1, 1, 1), alpha=1.0),
    Microfacet((1, 1, 1), alpha=0.3, sampling="hemisphere"),
    Microfacet((1, 1, 1), alpha=0.3, kd=(0.5, 0.5, 0.5), ks=0.5),
    Mirror(),
    Mirror((1, 1, 1), fresnel=True),
    Dielectric(1.5),
]
ROWS = 1 << 12


def directions_everywhere(rows: int, seed: int):
    """(n, wo, wi, u): random normals, wo and wi anywhere on the sphere (half of them below
    the surface), a row of each grazing exactly and just above and below it, and uniforms."""
    rng = np.random.default_rng(seed)
    n, wo, wi = (unit(rng.normal(size=(rows, 3))) for _ in range(3))
    for w in (wo, wi):
        for row, cos_theta in enumerate((0.0, 1e-7, -1e-7, 1.0, -1.0)):
            tangent = unit(np.cross(n[row], [0.6, 0.8, 0.0]))
            w[row] = cos_theta * n[row] + math.sqrt(1 - cos_theta**2) * tangent
    return n, wo, wi, rng.random((rows, 2))


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def cos(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (a * b).sum(axis=-1)


@pytest.mark.parametrize("material", MATERIALS, ids=repr)
def test_sample_never_returns_nan_and_its_weight_is_finite_and_not_negative(material):
    n, wo, _, u = directions_everywhere(ROWS, 0)
    wi = material.sample(wo, n, u)
    assert np.isfinite(wi).all()
    wi, weight = material.sample_weight(wo, n, u)
    assert np.isfinite(wi).all()
    assert np.isfinite(weight).all()
    assert (weight >= 0).all()
    # A direction wherever it can sample: a unit vector.
    can = (weight > 0).any(axis=1)
    np.testing.assert_allclose(np.linalg.norm(wi[can], axis=1), 1, atol=1e-6)


@pytest.mark.parametrize("material", MATERIALS, ids=repr)
def test_a_sample_carries_the_pdf_that_pdf_gives_its_direction(material):
    # What MIS weighs the emission found along wi with: the same numbers, bit for bit, as
    # sample_weight followed by pdf (which the renderer then need not call).
    n, wo, _, u = directions_everywhere(ROWS, 3)
    n, wo, u = (np.asfortranarray(a, dtype=np.float32) for a in (n, wo, u))
    front = np.ones(ROWS, dtype=bool)
    wi, weight, pdf = material.sample_weight_pdf(wo, n, u, front)
    expected_wi, expected_weight = material.sample_weight(wo, n, u, front)
    np.testing.assert_array_equal(wi, expected_wi)
    np.testing.assert_array_equal(weight, expected_weight)
    np.testing.assert_array_equal(pdf, material.pdf(wo, wi, n))


@pytest.mark.parametrize("material", MATERIALS, ids=repr)
def test_eval_and_pdf_are_finite_and_not_negative_everywhere(material):
    n, wo, wi, _ = directions_everywhere(ROWS, 1)
    f, pdf = material.eval(wo, wi, n), material.pdf(wo, wi, n)
    assert f.shape == (ROWS, 3)
    assert pdf.shape == (ROWS,)
    assert np.isfinite(f).all()
    assert (f >= 0).all()
    assert np.isfinite(pdf).all()
    assert (pdf >= 0).all()


@pytest.mark.parametrize("material", REFLECTIVE, ids=repr)
def test_a_reflective_material_is_black_and_never_samples_below_its_surface(material):
    n, wo, wi, u = directions_everywhere(ROWS, 2)
    below = (cos(wo, n) < 0) | (cos(wi, n) < 0)
    assert (material.eval(wo, wi, n)[below] == 0).all()
    assert (material.pdf(wo, wi, n)[below] == 0).all()
    _, weight = material.sample_weight(wo, n, u)
    assert (weight[cos(wo, n) < 0] == 0).all()


@pytest.mark.parametrize("material", SMOOTH, ids=repr)
def test_pdf_is_positive_wherever_sample_lands_above_the_surface(material):
    n, wo, _, u = directions_everywhere(ROWS, 3)
    above = cos(wo, n) > 0
    n, wo, u = n[above], wo[above], u[above]
    wi = material.sample(wo, n, u)
    landed = cos(wi, n) > 0
    assert landed.mean() > 0.5
    assert (material.pdf(wo, wi, n)[landed] > 0).all()


@pytest.mark.parametrize("material", SMOOTH, ids=repr)
def test_weight_is_f_cos_over_pdf_and_eval_is_reciprocal(material):
    n, wo, wi, u = directions_everywhere(ROWS, 4)
    sampled, weight = material.sample_weight(wo, n, u)
    generic_wi, generic = Material.sample_weight(material, wo, n, u)
    np.testing.assert_allclose(sampled, generic_wi, atol=1e-12)
    np.testing.assert_allclose(weight, generic, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(material.eval(wo, wi, n), material.eval(wi, wo, n), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("material", WHITE, ids=repr)
@pytest.mark.parametrize("degrees", [0, 45, 80, 89])
def test_a_white_material_reflects_at_most_what_it_receives(material, degrees):
    # E[f cos / pdf] over wi is the fraction of the light from wo that the surface sends
    # back (glass: what reflects plus what enters, as radiance seen inside, scaled 1/eta^2).
    rows = 1 << 16
    rng = np.random.default_rng(degrees)
    n = unit(rng.normal(size=(rows, 3)))
    phi = rng.uniform(0, 2 * math.pi, rows)
    theta = math.radians(degrees)
    local = np.column_stack(
        [math.sin(theta) * np.cos(phi), math.sin(theta) * np.sin(phi), np.full(rows, math.cos(theta))]
    )
    _, weight = material.sample_weight(to_world(local, n), n, rng.random((rows, 2)))
    mean = weight.mean(axis=0)
    standard_error = weight.std(axis=0, ddof=1) / math.sqrt(rows)
    assert np.all(mean <= 1 + 5 * standard_error + 1e-12), (mean, standard_error)


# -- the diffuse material's closed forms ------------------------------------------------------


def random_frame(n_rows: int, seed: int):
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(n_rows, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    wo = to_world(uniform_hemisphere(rng.random((n_rows, 2))), n)
    return rng, n, wo


@pytest.mark.parametrize("sampling", ["cosine", "uniform"])
def test_eval_pdf_and_sample_follow_the_contract(sampling):
    material = Diffuse(ALBEDO, sampling=sampling)
    rng, n, wo = random_frame(N, 0)
    wi = material.sample(wo, n, rng.random((N, 2)))
    assert np.isfinite(wi).all()
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-12)
    assert ((wi * n).sum(axis=1) >= 0).all()
    assert (material.pdf(wo, wi, n) > 0).all()
    np.testing.assert_allclose(material.eval(wo, wi, n), np.broadcast_to(ALBEDO / math.pi, wi.shape))
    # Reflective only: nothing below the surface, for wi or for wo.
    assert (material.eval(wo, -wi, n) == 0).all()
    assert (material.pdf(wo, -wi, n) == 0).all()
    assert (material.eval(-wo, wi, n) == 0).all()
    assert (material.pdf(-wo, wi, n) == 0).all()
    # Reciprocity.
    np.testing.assert_array_equal(material.eval(wo, wi, n), material.eval(wi, wo, n))


@pytest.mark.parametrize("sampling", ["cosine", "uniform"])
def test_pdf_integrates_to_one_and_reflectance_is_the_albedo(sampling):
    material = Diffuse(ALBEDO, sampling=sampling)
    rng, n, wo = random_frame(N, 1)
    # Uniform-sphere estimates: E[pdf / (1 / 4 pi)] = integral of pdf over the sphere.
    wi = rng.normal(size=(N, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    integral = (material.pdf(wo, wi, n) * 4 * math.pi).mean()
    assert integral == pytest.approx(1.0, abs=0.01)  # sd ~ 1.4 / sqrt(N): 3e-3
    cos = np.clip((wi * n).sum(axis=1), 0, None)
    reflectance = (material.eval(wo, wi, n) * cos[:, None] * 4 * math.pi).mean(axis=0)
    np.testing.assert_allclose(reflectance, ALBEDO, atol=0.01)


@pytest.mark.parametrize("sampling", ["cosine", "uniform"])
def test_sample_weight_equals_f_cos_over_pdf(sampling):
    material = Diffuse(ALBEDO, sampling=sampling)
    rng, n, wo = random_frame(1000, 2)
    u = rng.random((1000, 2))
    wi, weight = material.sample_weight(wo, n, u)
    generic_wi, generic = Material.sample_weight(material, wo, n, u)
    np.testing.assert_array_equal(wi, generic_wi)
    np.testing.assert_allclose(weight, generic, rtol=1e-10)
    # Below the surface the weight is zero, not NaN.
    _, below = material.sample_weight(-wo, n, u)
    assert (below == 0).all()


def test_stacked_materials_shade_each_row_with_its_own_albedo():
    red, blue = Diffuse([0.9, 0.1, 0.1]), Diffuse([0.1, 0.1, 0.9])
    stacked = Diffuse.stack([red, blue])
    rows = stacked.take(np.array([1, 0, 1]))
    n = np.tile([0.0, 0, 1], (3, 1))
    f = rows.eval(n, n, n)
    np.testing.assert_allclose(f, np.array([blue.albedo, red.albedo, blue.albedo]) / math.pi)


def test_unknown_sampling_is_refused():
    with pytest.raises(ValueError, match="sampling"):
        Diffuse(sampling="importance")


def test_with_sampling_returns_the_material_itself_when_nothing_changes():
    material = Diffuse(ALBEDO, sampling="cosine")
    assert material.with_sampling("cosine") is material
    uniform = material.with_sampling("uniform")
    assert uniform is not material
    assert type(uniform) is Diffuse
    assert (uniform.sampling, material.sampling) == ("uniform", "cosine")
    with pytest.raises(ValueError, match="sampling"):
        material.with_sampling("importance")


def test_sample_takes_front_in_every_library_material():
    for kind in (Material, Diffuse, Microfacet, Mirror, Dielectric):
        for method in (kind.sample, kind.sample_weight):
            parameters = list(inspect.signature(method).parameters)
            assert parameters == ["self", "wo", "n", "u", "front"], (kind, method)


def test_a_material_with_the_homeworks_three_argument_sample_gets_a_weight_with_front():
    # A student's material overrides sample(wo, n, u) without front; the renderer passes front
    # to sample_weight, which must not hand it on.
    class Homework(Material):
        def eval(self, wo, wi, n):
            return Diffuse(ALBEDO).eval(wo, wi, n)

        def pdf(self, wo, wi, n):
            return Diffuse(ALBEDO).pdf(wo, wi, n)

        def sample(self, wo, n, u):
            return Diffuse(ALBEDO).sample(wo, n, u)

    rng, n, wo = random_frame(100, 3)
    u = rng.random((100, 2))
    wi, weight = Homework().sample_weight(wo, n, u, np.ones(100, dtype=bool))
    np.testing.assert_array_equal(wi, Diffuse(ALBEDO).sample(wo, n, u))
    np.testing.assert_allclose(weight, np.broadcast_to(ALBEDO, weight.shape), rtol=1e-12)
