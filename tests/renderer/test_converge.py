"""``ptlab converge``: error measures, the spp ladder, time to a target, and its files."""

from __future__ import annotations

import csv
import dataclasses

import numpy as np
import pytest

import ptlab
import ptlab.measure.converge
from ptlab.cli import main
from ptlab.errors import PtlabError
from ptlab.image import read_image, write_image
from ptlab.measure.converge import Measurement, parse_estimators, time_to_reach
from ptlab.measure.metrics import relative_squared_error, relmse, rmse


def test_error_measures_match_their_definitions():
    reference = np.zeros((2, 2, 3))
    reference[0, 0] = 1.0
    image = reference.copy()
    image[0, 0, 0] = 1.5  # one channel of a bright pixel off by 0.5
    image[1, 1, :] = 0.1  # a black pixel turned grey
    assert rmse(image, reference) == pytest.approx(np.sqrt((0.25 + 3 * 0.01) / 12))
    # pbrt-v4's MRSE: (I - R)^2 / (R + 0.01)^2, averaged over pixels and channels.
    expected = (0.25 / 1.01**2 + 3 * 0.01 / 0.01**2) / 12
    assert relmse(image, reference) == pytest.approx(expected)
    per_pixel = relative_squared_error(image, reference)
    assert per_pixel.shape == (2, 2)
    assert per_pixel[0, 1] == 0
    assert relmse(reference, reference) == 0
    assert rmse(reference, reference) == 0


def test_estimators_are_parsed_and_bad_ones_named():
    labels = [(e.label, e.integrator, e.strategy) for e in parse_estimators("path:bsdf, path,whitted")]
    assert labels == [("path:bsdf", "path", "bsdf"), ("path", "path", "nee"), ("whitted", "whitted", "nee")]
    flags = [
        (e.label, e.strategy, e.adaptive, e.denoise, e.options()["denoise"])
        for e in parse_estimators("path:mis+denoise,path:nee+adaptive+denoise,path+denoise+adaptive")
    ]
    assert flags == [
        ("path:mis+denoise", "mis", False, True, True),
        ("path:nee+adaptive+denoise", "nee", True, True, True),
        ("path+denoise+adaptive", "nee", True, True, True),
    ]
    for bad, word in [
        ("path:foo", "strategy"),
        ("bdpt", "integrator"),
        ("whitted:mis", "no strategy"),
        ("path:mis,path:mis", "once"),
        ("whitted+denoise", "only path-traced images are denoised"),
        ("path+denoise+denoise", "integrator"),
    ]:
        with pytest.raises(PtlabError, match=word):
            parse_estimators(bad)


def _ladder(*points):
    return [Measurement("x", 2**k, seconds, 0.0, error, None) for k, (seconds, error) in enumerate(points)]


def test_time_to_reach_interpolates_log_log_and_extrapolates_with_slope_minus_one():
    # error = 1 / seconds exactly: the target 0.05 is reached at 20 s.
    ladder = _ladder((1, 1.0), (10, 0.1), (40, 0.025))
    seconds, extrapolated = time_to_reach(ladder, 0.05)
    assert seconds == pytest.approx(20.0)
    assert not extrapolated
    seconds, extrapolated = time_to_reach(ladder, 0.01)  # past the last rung: 0.025 * 40 / 0.01
    assert seconds == pytest.approx(100.0)
    assert extrapolated
    assert time_to_reach(ladder, 2.0) is None  # below the target from the start
    assert time_to_reach(_ladder((1, 1.0), (2, 1.2)), 0.1) is None  # error not falling
    # A denoised image's error has no known slope: not past its last rung, but between rungs.
    assert time_to_reach(ladder, 0.01, unbiased=False) is None
    assert time_to_reach(ladder, 0.05, unbiased=False) == pytest.approx((20.0, False))


@pytest.fixture(scope="module")
def reference_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("reference") / "ref.exr"
    image = ptlab.render("cornell-box", spp=256, res=24, seed=99, workers=1, strategy="mis")
    write_image(path, image)
    return path


