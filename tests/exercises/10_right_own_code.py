"""A right chapter-10 answer, written as a student would (not the library's code): the
balance and power heuristics, 0 where both densities are 0, the power heuristic's densities
divided by the larger first (no square of a large density overflows float32), and the
weight of the strategy that drew the sample with ``pdf``. It must get full marks; the
chapter's typical wrong answers are this file with the mistake patched in
(wrong_answers.toml)."""

import numpy as np


def balance_heuristic(pdf, other):
    total = pdf + other
    return np.where(total > 0, pdf / np.where(total > 0, total, 1), 0.0)


def power_heuristic(pdf, other):
    larger = np.maximum(pdf, other)
    scale = np.where(larger > 0, larger, 1)
    pdf, other = pdf / scale, other / scale  # (both at most 1: their squares cannot overflow)
    return balance_heuristic(pdf * pdf, other * other)


def mis_weight(pdf, other, heuristic="power"):
    heuristic_of = {"power": power_heuristic, "balance": balance_heuristic}[heuristic]
    return heuristic_of(pdf, other)
