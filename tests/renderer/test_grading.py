"""The grading harness: correct materials pass, each classic mistake fails with its hint.

``check_material`` is deterministic for a seed, so these tests cannot flake; they run with
fewer samples per wo than the default 10^6 to stay fast (weaker tests, same false-alarm
rates: at most about 1.2e-3 a material and seed, so the 40-odd gradings of right materials
here pass at their fixed seeds or fail on every run). ``scripts/false_alarm_rate.py``
measures the false-alarm rate over fresh seeds.
"""

from __future__ import annotations

import itertools
import math
import time
from pathlib import Path

import numpy as np
import pytest
import wrong_materials as wrong
from helpers import Recording, assert_every_call_mixes_its_rows

from ptlab.cli import main as ptlab_main
from ptlab.grading import check_material, checks, write_plots
from ptlab.grading.checks import chi2_sf, pooled_chi_square, z_two_sided
from ptlab.grading.probes import WALLS, Kept, Rotations, Walls, rows_of
from ptlab.grading.sphere import SphereGrid
from ptlab.materials import Diffuse, Microfacet

SAMPLES = 100_000
WRONG_FILE = str(Path(wrong.__file__))


# -- correct materials pass -----------------------------------------------------------------

BUILT_IN = (
    [Diffuse((0.8, 0.5, 0.2)), Diffuse((1, 1, 1), sampling="uniform")]
    + [
        Microfacet((1, 1, 1), alpha=alpha, sampling=sampling)
        for alpha in (0.05, 0.2, 0.5, 1.0)
        for sampling in ("vndf", "hemisphere")
    ]
    + [
        Microfacet("copper", alpha=0.1, kd=(0.4, 0.4, 0.4), ks=0.6),
        Microfacet("gold", roughness=0.7, kd=(0.5, 0.2, 0.1), ks=0.5, sampling="hemisphere"),
    ]
)


@pytest.mark.slow
@pytest.mark.parametrize("material", BUILT_IN, ids=repr)
def test_built_in_materials_pass_up_to_85_degrees(material):
    report = check_material(material, seed=1, samples=SAMPLES, wo_degrees=(0, 45, 85))
    assert report.passed, str(report)


def test_walter_half_vector_sampling_with_its_jacobian_passes():
    assert check_material(wrong.WalterSampling(), samples=SAMPLES).passed


def test_default_run_is_the_issues_and_reproducible():
    material = Microfacet("gold", roughness=0.5)
    a = check_material(material, seed=3, samples=20_000)
    b = check_material(material, seed=3, samples=20_000)
    assert [c.statistic for c in a.checks] == [c.statistic for c in b.checks]
    assert {c.name for c in a.checks} == {
        "consistency",
        "chi-square",
        "pdf normalisation",
        "energy",
        "reflectance",
        "estimator agreement",
        "sample_weight",
        "reciprocity",
        "float32",
        "row independence",
    }
    text = str(a)
    for column in ("check", "statistic", "threshold", "verdict", "hint"):
        assert column in text.splitlines()[1]
    assert text.endswith("PASSED")


# -- wrong materials fail with the right hint ---------------------------------------------------

