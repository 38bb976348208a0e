"""Measure the copy detector (``ptlab/course/sandbox/copies.py``): how often a rewritten copy of a
chapter's answers is found, and how close honest answers come to being taken for copies.

    python scripts/copy_detection.py            # every chapter, every rewrite (about a minute)
    python scripts/copy_detection.py --chapters 6 7

The copies are every chapter's answer file and each of its answers as a copier hands them in
(``tests/attacks/corpus.py``: the library's code of what the chapter's kit leaves out pasted
in), each put through every mechanical rewrite of ``tests/attacks/rewriters.py`` (names,
``operator`` calls, ``getattr``, aliases, split and inlined helpers, reordered statements,
dead code, constants, swapped operands, a wrapping class, conditional and loop forms, and
all at once). A copy that weighs less than ``MIN_COPIED_TOKENS`` as copied (a formula, or
code the exercise file spells out) cannot be told from honest work: it is listed, not
counted. The earlier releases' answers (``ptlab/course/sandbox/past_answers.json``) are put to
the detector as they were written, and all at once. The honest answers are the right and
wrong answers of ``tests/exercises`` and the exercise files as handed out.

Prints the detected share per chapter and per rewrite, the overall rate (the project asks for
95% at least), and the honest answers' highest similarity and weight against the thresholds
(docs/grading-security.md has the figures). Exit code 1 if the rate is under 95% or an
honest answer is taken for a copy.
"""

from __future__ import annotations

import argparse
import ast
import sys
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from attacks.corpus import (
    Copied,
    chapters,
    copied_files,
    detection,
    honest_files,
    honest_scores,
    near_weight,
    weighty,
)
from attacks.rewriters import REWRITES

from ptlab.course import chapter
from ptlab.course.sandbox.copies import (
    MIN_COPIED_TOKENS,
    THRESHOLD,
    copied_tokens,
    copies_in,
    past_answers,
)

#: The share of rewritten copies the detector must find.
REQUIRED_RATE = 0.95
#: How far below THRESHOLD an honest similarity still counts as close (and its weight with it).
MARGIN = 0.10


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--chapters", type=int, nargs="*", help="only these chapters (default: all)")
    args = parser.parse_args()
    numbers = args.chapters or chapters()
    started = time.perf_counter()
    rate = copies_found(numbers)
    past_found()
    honest_ok = honest_answers(numbers)
    print(f"\n({time.perf_counter() - started:.0f} s)")
    return 0 if rate >= REQUIRED_RATE and honest_ok else 1


def copies_found(numbers: list[int]) -> float:
    """Print the detected share per chapter and per rewrite; return the overall rate."""
    by_chapter: dict[int, list[bool]] = defaultdict(list)
    by_rewrite: dict[str, list[bool]] = defaultdict(list)
    light: list[Copied] = []
    missed = []
    for number in numbers:
        for copied in copied_files(number):
            if not weighty(copied):
                light.append(copied)
                continue
            for rewrite in REWRITES:
                found = detection(copied, rewrite)
                by_chapter[number].append(found.detected)
                by_rewrite[rewrite].append(found.detected)
                if not found.detected:
                    missed.append(found)
    print("Rewritten copies of the library's answers found as copies")
    print(f"\n  {'chapter':<10} {'found':>9}  copied files")
    for number, found in by_chapter.items():
        names = sum(1 for c in copied_files(number) if weighty(c))
        print(f"  {number:<10} {sum(found):>4}/{len(found):<4}  {names}")
    print(f"\n  {'rewrite':<24} {'found':>9}")
    for rewrite, found in by_rewrite.items():
        print(f"  {rewrite:<24} {sum(found):>4}/{len(found):<4}")
    every = [found for results in by_chapter.values() for found in results]
    rate = sum(every) / len(every) if every else 1.0
    print(f"\n  overall: {sum(every)}/{len(every)} = {rate:.1%} (at least {REQUIRED_RATE:.0%} asked)")
    for found in missed:
        weight = copied_tokens(list(found.found))
        where = f"chapter {found.copied.chapter} {found.copied.name}, {found.rewrite}"
        print(f"  missed: {where}: {weight} tokens")
    print(f"\n  too light to count alone (under {MIN_COPIED_TOKENS} tokens beyond the exercise file):")
    for copied in light:
        weight = copied_tokens(
            copies_in(ast.parse(copied.source), chapter(copied.chapter).rules.fingerprints)
        )
        print(f"    chapter {copied.chapter} {copied.name}: {weight}")
    return rate


def past_found() -> None:
    """Print how many of the earlier releases' answers that weigh enough alone are found."""
    chapter_of = {}
    for number in chapters():
        for answer in chapter(number).rules.fingerprints.answers:
            chapter_of.setdefault(answer.origin, number)
    found, total = 0, 0
    for past in past_answers():
        origin = f"{past['origin']} (as of {past['date']}, {past['commit']})"
        if origin not in chapter_of:
            continue  # (a version no chapter's answers keep: its grams are another's)
        copied = Copied(chapter_of[origin], origin, past["source"])
        if not weighty(copied):
            continue
        for rewrite in ("as copied", "all at once"):
            total += 1
            found += detection(copied, rewrite).detected
    print(f"\nEarlier releases' answers (weighing enough alone), as written and all at once: {found}/{total}")


def honest_answers(numbers: list[int]) -> bool:
    """Print how close the honest answers come to the thresholds; whether none is a copy."""
    scores = [s for s in honest_scores() if int(s.file.removeprefix("template ")[:2]) in numbers]
    files = sorted(
        {s.file for s in scores}
        | {f for f in honest_files() if int(f.removeprefix("template ")[:2]) in numbers}
    )
    print(
        f"\nHonest answers ({len(files)} files: tests/exercises right and wrong answers, the exercise files)"
    )
    weighing = [s for s in scores if s.answer.size >= MIN_COPIED_TOKENS / 2]
    top = max(weighing, key=lambda s: s.similarity, default=None)
    if top is not None:
        print(
            f"  highest similarity to an answer weighing {MIN_COPIED_TOKENS / 2:g} tokens or more: "
            f"{top.similarity:.2f} ({top.file}, {top.answer.origin}); THRESHOLD {THRESHOLD}"
        )
    weights = {file: near_weight(scores, file, MARGIN) for file in files}
    heaviest = max(weights, key=weights.get, default=None)
    if heaviest is not None:
        print(
            f"  most weight within {MARGIN} of THRESHOLD: {weights[heaviest]} tokens ({heaviest}); "
            f"MIN_COPIED_TOKENS {MIN_COPIED_TOKENS}"
        )
    copies = [file for file in files if near_weight(scores, file, 0.0) >= MIN_COPIED_TOKENS]
    print(f"  taken for copies: {', '.join(copies) if copies else 'none'}")
    return not copies


if __name__ == "__main__":
    sys.exit(main())
