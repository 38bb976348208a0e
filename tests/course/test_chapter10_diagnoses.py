"""Chapter 10's diagnoses, on heuristics written in this process (no student's process):
what the known-values checks say of a constant added to the denominator."""

from __future__ import annotations

import numpy as np
import pytest

from ptlab.course.chapter import CheckFailed, grading_seed
from ptlab.course.chapters import ch10_mis
from ptlab.course.messages import language

CASES = [(1, 1, 0.5), (3, 1, 0.75), (1, 3, 0.25), (0.2, 0.6, 0.25), (2, 0, 1.0)]


def balance_heuristic(pdf, other):  # (the students' name, and their usual slip)
    pdf, other = np.asarray(pdf), np.asarray(other)
    return pdf / (pdf + other + 1e-3)


def right_balance_heuristic(pdf, other):
    pdf, other = np.asarray(pdf), np.asarray(other)
    total = pdf + other
    return np.where(total > 0, pdf / np.where(total > 0, total, 1), 0)


def test_a_constant_in_the_denominator_is_named_by_the_known_values_check_with_its_size():
    with grading_seed(25), language("en"), pytest.raises(CheckFailed) as failed:
        ch10_mis._known_values(balance_heuristic, CASES, "pdf / (pdf + other)")
    message = str(failed.value)
    assert "a constant is added to the denominator" in message
    assert "eps ≈ 0.001" in message
    assert "np.where" in message


def test_the_known_values_check_passes_a_right_heuristic():
    with grading_seed(25), language("en"):
        assert "known values" in ch10_mis._known_values(right_balance_heuristic, CASES, "pdf / (pdf + other)")
