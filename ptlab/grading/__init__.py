"""Grading materials: is ``sample`` drawn from ``pdf``, and is ``eval`` physically plausible?

    >>> from ptlab.grading import check_material
    >>> from ptlab.materials import Microfacet
    >>> report = check_material(Microfacet("gold", roughness=0.5), seed=0)
    >>> report.passed
    True
    >>> print(report)            # a table: check, statistic, threshold, verdict, hint

``check_material`` runs every check of ``ptlab.grading.checks`` on a material (or, for a
delta material such as ``Mirror`` or ``Dielectric``, those of ``ptlab.grading.delta``),
each deterministic for a given seed and with a documented false-alarm rate; a wrong
material fails with a hint naming the likely mistake. ``write_plots`` draws a failed
chi-square test; ``ptlab grade FILE.py:Name`` (``ptlab.course.grade_command``) does all of it from
the command line.

The method follows the statistical tests of Mitsuba 3 (``mitsuba.chi2``) and Nori's
``warptest`` (Jakob et al.), with the failed-sample category and hints added.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

import numpy as np

from ptlab.grading import checks, delta
from ptlab.grading.material import AdaptedMaterial, as_material
from ptlab.grading.plots import write_plots
from ptlab.grading.probes import Kept
from ptlab.grading.report import Check, Report
from ptlab.grading.sphere import SphereGrid

__all__ = ["Check", "Report", "check_material", "write_plots"]

#: The angles between wo and n at which the statistical checks sample: head-on, oblique and grazing.
WO_DEGREES = (0.0, 45.0, 80.0)

_Result = TypeVar("_Result")


def check_material(material, seed: int = 0, *, samples: int = 1_000_000, wo_degrees=WO_DEGREES) -> Report:
    """Run every check on ``material`` and return the report.

    Args:
        material: anything with ``eval``, ``pdf`` and ``sample`` as in
            ``ptlab.materials.base.Material``; ``sample_weight`` (else derived from the
            three), ``is_delta`` (mirrors and glass; else False) and ``emission`` are optional
            (``ptlab.grading.material.as_material``).
        seed: seeds every random choice (the samples, the walls and the turn of every
            row, the order of the rows, the wo's angles).
        samples: directions drawn per wo for the statistical checks (default 10^6; fewer
            make the tests weaker, not wrong).
        wo_degrees: nominal angles of wo from the normal for the statistical checks, each
            moved by up to 5 degrees per seed (0 stays 0: ``checks.lobe_angles``).

    Delta materials (``is_delta``) get the checks of ``ptlab.grading.delta`` instead, at
    their own fixed angles and 2^14 stratified samples; ``samples`` and ``wo_degrees`` do
    not apply to them.
    """
    start = time.perf_counter()
    material = as_material(material)
    root = np.random.SeedSequence(seed)
    streams = [np.random.default_rng(s) for s in root.spawn(8)]
    if material.is_delta:
        results = _delta_checks(material, streams)
        samples = delta.SAMPLES
    else:
        results = _checks(material, streams, samples, tuple(wo_degrees))
    return Report(_describe(material), results, seed, samples, time.perf_counter() - start)


def _describe(material) -> str:
    """The material's repr, or its class name where the repr is Python's default."""
    if isinstance(material, AdaptedMaterial):
        material = material.material
    text = repr(material)
    return f"{type(material).__name__} object" if " object at 0x" in text else text


def _checks(material, streams, samples: int, wo_degrees: tuple) -> list[Check]:
    results = [_guard("consistency", checks.check_consistency, material, streams[1])]
    # The grid's frame is the checks' own: every row the material sees is turned by a
    # rotation of its own (ptlab.grading.probes), so no normal of the seed is needed.
    grid = SphereGrid.for_samples(checks.Z, samples)
    kept: list[Kept] = []
    degrees = checks.lobe_angles(wo_degrees, streams[7])
    failure = None  # measure's error, if it raised (then lobes, pointwise and walls are unset)
    try:
        lobes, pointwise, walls = checks.measure(material, grid, degrees, samples, streams[2], kept)
    except checks.MaterialError as error:
        failure = str(error)
    for name, check in (
        ("chi-square", lambda: checks.check_chi_square(material, lobes, walls, streams[3])),
        ("pdf normalisation", lambda: checks.check_normalisation(lobes)),
        ("energy", lambda: checks.check_energy(lobes)),
        ("reflectance", lambda: checks.check_reflectance(lobes)),
        ("estimator agreement", lambda: checks.check_estimator(lobes)),
        ("sample_weight", lambda: checks.check_sample_weight(pointwise)),
    ):
        results.append(_guard(name, check) if failure is None else _failure(name, failure))
    results.append(_guard("reciprocity", checks.check_reciprocity, material, streams[5]))
    results.append(_guard("float32", checks.check_float32, material, streams[6], kept=kept))
    results.append(_guard("row independence", checks.check_row_independence, material, kept, streams[4]))
    return results


def _delta_checks(material, streams) -> list[Check]:
    kept: list[Kept] = []
    try:
        scattering = delta.scatter_all(material, streams[1], kept)
    except checks.MaterialError as error:
        return [_failure(name, str(error)) for name in ("consistency", "directions", "energy")]
    scatters = scattering.scatters
    results = [
        _guard("consistency", delta.check_delta_consistency, material, scattering, kept),
        _guard("directions", delta.check_directions, material, scatters),
    ]
    if delta.transmits(scatters) and delta.relative_eta(material, scatters) is not None:
        results.append(_guard("Fresnel weights", delta.check_fresnel, material, scatters))
    results.append(_guard("energy", delta.check_delta_energy, material, scatters))
    front = _guard("front", delta.check_front, material, scattering)
    results += [front] if front is not None else []
    results.append(_guard("row independence", checks.check_row_independence, material, kept, streams[2]))
    return results


def _guard(name: str, check: Callable[..., _Result], *args, **keywords) -> _Result | Check:
    """Run one check (its result: a ``Check``, or for ``delta.check_front`` perhaps None); a
    material that raises fails it with the error as the hint."""
    try:
        return check(*args, **keywords)
    except checks.MaterialError as error:
        return _failure(name, str(error))


def _failure(name: str, problem: str) -> Check:
    return Check(name, "FAIL", "could not run", "-", problem)