MISTAKES = [
    ("MissingCosineInPdf", "chi-square", "misses a factor cos"),
    ("SkewedAzimuth", "chi-square", "the samples' azimuth about n is uneven"),
    ("AzimuthFromTheSameU", "chi-square", "azimuth about n is uneven"),
    ("BrighterWithFewNormals", "energy", "reflects more light than it receives"),
    ("BrighterWithFewNormals", "row independence", "depends on the other rows of the batch"),
    ("RightOnlyAtTheGradersAngles", "energy", "reflects more light than it receives"),
    ("WrongHemisphereOnSomeRows", "chi-square", "pdf returns 0 where sample goes"),
    ("DiskWithoutSqrt", "chi-square", "does not follow pdf"),
    ("VisibleNormalsPdfWithoutJacobian", "chi-square", "Jacobian 1 / (4 |wo . h|)"),
    ("FlippedBelow", "pdf normalisation", "flip a wi that landed below the surface back up"),
    ("SchlickTimesFive", "energy", "grows toward grazing wo"),
    ("FresnelOfNormal", "reciprocity", "depends on wo or wi alone"),
    ("EvalNotZeroBelow", "consistency", "not 0 below the surface"),
    ("PdfNotClamped", "consistency", "negative"),
    ("SampleNotNormalised", "consistency", "normalise them"),
    ("WeightOfUniformSampling", "sample_weight", "multiplies by cos(theta_i) twice"),
    ("MissingCosineInWeight", "sample_weight", "misses the factor cos"),
    ("CosineTwice", "reciprocity", "cosine counted twice"),
    ("PdfOffByConstant", "chi-square", "2x too small"),
    ("PdfOffByConstant", "pdf normalisation", "2x too small"),
    ("UniformSamplingCosinePdf", "chi-square", "cosine pdf for uniform sampling"),
    ("CosineSamplingUniformPdf", "chi-square", "1/(2 pi) while sampling cosine-weighted"),
    ("WrongHemisphere", "chi-square", "wrong hemisphere"),
    ("NonReciprocal", "reciprocity", "depends on wo or wi alone"),
    ("AlbedoAboveOne", "energy", "albedo or F0 above 1"),
    ("MissingOneOverPi", "energy", "without the 1/pi"),
    ("NanAtGrazing", "consistency", "NaN at grazing angles"),
    ("RightOnlyForRepeatedRows", "energy", "without the 1/pi"),
    ("DependsOnCallSize", "row independence", "depends on the other rows of the batch"),
    ("DependsOnRowOrder", "row independence", "depends on the other rows of the batch"),
    ("DependsOnMeanWo", "row independence", "depends on the other rows of the batch"),
    ("HalfVectorPdfWithoutJacobian", "chi-square", "Jacobian 1 / (4 |wo . h|)"),
    ("MirrorOfIncomingDirection", "directions", "neither the mirror reflection"),
    ("MirrorWithEval", "consistency", "both return 0"),
    ("GlassWithoutInversion", "directions", "inside and outside swapped"),
    ("GlassWeightedByFresnel", "Fresnel weights", "probability F and weigh it 1"),
]


@pytest.fixture(scope="module")
def reports():
    """One report per wrong material, shared by the hint tests."""
    return {
        name: check_material(getattr(wrong, name)(), samples=SAMPLES)
        for name in dict.fromkeys(name for name, _, _ in MISTAKES)
    }


@pytest.mark.slow
@pytest.mark.parametrize(("name", "check", "phrase"), MISTAKES, ids=[f"{m[0]}-{m[1]}" for m in MISTAKES])
def test_wrong_material_fails_with_the_right_hint(reports, name, check, phrase):
    report = reports[name]
    assert not report.passed
    assert report[check].verdict == "FAIL", str(report)
    assert phrase in report[check].hint, str(report)


@pytest.mark.slow
def test_each_wrong_material_fails_only_where_it_is_wrong(reports):
    # The checks that a mistake cannot touch stay green: the hints point at one place.
    assert reports["CosineTwice"].failed == ["reciprocity"]
    assert reports["NonReciprocal"].failed == ["reciprocity"]
    assert reports["MissingCosineInWeight"].failed == ["sample_weight"]
    assert reports["AlbedoAboveOne"].failed == ["energy"]
    assert reports["NanAtGrazing"].failed == ["consistency"]
    assert reports["DependsOnCallSize"].failed == ["row independence"]
    assert reports["SkewedAzimuth"].failed == ["chi-square"]
    assert reports["FresnelOfNormal"].failed == ["reciprocity"]
    assert reports["WeightOfUniformSampling"].failed == ["sample_weight"]


# -- every wrong material of the collection fails, every right one passes --------------------------

#: The collection's right materials, and the library's grey Diffuse (one number for its albedo).
RIGHT = [*wrong.RIGHT, "grey Diffuse"]


def _material(name: str):
    return Diffuse(0.5) if name == "grey Diffuse" else getattr(wrong, name)()


