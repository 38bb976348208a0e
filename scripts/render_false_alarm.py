"""Measure the render checks' noise ratios and false alarms over many grading seeds (not run in CI).

    python scripts/render_false_alarm.py --seeds 40 --variance-ratios
    python scripts/render_false_alarm.py --seeds 40 --check "ch07 white furnace"
    python scripts/render_false_alarm.py --seeds 5 --first-seed 1      # grading seeds 1..5

Each trial draws a fresh grading seed (from the operating system, as the grader does; or
``--first-seed`` K, K + 1, ...) and, inside it, renders what each render check renders (the
same settings, seeds and furnace parameters, through the chapters' own functions): the
library's passes, and a right answer's, whose functions (the right answers of
tests/exercises, which draw random numbers or sample otherwise than the library) are passed
to the render directly, in this process (not through the sandbox). It prints, per check, how
many comparisons failed (``compare_renders`` or ``furnace_verdict``, both sides of the noise
test included) with the rate's 95% Clopper-Pearson interval, and with ``--variance-ratios``
the largest and the smallest variance ratio (right answer / library, the half-th largest and
smallest over the regions, as ``renders.noise_test`` takes them) over the trials.
``--constant`` also grades, in every trial, a converged answer (the library's passes' mean
in every pass) and counts how often the too-clean test catches it (it must be every time);
``--wrong`` grades the wrong answers of ``WRONG`` (tests/exercises/07_wrong_furnace_fake.py,
the furnace's analytic value with a render's noise) and counts how often they fail (every
time too).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from scipy.stats import beta

from ptlab.course.chapter import (
    CheckFailed,
    grading_rng,
    grading_seed,
    grading_seed_for,
    new_grading_seed,
)
from ptlab.course.chapters.ch07_path_tracing import PATTERNED_FALSE_ALARM
from ptlab.course.renders import FALSE_ALARM, compare_renders, noise_test, regions_of
from ptlab.rendering.pieces import Pieces

RIGHT = Path(__file__).resolve().parents[1] / "tests" / "exercises"


def right_answer(name: str):
    """The right answer tests/exercises/``name``.py as a module of this process."""
    spec = importlib.util.spec_from_file_location(f"right_{name}", RIGHT / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def ch06(name: str) -> Callable:
    from ptlab.course.chapters.ch06_diffuse import (
        RENDER_SEED,
        SPP_STREAM,
        render_passes,
        render_spp_per_pass,
    )

    module = right_answer(name)

    def render():  # (as check_render makes them: the seed and the samples per pass drawn)
        seed, spp = grading_seed_for(RENDER_SEED), render_spp_per_pass(grading_rng(SPP_STREAM))
        return (
            render_passes(module.Lambertian, seed, spp_per_pass=spp),
            render_passes(seed=seed, spp_per_pass=spp),
            "regions",
        )

    return render


def ch09(sampling: str) -> Callable:
    from ptlab.course.chapters.ch06_diffuse import render_spp_per_pass
    from ptlab.course.chapters.ch09_microfacet import RENDER_SEED, SPP_STREAM, render_passes

    module = right_answer("09_right_walter")

    def render():  # (as _render makes them)
        seed, spp = grading_seed_for(RENDER_SEED), render_spp_per_pass(grading_rng(SPP_STREAM))
        student = render_passes(
            sampling, lambda f0, alpha: module.GGXMetal(f0, alpha, sampling), seed, spp_per_pass=spp
        )
        return student, render_passes(sampling, seed=seed, spp_per_pass=spp), "regions"

    return render


def ch07_furnace() -> tuple:
    from ptlab.course.chapters import ch07_path_tracing as ch07

    module = right_answer("07_right_own_random")

    def render():
        albedo, le = ch07.furnace_parameters()
        settings = dict(seed=grading_seed_for(ch07.FURNACE_SEED), albedo=albedo, emission=le)
        settings.update(rr=1.0, max_depth=ch07.FURNACE_DEPTH)
        student = ch07.furnace_images(Pieces(trace_paths=module.trace_paths), **settings)
        library = ch07.furnace_images(**settings)
        return student, library, ch07.furnace_radiance(ch07.FURNACE_DEPTH, albedo, le)

    return render


def ch07_patterned(answer: str = "07_right_own_random") -> Callable:
    from ptlab.course.chapters import ch07_path_tracing as ch07

    module = right_answer(answer)

    def render():  # (as check_furnace makes them)
        seed = grading_seed_for(ch07.PATTERNED_SEED)
        student = ch07.patterned_furnace_passes(module.trace_paths, seed)
        return student, ch07.patterned_furnace_passes(seed=seed), "patterned"

    return render


def ch07_roulette() -> tuple:
    from ptlab.course.chapters import ch07_path_tracing as ch07

    module = right_answer("07_right_own_random")

    def render():
        albedo, le = ch07.furnace_parameters()
        seed = grading_seed_for(ch07.FURNACE_SEED + 100)
        student = ch07.roulette_furnace_images(module.russian_roulette, seed, albedo, le)
        library = ch07.roulette_furnace_images(seed=seed, albedo=albedo, emission=le)
        return student, library, ch07.furnace_radiance(None, albedo, le)

    return render


def ch07_cornell() -> Callable:
    from ptlab.course.chapters import ch07_path_tracing as ch07

    module = right_answer("07_right_own_random")

    def render():
        seed = grading_seed_for(ch07.CORNELL_SEED)
        return ch07.cornell_passes(module.trace_paths, seed), ch07.cornell_passes(seed=seed), "regions"

    return render


CHECKS = {
    "ch06 render, uniform sampling": lambda: ch06("06_right_uniform"),
    "ch06 render, float32 class": lambda: ch06("06_right_plain_class_float32"),
    "ch07 white furnace": ch07_furnace,
    "ch07 patterned furnace": ch07_patterned,
    "ch07 roulette": ch07_roulette,
    "ch07 Cornell box": ch07_cornell,
    "ch09 render, Walter sampling": lambda: ch09("ggx"),
    "ch09 render, hemisphere": lambda: ch09("hemisphere"),
}


#: The kinds of check that compare two renders (``compare_renders``), with their mean
#: tests' false-alarm rates; the others are chapter 7's furnace (``furnace_verdict``).
COMPARED = {"regions": FALSE_ALARM, "patterned": PATTERNED_FALSE_ALARM}
#: Wrong answers that a check must fail in every trial (``--wrong``): a file of
#: tests/exercises, rendered by the check as the right answer is.
WRONG = {"ch07 patterned furnace": lambda: ch07_patterned("07_wrong_furnace_fake")}


def regions(images: np.ndarray, kind) -> np.ndarray:
    """The per-pass region values the noise test compares: colours summed, or the red
    (the furnace's)."""
    return regions_of(images).sum(axis=-1) if kind in COMPARED else regions_of(images)[..., 0]


def verdict(student: np.ndarray, library: np.ndarray, kind) -> str | None:
    """None if the check passes ``student``, else its message."""
    from ptlab.course.chapters.ch07_path_tracing import furnace_verdict

    try:
        if kind in COMPARED:
            compare_renders(student, library, "the render", false_alarm=COMPARED[kind])
        else:
            furnace_verdict(student, library, kind, "the furnace")
    except CheckFailed as failure:
        return str(failure)
    return None


def clopper_pearson(failures: int, trials: int) -> tuple[float, float]:
    low = beta.ppf(0.025, failures, trials - failures + 1) if failures else 0.0
    high = beta.ppf(0.975, failures + 1, trials - failures) if failures < trials else 1.0
    return float(low), float(high)


def trial(render: Callable, wrong: Callable | None, constant: bool) -> dict:
    """One grading seed of a check: the right answer's verdict (None: passed) and variance
    ratios, and whether a converged answer (``constant``) and the ``wrong`` one are caught."""
    student, library, kind = render()
    noise = noise_test(regions(student, kind), regions(library, kind))
    outcome = dict(message=verdict(student, library, kind), high=noise.high, low=noise.low)
    if constant:
        converged = np.broadcast_to(library.mean(axis=0), library.shape).copy()
        message = verdict(converged, library, kind)
        outcome["converged caught"] = message is not None and "too clean" in message
    if wrong is not None:
        outcome["wrong caught"] = verdict(*wrong()) is not None
    return outcome


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40, help="grading seeds (trials)")
    parser.add_argument("--first-seed", type=int, help="grading seeds K, K+1, ... (default: fresh ones)")
    parser.add_argument("--check", action="append", help="only these checks (repeatable)")
    parser.add_argument("--variance-ratios", action="store_true", help="print the variance ratios")
    parser.add_argument("--constant", action="store_true", help="also grade a converged answer")
    parser.add_argument("--wrong", action="store_true", help="also grade the checks' wrong answers (WRONG)")
    args = parser.parse_args()
    chosen = {name: make() for name, make in CHECKS.items() if not args.check or name in args.check}
    wrong = {name: WRONG[name]() for name in chosen if args.wrong and name in WRONG}
    outcomes: dict[str, list[dict]] = {name: [] for name in chosen}
    for number in range(args.seeds):
        seed = new_grading_seed() if args.first_seed is None else args.first_seed + number
        with grading_seed(seed):
            for name, render in chosen.items():
                outcome = trial(render, wrong.get(name), args.constant)
                outcomes[name].append(outcome)
                if outcome["message"] is not None:
                    print(f"grading seed {seed}, {name}: FAIL {outcome['message']}", flush=True)
    for name, found in outcomes.items():
        failures = sum(outcome["message"] is not None for outcome in found)
        low, high = clopper_pearson(failures, args.seeds)
        line = f"{name}: {failures} of {args.seeds} failed (95%: {low:.3g} to {high:.3g})"
        if args.variance_ratios:
            largest, smallest = max(o["high"] for o in found), min(o["low"] for o in found)
            line += f"; variance ratio at most {largest:.3g}, at least {smallest:.3g}"
        if args.constant:
            caught = sum(o["converged caught"] for o in found)
            line += f"; a converged answer caught as too clean {caught} of {args.seeds} times"
        if name in wrong:
            caught = sum(o["wrong caught"] for o in found)
            line += f"; the wrong answer failed {caught} of {args.seeds} times"
        print(line, flush=True)


if __name__ == "__main__":
    main()
