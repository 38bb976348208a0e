"""The diffuse material against its contract and its closed forms; the contract's one signature."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from ptlab.materials import Dielectric, Diffuse, Material, Microfacet, Mirror
from ptlab.sampling import to_world, uniform_hemisphere

N = 200_000
ALBEDO = np.array([0.8, 0.5, 0.2])


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
    assert (material.eval(wo, -wi, n) == 0).all() and (material.pdf(wo, -wi, n) == 0).all()
    assert (material.eval(-wo, wi, n) == 0).all() and (material.pdf(-wo, wi, n) == 0).all()
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
    assert integral == pytest.approx(1.0, abs=0.01)     # sd ~ 1.4 / sqrt(N): 3e-3
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
    assert uniform is not material and type(uniform) is Diffuse
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