@pytest.mark.slow
@pytest.mark.parametrize("name", wrong.WRONG)
def test_every_wrong_material_fails(name):
    # Seeds 0 and 1: a wrong material fails at every seed, not at one chosen for it.
    for seed in (0, 1):
        report = check_material(_material(name), seed=seed, samples=SAMPLES)
        assert not report.passed, str(report)


@pytest.mark.slow
@pytest.mark.parametrize("name", RIGHT)
def test_every_right_material_passes(name):
    # Each passes at fixed seeds; a false alarm (about 1.2e-3 a grading) would show on every run.
    for seed in (0, 1):
        report = check_material(_material(name), seed=seed, samples=SAMPLES)
        assert report.passed, str(report)
        assert set(report.warned) <= {"float32"}, str(report)


def test_the_collection_holds_thirty_wrong_materials_and_five_right_ones():
    assert len(set(wrong.WRONG)) >= 30
    assert len(set(RIGHT)) >= 5
    assert not set(wrong.WRONG) & set(wrong.RIGHT)
    assert set(wrong.__all__) == set(wrong.WRONG) | set(wrong.RIGHT)


def test_a_grey_diffuse_returns_a_colour_per_row():
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    f = Diffuse(0.5).eval(wo, wo[::-1], np.array([[0.0, 0.0, 1.0]] * 2))
    assert f.shape == (2, 3)
    np.testing.assert_allclose(f, 0.5 / math.pi)


def test_a_material_that_raises_fails_instead_of_crashing():
    class Broken(Diffuse):
        def pdf(self, wo, wi, n):
            raise ZeroDivisionError("oops")

    report = check_material(Broken(), samples=5000)
    assert not report.passed
    assert "pdf raised ZeroDivisionError: oops" in report["chi-square"].hint


@pytest.mark.slow
def test_plots_of_a_failed_chi_square(tmp_path, reports):
    written = write_plots(reports["UniformSamplingCosinePdf"], tmp_path)
    assert len(written) == 9
    assert all(p.suffix == ".png" and p.stat().st_size > 0 for p in written)
    assert write_plots(check_material(Diffuse(), samples=5000), tmp_path / "none") == []


# -- pieces -------------------------------------------------------------------------------------


def test_chi_square_p_value_is_scipys_and_pooling_keeps_totals():
    stats = pytest.importorskip("scipy.stats")
    assert chi2_sf(4200.0, 4095) == pytest.approx(stats.chi2.sf(4200.0, 4095), rel=1e-12)
    assert z_two_sided(0.05) == pytest.approx(1.959964, abs=1e-6)
    # Three small cells (expected 1, 2, 1) pool into one of 4, which joins the smallest regular one.
    statistic, dof = pooled_chi_square([3, 10, 10, 0, 1, 2], [1, 10, 10, 0, 2, 1])
    assert (statistic, dof) == (pytest.approx(2**2 / 14), 1)
    statistic, dof = pooled_chi_square([0, 20, 20], [0, 10, 30])
    assert (statistic, dof) == (pytest.approx(100 / 10 + 100 / 30), 1)


