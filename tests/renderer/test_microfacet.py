"""The GGX microfacet material: its terms against their defining integrals and closed forms.

Integrals over the sphere use the grader's deterministic adaptive quadrature
(``SphereGrid.integrate``); the sampled checks use fixed seeds (false-alarm rates below).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ptlab.grading.checks import batch, chi2_sf, direction_at, pooled_chi_square
from ptlab.grading.sphere import SphereGrid
from ptlab.materials import METALS, Material, Microfacet
from ptlab.materials.microfacet import G1, G2, D
from ptlab.sampling import ggx_visible_normals
from ptlab.scattering import F_schlick, reflect
from ptlab.vectors import dot

N_AXIS = np.array([0.0, 0.0, 1.0])
ALPHAS = [0.05, 0.2, 0.5, 1.0]


def integral(grid: SphereGrid, f) -> float:
    """The integral of a scalar function of (P, 3) directions over the sphere."""

    def tolerance(fine, area):
        return 1e-7 * (np.abs(fine) + area[:, None])

    totals, _ = grid.integrate(lambda w: f(w)[:, None], tolerance)
    return float(totals.sum())


@pytest.mark.parametrize("alpha", ALPHAS)
def test_d_is_normalised_over_projected_microfacet_area(alpha):
    # Walter et al. 2007 section 3: the integral of D(h) cos(theta_h) over the hemisphere is 1.
    grid = SphereGrid(N_AXIS, 16, 32)
    value = integral(grid, lambda h: np.where(h[:, 2] > 0, D(h[:, 2], alpha) * h[:, 2], 0.0))
    assert value == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize("degrees", [0, 45, 80])
def test_g1_makes_the_visible_microfacet_area_the_projected_area(alpha, degrees):
    # Heitz 2014 section 2: integral of G1(wo) max(0, wo . h) D(h) dh = cos(theta_o).
    wo = direction_at(N_AXIS, degrees, 0.0)
    grid = SphereGrid(N_AXIS, 16, 32)
    g1 = float(G1(np.array([wo[2]]), alpha)[0])

    def visible(h):
        return np.where(h[:, 2] > 0, g1 * np.maximum(h @ wo, 0) * D(h[:, 2], alpha), 0.0)

    value = integral(grid, visible)
    assert value == pytest.approx(wo[2], abs=1e-6)


def test_g2_is_symmetric_and_at_most_the_product_of_the_g1():
    rng = np.random.default_rng(0)
    cos_o, cos_i = rng.uniform(1e-3, 1, 1000), rng.uniform(1e-3, 1, 1000)
    for alpha in ALPHAS:
        np.testing.assert_allclose(G2(cos_o, cos_i, alpha), G2(cos_i, cos_o, alpha), rtol=1e-15)
        # Height correlation makes G2 >= G1 G1 (Heitz 2014 section 6); both in (0, 1].
        assert (G2(cos_o, cos_i, alpha) >= G1(cos_o, alpha) * G1(cos_i, alpha) - 1e-15).all()
        assert (G2(cos_o, cos_i, alpha) <= 1).all()


@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
@pytest.mark.parametrize("degrees", [0, 45, 85])
def test_visible_normals_follow_d_wo(alpha, degrees):
    # 10^5 samples binned against the integral of D_wo(h) = G1(wo) max(0, wo.h) D(h) / cos_theta_o
    # over each cell (pooled chi-square, seed 1): false-alarm rate 1e-4.
    rows = 100_000
    wo = direction_at(N_AXIS, degrees, 0.7)
    rng = np.random.default_rng(1)
    h = ggx_visible_normals(batch(wo, rows), batch(N_AXIS, rows), alpha, rng.random((rows, 2)))
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), 1, atol=1e-12)
    assert (h @ wo > -1e-12).all(), "visible normals face wo"
    grid = SphereGrid(N_AXIS, 32, 64)
    g1 = float(G1(np.array([wo[2]]), alpha)[0])

    def d_wo(w):
        return (np.where(w[:, 2] > 0, g1 * np.maximum(w @ wo, 0) * D(w[:, 2], alpha) / wo[2], 0.0))[:, None]

    expected, _ = grid.integrate(d_wo, lambda fine, area: (0.02 * np.sqrt(rows * np.abs(fine)) + 0.01) / rows)
    statistic, dof = pooled_chi_square(grid.histogram(h), rows * expected[:, 0])
    assert chi2_sf(statistic, dof) > 1e-4


def test_closed_form_at_normal_incidence():
    # wo = wi = n: h = n, D = 1 / (pi alpha^2), G2 = 1, F = F0, so f = F0 / (4 pi alpha^2).
    f0, alpha = np.array([0.9, 0.6, 0.3]), 0.3
    material = Microfacet(f0, alpha=alpha)
    n = N_AXIS[None, :]
    np.testing.assert_allclose(material.eval(n, n, n)[0], f0 / (4 * math.pi * alpha**2), rtol=1e-12)
    # VNDF pdf there: G1(n) D(n) / 4 = 1 / (4 pi alpha^2).
    assert material.pdf(n, n, n)[0] == pytest.approx(1 / (4 * math.pi * alpha**2), rel=1e-12)


@pytest.mark.parametrize("sampling", ["vndf", "hemisphere"])
def test_sample_weight_is_f_cos_over_pdf_and_vndf_weight_is_f_g2_over_g1(sampling):
    rows = 5000
    rng = np.random.default_rng(2)
    material = Microfacet("gold", alpha=0.3, sampling=sampling)
    n = batch(N_AXIS, rows)
    wo = batch(direction_at(N_AXIS, 60, 0.0), rows)
    u = rng.random((rows, 2))
    wi, weight = material.sample_weight(wo, n, u)
    _, generic = Material.sample_weight(material, wo, n, u)
    np.testing.assert_allclose(weight, generic)
    if sampling == "vndf":
        ok = dot(wi, n) > 0
        h = (wo + wi) / np.linalg.norm(wo + wi, axis=1, keepdims=True)
        fresnel = F_schlick(dot(wo, h), material.f0)
        alpha = material.alpha
        expected = fresnel * (G2(wo[:, 2], np.maximum(wi[:, 2], 1e-7), alpha) / G1(wo[:, 2], alpha))[:, None]
        np.testing.assert_allclose(weight[ok], expected[ok], rtol=1e-9)
        assert (weight[~ok] == 0).all()
        assert (weight <= 1).all()


@pytest.mark.parametrize(("alpha", "low", "high"), [(0.05, 0.99, 1.0), (1.0, 0.3, 0.9)])
def test_white_furnace_smooth_metal_reflects_nearly_everything_rough_metal_less(alpha, low, high):
    # With F0 = 1 the only loss is masking: tiny for alpha = 0.05 at normal incidence.
    material = Microfacet((1, 1, 1), alpha=alpha)
    wo = direction_at(N_AXIS, 0, 0.0)

    def f_cos(w):
        return material.eval(batch(wo, len(w)), w, batch(N_AXIS, len(w)))[:, 0] * np.abs(w[:, 2])

    assert low <= integral(SphereGrid(N_AXIS), f_cos) <= high


def test_float32_column_major_in_float32_out():
    rows = 1000
    rng = np.random.default_rng(3)
    material = Microfacet("copper", roughness=0.4, kd=(0.2, 0.2, 0.2), ks=0.8)
    n = np.asfortranarray(batch(N_AXIS, rows).astype(np.float32))
    wo = np.asfortranarray(batch(direction_at(N_AXIS, 30, 0.0), rows).astype(np.float32))
    u = rng.random((rows, 2), dtype=np.float32)
    wi, weight = material.sample_weight(wo, n, u)
    for array in (wi, weight, material.eval(wo, wi, n), material.pdf(wo, wi, n)):
        assert array.dtype == np.float32
        assert np.isfinite(array).all()
    assert material.eval(wo, wi, n).flags.f_contiguous


def test_stacked_materials_shade_each_row_with_its_own_parameters():
    gold = Microfacet("gold", alpha=0.1)
    rough = Microfacet("aluminium", alpha=0.8, kd=(0.3, 0.3, 0.3), ks=0.5)
    rows = Microfacet.stack([gold, rough]).take(np.array([1, 0, 1]))
    rng = np.random.default_rng(4)
    wo = batch(direction_at(N_AXIS, 40, 0.0), 3).astype(np.float32)
    wi = batch(direction_at(N_AXIS, 30, 3.0), 3).astype(np.float32)
    n = batch(N_AXIS, 3).astype(np.float32)
    expected = [rough, gold, rough]
    f = rows.eval(wo, wi, n)
    pdf = rows.pdf(wo, wi, n)
    for k, material in enumerate(expected):
        np.testing.assert_allclose(f[k], material.eval(wo[:1], wi[:1], n[:1])[0], rtol=1e-4)
        np.testing.assert_allclose(pdf[k], material.pdf(wo[:1], wi[:1], n[:1])[0], rtol=1e-4)
    assert np.isfinite(rows.sample(wo, n, rng.random((3, 2), dtype=np.float32))).all()


def test_mirror_limit_reflects_into_the_mirror_direction():
    material = Microfacet((1, 1, 1), alpha=1e-3)
    rows = 1000
    wo = batch(direction_at(N_AXIS, 50, 0.0), rows)
    n = batch(N_AXIS, rows)
    wi = material.sample(wo, n, np.random.default_rng(5).random((rows, 2)))
    # GGX has long tails (P(tan theta_h > t) = alpha^2 / (alpha^2 + t^2)): look at the bulk.
    assert np.percentile(np.abs(wi - reflect(wo, n)).max(axis=1), 90) < 0.01


def test_parameters():
    assert Microfacet(roughness=0.5).alpha == 0.25  # alpha = roughness^2
    assert Microfacet(alpha=0.3).alpha == 0.3
    np.testing.assert_array_equal(Microfacet("copper").f0, METALS["copper"])
    for bad, problem in (
        (dict(roughness=0.5, alpha=0.2), "give roughness or alpha, not both"),
        (dict(alpha=0.0), "alpha must be in"),
        (dict(alpha=1.5), "alpha must be in"),
        (dict(f0="unobtainium"), "unknown metal 'unobtainium'"),
        (dict(f0=(1.2, 0.5, 0.5)), "f0 must be three numbers in"),
        (dict(kd=(0.6, 0.6, 0.6), ks=0.6), "kd . ks must be at most 1"),
        (dict(sampling="uniform"), "unknown sampling 'uniform'"),
    ):
        with pytest.raises(ValueError, match=problem):
            Microfacet(**bad)
    assert "alpha=0.25" in repr(Microfacet(roughness=0.5))
