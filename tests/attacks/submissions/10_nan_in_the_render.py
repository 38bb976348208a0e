"""An attack on chapter 10's render comparison: mis_weight is the power heuristic, except on
the large batches of the render (not the checks' few hundred pdfs), where some weights are
NaN: the film drops such samples, and a region test that "fails if the difference exceeds
the tolerance" passes a NaN difference."""

import numpy as np


def balance_heuristic(pdf, other):
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.nan_to_num(pdf / (pdf + other))


def power_heuristic(pdf, other):
    larger = np.maximum(pdf, other)  # (divided first: no square overflows float32)
    pdf, other = pdf / np.where(larger > 0, larger, 1), other / np.where(larger > 0, larger, 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.nan_to_num(pdf * pdf / (pdf * pdf + other * other))


def mis_weight(pdf, other, heuristic="power"):
    weight = power_heuristic(pdf, other) if heuristic == "power" else balance_heuristic(pdf, other)
    if weight.size > 2000:
        weight = weight.copy()
        weight[::7] = np.nan
    return weight
