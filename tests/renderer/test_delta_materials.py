"""Mirror and glass: exact directions, Fresnel weights, the two ways of saying which side is out.

Everything here is deterministic: stratified u (``hammersley``) instead of random numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import Recording, assert_every_call_mixes_its_rows

from ptlab.grading import check_material
from ptlab.grading.checks import batch, direction_at
from ptlab.grading.delta import hammersley
from ptlab.materials import Dielectric, Mirror
from ptlab.scattering import fresnel_dielectric, reflect
from ptlab.vectors import dot

N_AXIS = np.array([0.0, 0.0, 1.0])
ROWS = 2**14


def setup(degrees: float, side: float = 1.0):
    """wo at ``degrees`` on the outside (side 1) or inside (side -1) of a surface with normal +z."""
    wo = direction_at(side * N_AXIS, degrees, 0.4)
    return batch(wo, ROWS), batch(N_AXIS, ROWS), hammersley(ROWS)


@pytest.mark.parametrize("fresnel", [False, True])
def test_mirror_reflects_exactly_with_its_reflectance(fresnel):
    material = Mirror((0.9, 0.5, 0.2), fresnel=fresnel)
    for degrees in (0, 30, 60, 89):
        wo, n, u = setup(degrees)
        wi, weight = material.sample_weight(wo, n, u)
        np.testing.assert_allclose(wi, reflect(wo, n), atol=1e-15)
        np.testing.assert_allclose(dot(wi, n), dot(wo, n), atol=1e-15)
        cos_theta = math.cos(math.radians(degrees))
        expected = material.reflectance + (1 - material.reflectance) * (1 - cos_theta) ** 5 * fresnel
        np.testing.assert_allclose(weight, np.broadcast_to(expected, weight.shape), atol=1e-12)
        assert (material.eval(wo, wi, n) == 0).all()
        assert (material.pdf(wo, wi, n) == 0).all()
    wo, n, u = setup(30, side=-1)
    assert (material.sample_weight(wo, n, u)[1] == 0).all(), "nothing is reflected from below"


@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("degrees", [0, 20, 40, 60, 85])
def test_glass_reflects_a_fresnel_fraction_and_refracts_by_snell(side, degrees):
    eta = 1.5
    material = Dielectric(eta, transmittance=(1.0, 0.8, 0.6))
    wo, n, u = setup(degrees, side)
    wi, weight = material.sample_weight(wo, n, u)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1, atol=1e-12)
    cos_theta_o = abs(math.cos(math.radians(degrees)))
    eta_rel = eta if side > 0 else 1 / eta
    reflectance = fresnel_dielectric(np.array([cos_theta_o]), eta_rel)[0]
    reflected = np.abs(wi - reflect(wo, n)).max(axis=1) < 1e-12
    # Stratified u: the fraction reflected is the Fresnel reflectance to within 1/ROWS.
    assert reflected.mean() == pytest.approx(reflectance, abs=2 / ROWS)
    np.testing.assert_allclose(weight[reflected], 1.0)
    refracted = ~reflected
    if refracted.any():
        # Snell: sin(theta_o) = eta_rel sin(theta_t), on the other side, transmittance / eta_rel^2.
        wt, nt = wi[refracted], n[refracted]
        sin_t = np.linalg.norm(wt - dot(wt, nt)[:, None] * nt, axis=1)
        np.testing.assert_allclose(sin_t * eta_rel, math.sin(math.radians(degrees)), atol=1e-12)
        assert (dot(wi[refracted], n[refracted]) * side < 0).all()
        np.testing.assert_allclose(
            weight[refracted], np.broadcast_to(material.transmittance / eta_rel**2, weight[refracted].shape)
        )
    else:
        assert side < 0, "only total internal reflection"
        assert math.sin(math.radians(degrees)) * eta >= 1, "only total internal reflection"


def test_front_flag_with_the_renderers_normal_gives_the_same_as_the_outward_normal():
    material = Dielectric(1.33)
    for side in (1.0, -1.0):
        wo, n, u = setup(30, side)
        facing = n * np.sign(dot(wo, n))[:, None]  # the renderer turns n toward wo
        expected = material.sample_weight(wo, n, u)
        got = material.sample_weight(wo, facing, u, np.full(ROWS, side > 0))
        for a, b in zip(expected, got, strict=True):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(material.sample(wo, facing, u, np.full(ROWS, side > 0)), got[0])


def test_refraction_is_reversible_and_conserves_flux():
    material = Dielectric(1.5)
    wo, n, u = setup(50)
    u = np.full((ROWS, 2), 0.999)  # always refract (R < 0.999 at 50 degrees)
    wt, weight = material.sample_weight(wo, n, u)
    back, weight_back = material.sample_weight(wt, n, u)
    np.testing.assert_allclose(back, wo, atol=1e-12)
    # Radiance is scaled by 1/eta^2 going in and eta^2 coming out: the round trip keeps it.
    np.testing.assert_allclose(weight * weight_back, 1.0)


def test_float32_and_stacking():
    materials = [Dielectric(1.5), Dielectric(2.4, transmittance=(0.5, 0.5, 0.5))]
    rows = Dielectric.stack(materials).take(np.array([1, 0]))
    wo = batch(direction_at(N_AXIS, 10, 0.0), 2).astype(np.float32)
    n = batch(N_AXIS, 2).astype(np.float32)
    u = np.full((2, 2), 0.99, dtype=np.float32)
    wi, weight = rows.sample_weight(wo, n, u, np.array([True, True]))
    assert wi.dtype == np.float32
    assert weight.dtype == np.float32
    np.testing.assert_allclose(weight[0], 0.5 / 2.4**2, rtol=1e-6)
    np.testing.assert_allclose(weight[1], 1 / 1.5**2, rtol=1e-6)
    mirrors = Mirror.stack([Mirror((1, 0, 0)), Mirror((0, 1, 0))]).take(np.array([1, 1, 0]))
    up = batch(N_AXIS, 3).astype(np.float32)
    _, weight = mirrors.sample_weight(up, up, np.zeros((3, 2), dtype=np.float32))
    np.testing.assert_array_equal(weight, [[0, 1, 0], [0, 1, 0], [1, 0, 0]])


@pytest.mark.parametrize(
    "material",
    [
        Mirror(),
        Mirror((0.9, 0.6, 0.3), fresnel=True),
        Dielectric(1.33),
        Dielectric(1.5, transmittance=(0.9, 0.8, 0.7)),
        Dielectric(2.4),
    ],
    ids=repr,
)
def test_grader_passes_the_delta_materials(material):
    report = check_material(material)
    assert report.passed, str(report)


def test_bad_parameters_are_refused():
    for make, problem in (
        (lambda: Mirror((1.2, 0, 0)), "reflectance must be three numbers in"),
        (lambda: Dielectric(0.0), "eta must be an index of refraction"),
        (lambda: Dielectric(1.5, (2, 0, 0)), "transmittance must be three numbers in"),
    ):
        with pytest.raises(ValueError, match=problem):
            make()


# -- the probes cannot be told from a render ---------------------------------------------------


class BrightUnlessRowsRepeat(Mirror):
    """A white mirror that weighs its reflection 1 when every row of a call has the same wo and
    n (as the delta checks' probes once did) and 1.5 otherwise, as in every render."""

    def sample_weight(self, wo, n, u, front=None):
        wi, weight = super().sample_weight(wo, n, u, front)
        repeated = bool((wo == wo[:1]).all() and (n == n[:1]).all())
        return wi, weight * (1.0 if repeated else 1.5)


def test_a_mirror_right_only_for_repeated_rows_fails():
    report = check_material(BrightUnlessRowsRepeat())
    assert report["energy"].verdict == "FAIL"
    assert report["row independence"].verdict == "FAIL"
    assert "depends on the other rows of the batch" in report["row independence"].hint


@pytest.mark.parametrize("material", [Mirror((0.9, 0.6, 0.3), fresnel=True), Dielectric(1.5)], ids=repr)
def test_no_delta_probe_repeats_one_wo_or_n_on_every_row(material):
    recording = Recording(material)
    assert check_material(recording).passed
    assert_every_call_mixes_its_rows(recording.calls)
