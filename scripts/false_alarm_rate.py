"""Measure how often the grader fails a correct material by chance (not run in CI).

    python scripts/false_alarm_rate.py                 # 200 seeds, 10^6 samples per wo
    python scripts/false_alarm_rate.py --seeds 50 --samples 200000 --every-material
    python scripts/false_alarm_rate.py --seeds 5 --first-seed 1    # grading seeds 1..5
    python scripts/false_alarm_rate.py --harness-seed 0            # ptlab grade's fixed seed

Trial k draws a fresh grading seed (from the operating system, as the exercise grader does;
or ``--first-seed`` K + k) and grades the (k mod M)-th of M correct materials (or, with
``--every-material``, all of them) with the harness's seed that the material-harness checks
of chapters 6 and 9 derive from it (``ptlab.course.chapter.grading_seed_for``), the
harness's defaults otherwise (``--harness-seed N``: every material once with the harness's
seed N itself, as ``ptlab grade --seed N`` grades). Four of them compute in float32, as a
student's material may (the renderer passes float32 arrays): the library's on float32
copies of the arguments, and a Lambertian whose pi is ``np.float32(math.pi)``; they have only
the homework's three functions, as the graders accept. It prints each failure with the
failed checks, then per check the runs it failed and its rate with a 95% Clopper-Pearson
interval (and, for the chi-square, the runs whose smallest p-value came within 10x of its
threshold: about 10x its rate, a check of its calibration with fewer runs). The checks'
documented rates add up to about 0.12%.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections import Counter

# One core, as the performance target says (NumPy's BLAS would otherwise spread over all).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from scipy.stats import beta

from ptlab.course.chapter import grading_seed, grading_seed_for, new_grading_seed
from ptlab.grading import check_material
from ptlab.materials import Dielectric, Diffuse, Microfacet, Mirror


class Float32:
    """A correct material computing in float32: ``material``'s three functions on float32
    copies of the arguments (no sample_weight of its own: the graders derive it)."""

    def __init__(self, material):
        self.material = material

    def eval(self, wo, wi, n):
        return self.material.eval(*(np.asarray(a, np.float32) for a in (wo, wi, n)))

    def pdf(self, wo, wi, n):
        return self.material.pdf(*(np.asarray(a, np.float32) for a in (wo, wi, n)))

    def sample(self, wo, n, u):
        return self.material.sample(*(np.asarray(a, np.float32) for a in (wo, n, u)))

    def __repr__(self) -> str:
        return f"float32 {self.material!r}"


class Float32Pi:
    """A correct Lambertian (cosine sampling) whose pi is np.float32(math.pi)."""

    albedo = np.array([0.8, 0.5, 0.2])

    def eval(self, wo, wi, n):
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return above[:, None] * self.albedo / np.float32(math.pi)

    def pdf(self, wo, wi, n):
        cos_theta = np.sum(wi * n, axis=1)
        return np.where((np.sum(wo * n, axis=1) > 0) & (cos_theta > 0), cos_theta / np.float32(math.pi), 0.0)

    def sample(self, wo, n, u):
        from ptlab.sampling import cosine_hemisphere_around

        return cosine_hemisphere_around(n, u)

    def __repr__(self) -> str:
        return "Lambertian with a float32 pi"


MATERIALS = [
    Diffuse((0.8, 0.5, 0.2)),
    Diffuse((1.0, 1.0, 1.0), sampling="uniform"),
    Microfacet((1.0, 1.0, 1.0), alpha=0.05),
    Microfacet("gold", alpha=0.3),
    Microfacet("aluminium", alpha=1.0),
    Microfacet((1.0, 1.0, 1.0), alpha=0.05, sampling="hemisphere"),
    Microfacet("copper", alpha=0.2, kd=(0.3, 0.3, 0.3), ks=0.7),
    Microfacet("silver", roughness=0.6, kd=(0.5, 0.4, 0.3), ks=0.5, sampling="hemisphere"),
    Mirror((0.9, 0.8, 0.7), fresnel=True),
    Dielectric(1.5),
    Float32(Diffuse((0.8, 0.5, 0.2))),
    Float32(Microfacet("gold", alpha=0.3)),
    Float32(Microfacet((1.0, 1.0, 1.0), alpha=0.05, sampling="hemisphere")),
    Float32Pi(),
]


def interval(failures: int, runs: int) -> tuple[float, float]:
    """The 95% Clopper-Pearson interval of a rate of ``failures`` in ``runs``."""
    low = beta.ppf(0.025, failures, runs - failures + 1) if failures else 0.0
    high = beta.ppf(0.975, failures + 1, runs - failures) if failures < runs else 1.0
    return low, high


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=200, help="trials, one grading seed each")
    parser.add_argument("--first-seed", type=int, help="grading seeds K, K+1, ... (default: fresh ones)")
    parser.add_argument("--harness-seed", type=int, help="grade every material once with this harness seed")
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument(
        "--every-material", action="store_true", help="grade every material on every seed (M times longer)"
    )
    args = parser.parse_args()
    runs = failures = near = 0
    by_check: Counter = Counter()
    ran: Counter = Counter()
    start = time.perf_counter()
    trials = 1 if args.harness_seed is not None else args.seeds
    for trial in range(trials):
        every = args.every_material or args.harness_seed is not None
        chosen = MATERIALS if every else [MATERIALS[trial % len(MATERIALS)]]
        if args.harness_seed is not None:
            graded = seed = args.harness_seed
        else:
            graded = new_grading_seed() if args.first_seed is None else args.first_seed + trial
            with grading_seed(graded):
                seed = grading_seed_for(6)  # (chapter 6's harness check: stream 6)
        for material in chosen:
            report = check_material(material, seed=seed, samples=args.samples)
            runs += 1
            ran.update(check.name for check in report.checks)
            by_check.update(report.failed)
            chi_square = next((c for c in report.checks if c.name == "chi-square"), None)
            if chi_square is not None and chi_square.data["p"] < 10 * chi_square.data["threshold"]:
                near += 1
            if not report.passed:
                failures += 1
                print(
                    f"grading seed {graded} (harness seed {seed}): {report.material} failed "
                    f"{', '.join(report.failed)}",
                    flush=True,
                )
                for check in report.checks:
                    if not check.passed:
                        print(
                            f"    {check.name}: {check.statistic} (threshold {check.threshold})", flush=True
                        )
        if (trial + 1) % 20 == 0:
            print(
                f"... {trial + 1} seeds, {runs} runs, {failures} failures, "
                f"{time.perf_counter() - start:.0f} s",
                flush=True,
            )
    for name, count in ran.items():
        low, high = interval(by_check[name], count)
        print(f"{name}: {by_check[name]} of {count} runs failed (95% interval {low:.2%} .. {high:.2%})")
    low, high = interval(near, ran["chi-square"])
    print(
        f"chi-square within 10x of its threshold: {near} of {ran['chi-square']} "
        f"(95% interval {low:.2%} .. {high:.2%})"
    )
    low, high = interval(failures, runs)
    print(
        f"false alarms: {failures} of {runs} runs = {failures / runs:.2%} "
        f"(95% interval {low:.2%} .. {high:.2%}), {time.perf_counter() - start:.0f} s, "
        f"{args.samples:,} samples per wo"
    )


if __name__ == "__main__":
    main()
