"""A typical wrong chapter-10 answer: both strategies weighted 1.

The heuristics are right, but ``mis_weight`` returns 1 for every sample: a light path that
both light sampling and BSDF sampling can find is counted by both, twice in all (the double
counting that Homework 7's "do not add emission after a light sample" avoids). The picture
comes out too bright wherever both strategies find the light.
"""

import numpy as np

EXPECTED_FAILURES = ("weights sum to 1", "zero and delta pdfs", "render")


def balance_heuristic(pdf, other):
    total = pdf + other
    return np.where(total > 0, pdf / np.where(total > 0, total, 1), 0.0)


def power_heuristic(pdf, other):
    return balance_heuristic(pdf * pdf, other * other)


def mis_weight(pdf, other, heuristic="power"):
    return np.ones_like(pdf)
