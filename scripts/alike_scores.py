"""Measure grade-all's pairs of alike students (``ptlab.course.alike``) on the test answers.

    python scripts/alike_scores.py               # per chapter: honest pairs, copies
    python scripts/alike_scores.py --class 400   # and the time to compare a class of 400

For each chapter it prints the most similar pair of honest submissions written apart from
each other (``tests/alike_corpus.py``: the answers of ``tests/exercises`` and the library's
own, each author's against the others'), with the fingerprints they share, both among pairs
that share at least ``MIN_SHARED`` (which can be reported) and among all; the most similar
pair written by one author (a wrong answer and the right answer it was made from, which a
teacher would want to see); and the least similar copy of an honest submission with its
names changed, its statements and functions reordered and dead code added (each against
its original). ``--class N`` times the fingerprints and the comparison of N submissions of
chapter 7 (copies of its honest files, each dressed with a seed of its own: every two
copies of one file are a pair).
"""

from __future__ import annotations

import argparse
import sys
import time
from itertools import combinations
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from alike_corpus import copied, honest

from ptlab.course import all_chapters
from ptlab.course.alike import MIN_SHARED, THRESHOLD, alike_pairs, fingerprints


def _similarity(first: frozenset[int], second: frozenset[int]) -> tuple[float, int]:
    shared = len(first & second)
    return (shared / min(len(first), len(second)) if first and second else 0.0), shared


def chapter_scores(number: int) -> dict:
    """The figures the module docstring lists, for chapter ``number``."""
    submissions = honest(number)
    prints = {h.label: fingerprints({"file.py": h.source.encode()}) for h in submissions}
    honest_pairs, derived_pairs = [], []
    for first, second in combinations(submissions, 2):
        score, shared = _similarity(prints[first.label], prints[second.label])
        entry = (score, shared, first.label, second.label)
        (honest_pairs if first.author != second.author else derived_pairs).append(entry)
    countable = [pair for pair in honest_pairs if pair[1] >= MIN_SHARED]
    copies = []
    for seed, submission in enumerate(submissions):
        original = prints[submission.label]
        if len(original) >= MIN_SHARED:
            dressed = fingerprints({"file.py": copied(submission.source, seed).encode()})
            copies.append((*_similarity(original, dressed), submission.label, "its copy"))
    return {
        "honest": max(countable, default=None),
        "honest, any size": max(honest_pairs, default=None),
        "one author": max(derived_pairs, default=None),
        "copy": min(copies, default=None),
    }


def time_a_class(size: int) -> tuple[float, float, int]:
    """Seconds to fingerprint and to compare ``size`` submissions of chapter 7, and the pairs
    reported."""
    sources = [h.source for h in honest(7)]
    files = [copied(sources[k % len(sources)], k) for k in range(size)]
    start = time.perf_counter()
    prints = {
        f"student {k}": fingerprints({"07_path_tracing.py": text.encode()}) for k, text in enumerate(files)
    }
    middle = time.perf_counter()
    pairs = alike_pairs(prints)
    return middle - start, time.perf_counter() - middle, len(pairs)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--class", dest="size", type=int, default=0, help="time a class of this size")
    args = parser.parse_args()
    print(f"reported from similarity {THRESHOLD} and {MIN_SHARED} shared fingerprints")
    for chapter in all_chapters():
        print(f"chapter {chapter.number}:")
        for what, found in chapter_scores(chapter.number).items():
            if found is not None:
                score, shared, first, second = found
                print(f"  {what:18s} {score:.2f} ({shared} shared)  {first} / {second}")
    if args.size:
        reading, comparing, pairs = time_a_class(args.size)
        print(
            f"{args.size} students: fingerprints {reading:.2f} s, comparison {comparing:.2f} s, {pairs} pairs"
        )


if __name__ == "__main__":
    main()