def test_sphere_grid_cells_have_equal_area_and_integration_is_exact_for_smooth_functions():
    grid = SphereGrid(np.array([0.3, -0.4, 0.866]) / np.linalg.norm([0.3, -0.4, 0.866]), 16, 32)

    # Two lobes at once: 1 and x^2, then 2 and y^2.
    def f(lobe, w):
        return np.column_stack([1.0 + lobe, w[np.arange(len(w)), lobe] ** 2])

    totals, errors = grid.integrate_lobes(f, lambda fine, area: 1e-12 + 0 * fine, 2)
    assert totals.shape == (2, grid.cells, 2)
    assert errors.shape == (2, 2)
    np.testing.assert_allclose(totals[0, :, 0], 4 * math.pi / grid.cells, rtol=1e-12)
    np.testing.assert_allclose(totals[1, :, 0], 8 * math.pi / grid.cells, rtol=1e-12)
    np.testing.assert_allclose(totals[:, :, 1].sum(axis=1), 4 * math.pi / 3, rtol=1e-10)
    rng = np.random.default_rng(0)
    w = rng.normal(size=(10_000, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    assert grid.histogram(w).sum() == 10_000


# -- the command ------------------------------------------------------------------------------


@pytest.mark.subprocess
def test_grade_exit_codes(tmp_path, capsys):
    assert ptlab_main(["grade", f"{PLAIN}:Lambertian", "--samples", "20000"]) == 0
    assert "PASSED" in capsys.readouterr().out
    assert (
        ptlab_main(
            [
                "grade",
                f"{WRONG_FILE}:PdfOffByConstant",
                "--samples",
                "20000",
                "--plots",
                str(tmp_path / "plots"),
            ]
        )
        == 1
    )
    out = capsys.readouterr().out
    assert "FAILED" in out
    assert "2x too small" in out
    assert len(list((tmp_path / "plots").glob("*.png"))) == 9
    assert (
        ptlab_main(
            ["grade", f"{PLAIN}:Lambertian", "--args", '{"albedo": [0.2, 0.5, 0.9]}', "--samples", "20000"]
        )
        == 0
    )


@pytest.mark.subprocess
def test_grade_leaves_out_the_lambertian_the_checks_hand_to_students(tmp_path, capsys):
    path = tmp_path / "material.py"
    path.write_text(
        "from ptlab.course.given import FlakyDiffuse\n"
        "class Lambertian:\n"
        "    def eval(self, wo, wi, n):\n        return FlakyDiffuse().eval(wo, wi, n)\n"
        "    def pdf(self, wo, wi, n):\n        return FlakyDiffuse().pdf(wo, wi, n)\n"
        "    def sample(self, wo, n, u):\n        return FlakyDiffuse().sample(wo, n, u)\n"
    )
    assert ptlab_main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    out = " ".join(capsys.readouterr().out.split())  # (the table wraps its hints)
    assert "FAILED" in out
    assert "eval raised NotInKitError: ptlab.course.given.FlakyDiffuse.eval is left out of the kit" in out


@pytest.mark.subprocess
def test_grade_runs_a_material_without_the_librarys_materials(capsys):
    # WalterSampling is the library's microfacet material with another sampler: right, but
    # built on a material that is not in the kit ``ptlab grade`` runs it with.
    assert ptlab_main(["grade", f"{WRONG_FILE}:WalterSampling", "--samples", "20000"]) == 2
    err = capsys.readouterr().err
    assert "ptlab.materials.microfacet.Microfacet.__init__ is left out of the kit" in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("name", "code", "phrase"),
    [
        ("SkewedAzimuth", 1, "azimuth about n is uneven"),
        ("BrighterWithFewNormals", 1, "FAILED: energy"),
        ("RightOnlyAtTheGradersAngles", 1, "FAILED: energy"),
        ("RightVisibleNormals", 0, "PASSED"),
        ("RightFloat64Albedo", 0, "PASSED, with warnings: float32"),
    ],
)
def test_ptlab_grade_of_the_collection_in_the_students_process(capsys, name, code, phrase):
    # (10^5 samples per wo: the exercises' harness has 2 x 10^5, ptlab grade's default 10^6.)
    assert ptlab_main(["grade", f"{WRONG_FILE}:{name}", "--samples", "100000"]) == code
    out = " ".join(capsys.readouterr().out.split())  # (the table wraps its hints)
    assert phrase in out, out


@pytest.mark.subprocess
@pytest.mark.parametrize(
    ("target", "args", "message"),
    [
        ("missing.py:Material", "{}", "no such file"),
        ("{wrong}:NoSuchClass", "{}", "no class or object named"),
        ("{wrong}:WalterSampling", "{not json", "not valid JSON"),
        ("{wrong}:WalterSampling", '{"colour": 1}', "raised TypeError"),
        ("{wrong}:ALBEDO", "{}", "is not a material"),
        ("{wrong}", "{}", "expected FILE.py:Name"),
        ("{syntax}:Anything", "{}", "syntax error"),
    ],
)
def test_grade_cannot_load_gives_exit_2_and_one_line(tmp_path, capsys, target, args, message):
    syntax = tmp_path / "broken.py"
    syntax.write_text("def f(:\n")
    target = target.format(wrong=WRONG_FILE, syntax=syntax)
    assert ptlab_main(["grade", target, "--args", args]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


# -- any object with the homework's three functions; float32 arithmetic ------------------------

PLAIN = Path(__file__).parents[1] / "exercises" / "06_right_plain_class_float32.py"


class PlainDiffuse:
    """The homework's three functions and nothing else (no base class)."""

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return np.outer(above * 0.7 / math.pi, np.ones(3))

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / math.pi, 0.0)

    def sample(self, wo, n, u):
        from ptlab.sampling import cosine_hemisphere_around

        return cosine_hemisphere_around(n, u)


def test_an_object_with_only_the_three_functions_is_a_material():
    report = check_material(PlainDiffuse(), samples=SAMPLES)
    assert report.passed, str(report)
    assert report["sample_weight"].verdict == "pass"  # derived from the three, and checked


@pytest.mark.subprocess
def test_ptlab_grade_takes_a_class_that_inherits_from_nothing(capsys):
    assert (
        ptlab_main(
            ["grade", f"{PLAIN}:Lambertian", "--samples", "20000", "--args", '{"albedo": [0.8, 0.5, 0.2]}']
        )
        == 0
    )
    out = capsys.readouterr().out
    assert out.startswith("Lambertian object")
    assert "PASSED" in out


class Float32Pi(Diffuse):
    """A right Lambertian whose pi is np.float32(math.pi): its pdf integrates to 1 - 2.8e-8,
    and with cosine sampling every sample's f cos / pdf is the same, so no noise covers it."""

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return above[:, None] * self.albedo / np.float32(math.pi)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / np.float32(math.pi), 0.0)


