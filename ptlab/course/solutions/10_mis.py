"""Chapter 10, the library's own answer: ``ptlab.integrators.path.mis_weight``.

The library has the two heuristics as the two branches of ``mis_weight``; the exercise's
names call it with each.
"""

from ptlab.integrators.path import mis_weight

__all__ = ["balance_heuristic", "mis_weight", "power_heuristic"]


def balance_heuristic(pdf, other):
    """pdf / (pdf + other), 0 where both are 0."""
    return mis_weight(pdf, other, "balance")


def power_heuristic(pdf, other):
    """pdf^2 / (pdf^2 + other^2), 0 where both are 0."""
    return mis_weight(pdf, other, "power")
