"""An attack on ``ptlab grade`` that recognises its probes: the old probes sent one wo and
one n on every row of a call, which no render does, so a material could be right only
then. Every probe now turns each row by a rotation of its own
(``ptlab.grading.probes``)."""

from __future__ import annotations

import pytest

from ptlab.cli import main

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes


def test_a_material_right_only_for_repeated_rows_fails(attack, capsys):
    path = attack("recognises_the_grader.py")
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out
    assert "PASSED" not in out
    assert "energy" in out
    assert "without the 1/pi" in out