def test_float32_rounding_in_a_material_is_not_a_mistake():
    # 10^6 samples at 80 degrees: there the tolerance without the float32 slack was 3e-9.
    report = check_material(Float32Pi((0.8, 0.8, 0.8)), samples=1_000_000, wo_degrees=(80,))
    assert report["estimator agreement"].verdict == "pass", str(report)


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_material_that_hangs_stops_within_its_time_limit(tmp_path, capsys):
    path = tmp_path / "slow.py"
    path.write_text(
        PLAIN.read_text() + "\n\nclass Slow(Lambertian):\n"
        "    def pdf(self, wo, wi, n):\n        while True:\n            pass\n"
    )
    start = time.monotonic()
    assert ptlab_main(["grade", f"{path}:Slow", "--samples", "20000", "--time-limit", "3"]) == 1
    assert time.monotonic() - start < 30
    out = capsys.readouterr().out
    assert "FAILED: took longer than 3 s and was stopped (in Slow.pdf)" in out


# -- the probes cannot be told from a render ---------------------------------------------------


def test_no_probe_repeats_one_wo_or_n_on_every_row():
    material = Recording(Microfacet("gold", roughness=0.4))
    assert check_material(material, samples=20_000).passed
    assert len(material.calls) > 100
    assert_every_call_mixes_its_rows(material.calls)