def clock_by_samples(monkeypatch, seconds_per_spp: float) -> None:
    """Make each render that ``ptlab converge`` times take ``seconds_per_spp`` x spp seconds
    by its clock: the ladder it climbs within a budget is then the same on any machine."""
    render = ptlab.measure.converge.render_result

    def timed(scene, spp, **options):
        return dataclasses.replace(render(scene, spp=spp, **options), seconds=seconds_per_spp * spp)

    monkeypatch.setattr(ptlab.measure.converge, "render_result", timed)


def test_converge_writes_the_table_chart_and_strip(tmp_path, reference_file, capsys, monkeypatch):
    clock_by_samples(monkeypatch, 0.01)
    out = tmp_path / "out"
    code = main(
        [
            "converge",
            "cornell-box",
            "--integrators",
            "path:bsdf,path:nee",
            "--res",
            "24",
            "--budget",
            "1.5",
            "--reference",
            str(reference_file),
            "--out",
            str(out),
            "--workers",
            "1",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "time to reach relMSE 0.01" in text
    with open(out / "convergence.csv") as table:
        rows = list(csv.DictReader(table))
    assert list(rows[0]) == ["integrator", "spp", "seconds", "rmse", "relmse", "relmse_estimate"]
    for label in ("path:bsdf", "path:nee"):
        ladder = [r for r in rows if r["integrator"] == label]
        spp = [int(r["spp"]) for r in ladder]
        # 1 to 64 spp take 1.27 s; a 128-spp rung (1.28 s more) would pass the 1.5 s.
        assert spp == [1, 2, 4, 8, 16, 32, 64], spp
        assert [float(r["seconds"]) for r in ladder] == pytest.approx([0.01 * s for s in spp])
        errors = [float(r["relmse"]) for r in ladder]
        # Fixed seed; at 64x the samples the error of an unbiased estimator is about 64x
        # lower, so halving is a safe margin.
        assert errors[-1] < errors[0] / 2, (label, errors)
    # On the Cornell box, light sampling beats BSDF sampling at equal spp by far.
    at_four = {r["integrator"]: float(r["relmse"]) for r in rows if r["spp"] == "4"}
    assert at_four["path:nee"] < at_four["path:bsdf"] / 3
    for name in ("convergence.png", "equal-time.png"):
        pixels, _ = read_image(out / name)
        assert pixels.shape[0] > 200
        assert pixels.std() > 0.05
    reference, _ = read_image(out / "reference.exr")
    np.testing.assert_array_equal(reference, read_image(reference_file)[0])


def test_the_rendered_reference_is_cached(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PTLAB_CACHE", str(tmp_path / "cache"))
    arguments = [
        "converge",
        "cornell-box",
        "--integrators",
        "path:nee",
        "--res",
        "16",
        "--budget",
        "0.2",
        "--reference-spp",
        "8",
        "--workers",
        "1",
    ]
    assert main([*arguments, "--out", str(tmp_path / "a")]) == 0
    assert "cached" not in capsys.readouterr().out
    assert main([*arguments, "--out", str(tmp_path / "b")]) == 0
    assert "(cached)" in capsys.readouterr().out
    first, _ = read_image(tmp_path / "a" / "reference.exr")
    second, _ = read_image(tmp_path / "b" / "reference.exr")
    np.testing.assert_array_equal(first, second)
    # The reference has its own seed: it is not the ladder's 8-spp render.
    ladder_render = ptlab.render("cornell-box", spp=8, res=16, seed=0, workers=1, strategy="mis")
    assert not np.array_equal(first, ladder_render)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--res", "32"], "the reference is 24x24"),
        (["--integrators", "path:nope"], "strategy"),
        (["--budget", "0"], "budget"),
        (["--target", "-1"], "target"),
    ],
)
def test_bad_converge_options_are_one_line_errors(tmp_path, reference_file, capsys, arguments, message):
    out = tmp_path / "out"
    code = main(
        [
            "converge",
            "cornell-box",
            "--reference",
            str(reference_file),
            "--res",
            "24",
            "--out",
            str(out),
            "--workers",
            "1",
            *arguments,
        ]
    )
    assert code == 2
    error = capsys.readouterr().err
    assert message in error
    assert error.count("\n") == 1
    assert not out.exists()
