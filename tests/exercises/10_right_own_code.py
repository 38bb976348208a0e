"""A right chapter-10 answer, written as a student would (not the library's code): the
balance and power heuristics, 0 where both densities are 0, and the weight of the strategy
that drew the sample with ``pdf``. It must get full marks; the chapter's typical wrong
answers are this file with the mistake patched in (wrong_answers.toml)."""

import numpy as np


def balance_heuristic(pdf, other):
    total = pdf + other
    return np.where(total > 0, pdf / np.where(total > 0, total, 1), 0.0)


def power_heuristic(pdf, other):
    return balance_heuristic(pdf * pdf, other * other)


def mis_weight(pdf, other, heuristic="power"):
    heuristic_of = {"power": power_heuristic, "balance": balance_heuristic}[heuristic]
    return heuristic_of(pdf, other)
