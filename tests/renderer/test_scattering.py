"""Reflection, refraction and Fresnel (``ptlab.scattering``) against the laws they come from.

Everything here is deterministic (fixed seeds); the tolerances are float64 rounding.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ptlab.scattering import F_schlick, FresnelSplit, fresnel_dielectric, reflect, refract
from ptlab.vectors import cross, dot

GLASS = 1.5
ROWS = 1000


def frames(seed: int, rows: int = ROWS) -> tuple[np.ndarray, np.ndarray]:
    """(rows, 3) random unit normals ``n`` and unit ``wo`` above them, at every angle."""
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(rows, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    wo = rng.normal(size=(rows, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    return n, wo * np.sign(dot(wo, n))[:, None]


def sin_theta(w: np.ndarray, n: np.ndarray) -> np.ndarray:
    return np.linalg.norm(cross(w, n), axis=1)


def test_reflect_is_an_involution_at_the_same_angle():
    n, wo = frames(0)
    wi = reflect(wo, n)
    np.testing.assert_allclose(reflect(wi, n), wo, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-14)
    np.testing.assert_allclose(dot(wi, n), dot(wo, n), atol=1e-15)  # theta_r = theta_o
    # In the plane of wo and n, on the other side of n: wo + wi is along n.
    np.testing.assert_allclose(cross(wo + wi, n), 0, atol=1e-14)
    np.testing.assert_allclose(reflect(n, n), n, atol=1e-14)  # straight back


@pytest.mark.parametrize("eta_rel", [GLASS, 1 / GLASS, 2.4])
def test_refract_obeys_snells_law(eta_rel):
    n, wo = frames(1)
    if eta_rel < 1:  # leaving the denser side: only directions inside the critical angle
        inside = sin_theta(wo, n) < eta_rel
        n, wo = n[inside], wo[inside]
    wt = refract(wo, n, eta_rel)
    np.testing.assert_allclose(np.linalg.norm(wt, axis=1), 1, atol=1e-14)
    assert (dot(wt, n) < 0).all(), "the refracted ray goes through, to the far side"
    # eta_o sin(theta_o) = eta_t sin(theta_t), and wt in the plane of wo and n, across n.
    np.testing.assert_allclose(eta_rel * sin_theta(wt, n), sin_theta(wo, n), atol=1e-14)
    np.testing.assert_allclose(dot(cross(wo, n), wt), 0, atol=1e-14)
    np.testing.assert_allclose(refract(n, n, eta_rel), -n, atol=1e-15)  # straight through


def test_refraction_is_reversible_with_per_row_indices():
    n, wo = frames(2)
    eta = np.random.default_rng(3).uniform(1.01, 3.0, ROWS)
    wt = refract(wo, n, eta)
    # Light coming back along the refracted ray, from the far side (-n faces wt), leaves along wo.
    np.testing.assert_allclose(refract(wt, -n, 1 / eta), wo, atol=1e-13)


def test_total_internal_reflection_beyond_the_critical_angle():
    critical = math.asin(1 / GLASS)
    theta = np.linspace(critical + 1e-6, math.pi / 2, 50)
    n = np.tile([0.0, 0.0, 1.0], (len(theta), 1))
    wo = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    assert (fresnel_dielectric(np.cos(theta), 1 / GLASS) == 1).all()
    assert np.isfinite(refract(wo, n, 1 / GLASS)).all(), "no NaN where there is no refraction"
    just_inside = np.array([math.cos(critical - 1e-3)])
    assert fresnel_dielectric(just_inside, 1 / GLASS)[0] < 1


def test_fresnel_dielectric_known_values():
    # Normal incidence: ((eta - 1) / (eta + 1))^2, from either side; grazing: 1.
    for eta in (GLASS, 1 / GLASS, 2.4):
        assert fresnel_dielectric(np.array([1.0]), eta)[0] == pytest.approx(((eta - 1) / (eta + 1)) ** 2)
        assert fresnel_dielectric(np.array([0.0]), eta)[0] == pytest.approx(1.0)
    # Brewster's angle tan(theta) = eta: the parallel part vanishes, R = r_perp^2 / 2.
    brewster = math.atan(GLASS)
    cos_i, cos_t = math.cos(brewster), math.cos(math.pi / 2 - brewster)
    r_perp = (cos_i - GLASS * cos_t) / (cos_i + GLASS * cos_t)
    assert fresnel_dielectric(np.array([cos_i]), GLASS)[0] == pytest.approx(r_perp**2 / 2)


def test_fresnel_is_the_same_from_both_sides():
    # Light crossing back along the refracted ray reflects the same fraction (Stokes relations).
    n, wo = frames(4)
    wt = refract(wo, n, GLASS)
    outside = fresnel_dielectric(dot(wo, n), GLASS)
    inside = fresnel_dielectric(dot(wt, -n), 1 / GLASS)
    # (Near grazing the inside angle nears the critical one, where F is steep: rounding grows.)
    np.testing.assert_allclose(outside, inside, rtol=1e-10)
    assert ((outside >= 0) & (outside <= 1)).all()


def test_fresnel_keeps_float32():
    cos_theta = np.linspace(0, 1, 11, dtype=np.float32)
    eta_rel = np.full(11, 1 / GLASS, dtype=np.float32)
    assert fresnel_dielectric(cos_theta, eta_rel).dtype == np.float32


def test_schlick_fresnel_runs_from_f0_to_one():
    f0 = np.array([0.9, 0.5, 0.1])
    fresnel = F_schlick(np.array([1.0, 0.0, 0.5]), f0)
    np.testing.assert_allclose(fresnel[0], f0)
    np.testing.assert_allclose(fresnel[1], 1.0)
    np.testing.assert_allclose(fresnel[2], f0 + (1 - f0) * 0.5**5)
    # One F0 per row.
    rows = F_schlick(np.array([1.0, 0.0]), np.array([[0.2, 0.3, 0.4], [0.5, 0.6, 0.7]]))
    np.testing.assert_allclose(rows, [[0.2, 0.3, 0.4], [1.0, 1.0, 1.0]])


def test_the_fresnel_split_uses_the_formulas_it_is_given_and_weighs_both_ways():
    # With a Fresnel reflectance of 1/4 everywhere (given in place of the library's, as a
    # student's is), both branches carry 1/4 and 3/4 T / eta_rel^2, and the random choice
    # reflects exactly where u < 1/4, with weights 1 and T / eta_rel^2.
    n, wo = frames(7)
    outside = np.arange(ROWS) % 2 == 0

    def quarter(cos_theta, eta_rel):
        return np.full(len(cos_theta), 0.25)

    split = FresnelSplit.at(wo, n, GLASS, outside, fresnel=quarter)
    eta_rel = np.where(outside, GLASS, 1 / GLASS)
    np.testing.assert_allclose(split.reflected, reflect(wo, n))
    np.testing.assert_allclose(split.refracted, refract(wo, n, eta_rel))
    transmittance = np.array([1.0, 0.5, 0.25])
    (_, reflected), (_, refracted) = split.both(transmittance)
    np.testing.assert_allclose(reflected, 0.25)
    np.testing.assert_allclose(refracted, 0.75 * transmittance / (eta_rel**2)[:, None])
    u = (np.arange(ROWS) + 0.5) / ROWS
    wi, weight = split.choose(u, transmittance)
    chose_reflection = u < 0.25
    np.testing.assert_array_equal(wi[chose_reflection], split.reflected[chose_reflection])
    np.testing.assert_array_equal(wi[~chose_reflection], split.refracted[~chose_reflection])
    np.testing.assert_allclose(weight[chose_reflection], 1)
    expected = transmittance / (eta_rel**2)[:, None]
    np.testing.assert_allclose(weight[~chose_reflection], expected[~chose_reflection])
    # The library's own formulas by default.
    np.testing.assert_allclose(
        FresnelSplit.at(wo, n, GLASS, outside).R, fresnel_dielectric(dot(wo, n), eta_rel)
    )
