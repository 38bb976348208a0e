"""Run the checks of chapters whose checks are deterministic over many grading seeds, with the
right answers of tests/exercises, in this process (not run in CI).

    python scripts/check_seeds.py --seeds 1000                 # chapters 10 and 11
    python scripts/check_seeds.py --seeds 50 --chapter 10 --every-render 1

A deterministic check has no false alarm by chance, but its inputs are new for each grading
seed, and a tolerance too tight for some of them would fail a right answer now and then. So
every check of the chapter runs, at grading seeds 1, 7920, 15839, ..., on each right answer
(``NN_right_*.py``); the script prints every failure and, per chapter, how many there were.
The answers are trusted files, imported here: the graders' questions of who wrote a
function (``ptlab.course.chapter.require``: the library's answer under another name, a
copy) need the sandbox's view of a submission, and are not asked. Chapter 10's render is
slower than the rest: it runs every ``--every-render`` seeds.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

from ptlab.course import chapter
from ptlab.course.chapter import CheckFailed, grading_seed

ANSWERS = Path(__file__).resolve().parents[1] / "tests" / "exercises"


def right_answers(number: int) -> list:
    """The right answers of chapter ``number`` in tests/exercises, as modules of this process."""
    modules = []
    for path in sorted(ANSWERS.glob(f"{number:02d}_right_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        modules.append(module)
    return modules


def failures_over_seeds(number: int, seeds: int, every_render: int) -> str:
    """Chapter ``number``'s checks on its right answers over ``seeds`` grading seeds: each
    failure printed, and a line saying how many there were."""
    found, modules = chapter(number), right_answers(number)
    failures = runs = 0
    for k in range(seeds):
        with grading_seed(1 + 7919 * k):
            for module in modules:
                for check in found.checks:
                    if check.name == "render" and k % every_render:
                        continue
                    runs += 1
                    try:
                        check.run(module)
                    except CheckFailed as failure:
                        failures += 1
                        print(f"chapter {number}, {module.__name__}, {check.name}: {failure}", flush=True)
    return f"chapter {number}: {failures} of {runs} checks failed ({len(modules)} answers, {seeds} seeds)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100, help="grading seeds")
    parser.add_argument("--chapter", type=int, action="append", help="chapters (default: 10 and 11)")
    parser.add_argument("--every-render", type=int, default=10, help="run chapter 10's render every N seeds")
    args = parser.parse_args()
    rules = sys.modules["ptlab.course.chapter"]
    rules.library_answer = lambda module, name: None  # (see the docstring)
    rules.copied_answer = lambda module: None
    for number in args.chapter or [10, 11]:
        print(failures_over_seeds(number, args.seeds, args.every_render), flush=True)


if __name__ == "__main__":
    main()
