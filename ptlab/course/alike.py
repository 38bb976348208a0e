"""Pairs of students whose files are alike, for a teacher to look at (``grade-all``).

As MOSS does (Schleimer, Wilkerson and Aiken, "Winnowing: local algorithms for document
fingerprinting", SIGMOD 2003), each submission becomes a set of fingerprints of its
normalised code, and each pair of students is scored by the fingerprints they share:

* **fingerprints**: the grams of every function of the submission's Python files
  (``ptlab.course.sandbox.copies.grams``: runs of tokens in which names, docstrings and
  annotations are gone, and neither the order of statements and functions nor that of the
  operands of ``+`` and ``*`` counts), less those of the exercise files
  (``copies.template_grams``): what every student is handed is no evidence;
* **similarity**: the share of the smaller submission's fingerprints that the other holds
  (the containment of Broder, "On the resemblance and containment of documents", 1997):
  padding a copy with code of one's own does not lower it.

A pair is reported from ``THRESHOLD`` similarity and ``MIN_SHARED`` shared fingerprints.
Measured on the answers of ``tests/exercises`` and the library's own, each chapter's
against each other (``scripts/alike_scores.py`` prints the figures, ``tests/course/test_alike.py``
checks them): honest submissions written apart share at most 0.56 of their fingerprints
where they share at least ``MIN_SHARED`` (chapter 8, whose exercise file's hints spell out
the tiles, the job and the pool), and 0.72 where they share fewer (chapter 2's
Moller-Trumbore steps, 13 fingerprints, which the formula dictates). A copy of a submission
with its names changed, its statements and functions reordered and dead code added holds
all of it: 1.00. ``THRESHOLD`` = 0.8 leaves 0.24 above the honest, and a copy of which a
fifth is written anew is still reported. ``MIN_SHARED`` = 25 is about twice
what a dictated formula shares: the answers of chapters 2, 4 and 10 are smaller than that
beyond the exercise file, and their pairs are never reported (their formulas leave too
little room to tell copying from them). Files of one author (a wrong answer made from the
same student's right one) are up to 1.00 alike, and reported as a copy would be.

Every pair is compared as two sets of fingerprints, each submission's syntax tree read once
(``docs/exercises.md`` has the time for 1000 students).
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from dataclasses import dataclass
from itertools import combinations

from ptlab.course.sandbox.copies import functions_in, grams, template_grams

#: Share of the smaller submission's fingerprints found in the other from which a pair is
#: reported (see the module docstring for the measurement).
THRESHOLD = 0.8
#: Fingerprints two submissions must share to be reported: fewer are a formula's few lines.
MIN_SHARED = 25
#: The largest submission (its Python files together) that is compared: the grader reads
#: them all in its own process, and a file of megabytes of statements takes gigabytes to
#: parse. An exercise's answer is a few kilobytes.
MAX_COMPARED_BYTES = 256 << 10


@dataclass(frozen=True)
class Alike:
    """Two submissions found alike.

    Attributes:
        first, second: the two students, as the caller named them.
        similarity: the share of the smaller one's fingerprints the other holds (0..1).
        shared: the fingerprints they share.
        sizes: each one's fingerprints.
    """

    first: str
    second: str
    similarity: float
    shared: int
    sizes: tuple[int, int]


def fingerprints(files: Mapping[str, bytes]) -> frozenset[int] | None:
    """The fingerprints of a submission's Python files ({name: bytes}): the grams of their
    functions, less those of the exercise files; None if they cannot be compared (larger
    than ``MAX_COMPARED_BYTES`` together, or a file Python cannot read)."""
    if sum(len(data) for data in files.values()) > MAX_COMPARED_BYTES:
        return None
    found: set[int] = set()
    for name, data in files.items():
        try:
            for function in functions_in(ast.parse(data, filename=name)):
                found |= grams(function)
        except (SyntaxError, ValueError, RecursionError, MemoryError):
            return None
    return frozenset(found - template_grams())


def alike_pairs(prints: Mapping[str, frozenset[int]]) -> list[Alike]:
    """The pairs of ``prints`` ({student: fingerprints}) that are alike (see the module
    docstring), the most similar first."""
    large = [(student, found) for student, found in prints.items() if len(found) >= MIN_SHARED]
    pairs = []
    for (first, mine), (second, theirs) in combinations(large, 2):
        shared = len(mine & theirs)
        similarity = shared / min(len(mine), len(theirs))
        if shared >= MIN_SHARED and similarity >= THRESHOLD:
            pairs.append(Alike(first, second, similarity, shared, (len(mine), len(theirs))))
    return sorted(pairs, key=lambda pair: (-pair.similarity, -pair.shared, pair.first, pair.second))
