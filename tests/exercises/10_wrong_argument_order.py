"""A typical wrong chapter-10 answer: the densities passed on in the wrong order.
``mis_weight(pdf, other)`` is the weight of the strategy that drew the sample with ``pdf``;
this one calls the heuristics with ``(other, pdf)``, so each strategy gets the other's
weight. The two weights still add up to 1, but the picture keeps the noise MIS is meant to
remove: a light seen in a smooth plate is weighted toward light sampling, the strategy that
finds it worst. The heuristics themselves are right."""

import numpy as np

EXPECTED_FAILURES = ("weights sum to 1", "zero and delta pdfs", "render")
EXPECTED_HINTS = {"weights sum to 1": ("the wrong order", "The argument order")}
MISLEADING_HINTS = {"weights sum to 1": ("heuristic argument passed on",)}


def balance_heuristic(pdf, other):
    total = pdf + other
    return np.where(total > 0, pdf / np.where(total > 0, total, 1), 0.0)


def power_heuristic(pdf, other):
    return balance_heuristic(pdf * pdf, other * other)


def mis_weight(pdf, other, heuristic="power"):
    heuristic_of = {"power": power_heuristic, "balance": balance_heuristic}[heuristic]
    return heuristic_of(other, pdf)            # (the bug: the arguments swapped)