def test_probes_look_like_a_render_a_few_walls_each_on_many_rows():
    material = Recording(Diffuse((0.8, 0.5, 0.2)))
    samples = 300_000
    assert check_material(material, samples=samples).passed
    # measure's sample calls (the first large ones): a render's sizes (a quarter of a
    # render's batch up to one), the last what is left of its 3 x 300 000 rows.
    sizes = [len(wo) for method, wo, _ in material.calls if method == "sample"]
    first = next(k for k, size in enumerate(sizes) if size > 10_000)
    measured = list(
        itertools.takewhile(lambda k: sum(sizes[first:k]) < 3 * samples, range(first, len(sizes)))
    )
    assert sum(sizes[k] for k in measured) == 3 * samples
    assert all(checks.RENDER_BATCH // 4 <= sizes[k] <= checks.RENDER_BATCH for k in measured[:-1])
    samples_calls = [(wo, n) for method, wo, n in material.calls if method == "sample"]
    for k in measured:
        wo, n = samples_calls[k]
        normals, rows = np.unique(n, axis=0, return_counts=True)
        # A few normals (a wall's exactly the same on all of its rows), each on many rows ...
        assert len(normals) == WALLS
        assert rows.min() > len(wo) / (2 * WALLS), rows
        # ... and on a wall, no two rows share wo (but the head-on ones, where wo is n).
        on_wall = (n == normals[0]).all(axis=1) & (wo != n).any(axis=1)
        assert len(np.unique(wo[on_wall], axis=0)) == on_wall.sum()
    # (The other calls: the quadrature's and consistency's on walls too, reciprocity's and
    # float32's on a curved surface, a normal per row; none one wo or n on every row.)
    assert_every_call_mixes_its_rows(material.calls)


def test_a_walls_normal_is_the_same_to_the_bit_and_its_frame_fixed():
    rng = np.random.default_rng(3)
    walls = Walls(rng)
    turn = walls.rotations(rng, 10_000)
    n = turn.apply(checks.Z)
    for k in range(walls.count):
        on = turn.wall == k
        assert (n[on] == n[on][0]).all()
    # to_wall undoes the wall's frame only: n goes to +z, and wo keeps its twist about it.
    np.testing.assert_allclose(turn.to_wall(n), np.tile(checks.Z, (10_000, 1)), atol=1e-15)
    wo = turn.apply(np.array([0.6, 0.0, 0.8]))
    local = turn.to_wall(wo)
    np.testing.assert_allclose(local[:, 2], 0.8, atol=1e-15)
    assert np.ptp(np.arctan2(local[:, 1], local[:, 0])) > 6  # (twisted over the whole circle)
    np.testing.assert_allclose(turn.undo(wo), np.tile([0.6, 0.0, 0.8], (10_000, 1)), atol=1e-15)
    # A curved surface's rows each have a normal of their own.
    assert len(np.unique(Rotations.each_row(rng, 1000).apply(checks.Z), axis=0)) == 1000


def test_the_wo_angles_move_per_seed_within_their_bounds():
    angles = [checks.lobe_angles((0.0, 45.0, 80.0, 85.0), np.random.default_rng(seed)) for seed in range(50)]
    assert all(a[0] == 0.0 for a in angles)  # (head-on stays head-on)
    assert all(40 <= a[1] <= 50 and 75 <= a[2] <= 85 and 82.5 <= a[3] <= 87.5 for a in angles)
    assert len({a[1] for a in angles}) > 25
    assert checks.lobe_angles((45.0,), np.random.default_rng(7)) == checks.lobe_angles(
        (45.0,), np.random.default_rng(7)
    )


def test_a_skewed_azimuth_passes_every_lobe_and_fails_on_the_walls():
    # phi = 2 pi u1^2 with the cosine pdf: each lobe's rows, turned back by their own twist,
    # spread the skew evenly (every wo's p-value is fine); each wall's frame keeps it.
    report = check_material(wrong.SkewedAzimuth(), samples=SAMPLES)
    chi_square = report["chi-square"]
    assert chi_square.verdict == "FAIL"
    assert min(lobe["p"] for lobe in chi_square.data["lobes"]) > 1e-4, str(report)
    assert len(chi_square.data["walls"]) == WALLS  # (every wall fails)
    assert "wall" in chi_square.statistic


def test_a_walls_test_is_even_in_azimuth_per_band():
    grid = SphereGrid(checks.Z, 4, 8)
    even = np.tile(np.repeat([0, 0, 80, 800], 8), 1)
    assert checks.wall_chi_square(even, grid) == (0.0, 14, 1.0)
    skewed = even.copy()
    skewed[-8:] = [900, 700] * 4  # (the band of 800s made uneven, its total kept)
    statistic, dof, p = checks.wall_chi_square(skewed, grid)
    assert (statistic, dof) == (pytest.approx(8 * 100**2 / 800), 14)
    assert p < 1e-10


def test_row_independence_tells_rounding_from_dependence():
    """Heitz's visible normals as published, at wo = n (one wall's rows, column-major): the
    tangent that lensq's rounding noise picks differs between a batch and a row alone, by
    whole angles, because einsum rounds a column-major batch otherwise than one row. That
    is no dependence on other rows: the row's answer moves as far when its inputs move by a
    few ulps, which a material that depends on the batch does not do."""
    material = wrong.RightVisibleNormals()
    rng = np.random.default_rng(0)
    rows = 4096
    turn = Walls(rng, along_axes=0).rotations(rng, rows)  # (tilted walls: n's x and y round)
    n = turn.apply(checks.Z)
    wo = turn.apply(np.tile(checks.Z, (rows, 1)))  # (wo = n, to the bit)
    u = rng.random((rows, 2))
    kept: list = []
    checks.call(material, "sample", wo, n, u, shapes=[(rows, 3)], keep=kept)
    record = kept[0]
    alone = np.concatenate([material.sample(*(rows_of(a, [k]) for a in record.arguments)) for k in range(32)])
    assert (np.abs(alone - record.answer[0]).max(axis=1) > 1e-3).any()  # (the failure once reported)
    result = checks.check_row_independence(material, kept, rng, sizes=[1000, 2**18])
    assert result.verdict == "pass", result
    assert "ill-conditioned" in result.statistic
    for mistake in (wrong.DependsOnCallSize(), wrong.DependsOnRowOrder(), wrong.DependsOnMeanWo()):
        kept = []
        cos_theta_o = rng.uniform(0.1, 1.0, rows)  # (a mean over rows that depends on the rows)
        wo = turn.apply(np.column_stack([np.sqrt(1 - cos_theta_o**2), 0 * cos_theta_o, cos_theta_o]))
        for method, arguments in (("sample", (wo, n, u)), ("eval", (wo, wo[::-1], n))):
            checks.call(mistake, method, *arguments, keep=kept)
        assert checks.check_row_independence(mistake, kept, rng, sizes=[1000, 2**18]).verdict == "FAIL"


def test_a_material_right_only_for_repeated_rows_fails_in_process():
    report = check_material(wrong.RightOnlyForRepeatedRows(), samples=SAMPLES)
    assert report["energy"].verdict == "FAIL"
    assert "without the 1/pi" in report["energy"].hint
    assert report["row independence"].verdict == "FAIL"


@pytest.mark.subprocess
def test_row_independence_holds_for_float32_arithmetic_and_a_student_process(capsys):
    # The float32 Lambertian of the exercises, graded in its own process: every row asked
    # again alone and shuffled, in float64 and in float32, gives the same answer.
    assert ptlab_main(["grade", f"{PLAIN}:Lambertian", "--samples", "20000"]) == 0
    out = capsys.readouterr().out
    assert "row independence" in out
    assert "PASSED" in out


# -- batches of other sizes; materials that give no direction or reflect nothing ----------------


class RightOnlyInTheGradersSizes(Diffuse):
    """7.6x too bright in a call of more than 10 000 rows, except in sizes the old harness
    used (multiples of 1000, the samples, or of 3, its quadrature's): a render's sizes."""

    def eval(self, wo, wi, n):
        rows = len(wo)
        return super().eval(wo, wi, n) * (7.6 if rows > 10_000 and rows % 3 and rows % 1000 else 1.0)


class GivesNoDirection:
    """sample returns -n (pdf 0 there), eval and pdf 0: consistent, and useless."""

    def eval(self, wo, wi, n):
        return np.zeros((len(wo), 3))

    def pdf(self, wo, wi, n):
        return np.zeros(len(wo))

    def sample(self, wo, n, u):
        return -np.asarray(n)


class Black:
    """Cosine sampling with its pdf (the homework's three functions), eval 0 everywhere."""

    def eval(self, wo, wi, n):
        return np.zeros((len(wo), 3), dtype=wi.dtype)

    def pdf(self, wo, wi, n):
        return Diffuse().pdf(wo, wi, n)

    def sample(self, wo, n, u):
        return Diffuse().sample(wo, n, u)


def test_batch_sizes_hold_a_renders_batch_and_others_drawn_per_run():
    first, second = checks.batch_sizes(), checks.batch_sizes()
    assert first[0] == second[0] == checks.RENDER_BATCH == 2**18
    for sizes in (first, second):
        assert len(sizes) == 1 + checks.RANDOM_BATCHES
        assert all(checks.ROW_INDEPENDENCE_ROWS < s <= checks.LARGEST_BATCH for s in sizes)
    assert first[1:] != second[1:]  # (fresh entropy: equal with probability below 1e-12)


def test_kept_rows_go_inside_a_larger_batch_at_random_places_in_their_layout():
    rng = np.random.default_rng(0)
    rows = 100
    wo = np.asfortranarray(rng.normal(size=(rows, 3)).astype(np.float32))
    u = np.ascontiguousarray(rng.random((rows, 2)).astype(np.float32))
    record = Kept.first_rows("sample", (wo, wo, u), np.zeros((rows, 3)), 8)
    arguments, places = record.inside(5000, rng)
    assert [a.shape for a in arguments] == [(5000, 3), (5000, 3), (5000, 2)]
    assert arguments[0].dtype == np.float32
    assert arguments[0].flags.f_contiguous
    assert arguments[2].flags.c_contiguous
    assert (arguments[2] < 1).all()
    assert (arguments[2] >= 0).all()
    np.testing.assert_array_equal(arguments[0][places], wo[:8])
    assert len(set(places.tolist())) == 8
    # The other rows are the pool's rows turned: a rotation keeps each one's length.
    others = np.setdiff1d(np.arange(5000), places)
    lengths = np.linalg.norm(wo.astype(np.float64), axis=1)
    turned = np.linalg.norm(arguments[0][others].astype(np.float64), axis=1)
    assert np.abs(turned[:, None] - lengths[None, :]).min(axis=1).max() < 1e-5
    assert not np.isin(arguments[0][others], wo).all()  # (turned, not copied)


@pytest.mark.slow
def test_a_material_wrong_only_in_a_renders_batch_sizes_fails_row_independence():
    report = check_material(RightOnlyInTheGradersSizes((0.8, 0.5, 0.2)), samples=20_000)
    assert report.failed == ["row independence"], str(report)
    assert "inside a batch of 262144 rows" in report["row independence"].hint


@pytest.mark.slow
def test_row_independence_passes_inside_batches_of_many_sizes():
    material = Microfacet((1, 1, 1), alpha=0.05)
    kept: list = []
    rng = np.random.default_rng(5)
    checks.check_float32(material, rng, kept=kept)
    sizes = [33, 1000, 4097, 2**18, 2**19]
    assert checks.check_row_independence(material, kept, rng, sizes=sizes).verdict == "pass"


@pytest.mark.slow
def test_a_material_that_gives_no_direction_fails_with_a_clear_hint():
    report = check_material(GivesNoDirection(), samples=20_000)
    assert report.failed == ["reflectance"], str(report)
    assert report["reflectance"].hint.startswith("sample returns no direction with a positive pdf")


@pytest.mark.slow
def test_a_black_material_passes_with_a_warning_that_says_so():
    report = check_material(Black(), samples=20_000)
    assert report.passed, str(report)
    assert report.warned == ["reflectance"], str(report)
    assert "reflects nothing: albedo 0 for every probe" in report["reflectance"].hint
    assert str(report).endswith("PASSED, with warnings: reflectance")


@pytest.mark.slow
def test_a_sampler_failing_half_its_samples_is_no_mistake():
    # GGX with alpha 1 reflects half of its visible normals below the surface at wo 0.
    report = check_material(Microfacet((1, 1, 1), alpha=1.0), samples=20_000, wo_degrees=(0, 80))
    assert report["reflectance"].verdict == "pass", str(report)
