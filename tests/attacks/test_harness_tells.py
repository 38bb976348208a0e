"""Attacks on the material harness through what its probes look like (docs/grading-security.md):

* a material right in calls of the grader's sizes and 7.6x too bright in calls of a render's
  (``harness_batch_size.py``): rows are now asked again inside batches of a render's size
  (2^18) and of sizes drawn at random per run, and chapter 6's render has calls of a
  render's sizes;
* a material that gives no direction (``sample`` returns -n, pdf and eval 0:
  ``harness_null.py``), and one that is consistent but black (``harness_black.py``): the
  harness fails the first ("sample returns no direction with a positive pdf") and names the
  second ("reflects nothing"); the exercises' harness points need the chapter's eval.
"""

from __future__ import annotations

import pytest

from attacks.hostile import verdict_lines
from ptlab.cli import main
from ptlab.course import chapter
from ptlab.course.grader import grade

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes


def _by_name(result) -> dict:
    return {check.name: check for check in result.results}


def test_a_material_that_knows_the_graders_batch_sizes_fails_ptlab_grade(attack, capsys):
    path = attack("harness_batch_size.py")
    # 200 000 samples per wo: the exercises' harness, whose sizes it dodges as the default's.
    assert main(["grade", f"{path}:Lambertian", "--samples", "200000"]) == 1
    out = capsys.readouterr().out
    failed = next(line for line in out.splitlines() if line.startswith("FAILED:"))
    # (Its calls of a render's sizes now differ from its rows asked alone, and its
    # samples from the pdf: row independence fails among others.)
    assert "row independence" in failed, out


def test_a_material_that_knows_the_graders_batch_sizes_gets_no_harness_or_render_points(attack):
    result = grade(chapter(6), attack("harness_batch_size.py", "06_diffuse.py"))
    checks = _by_name(result)
    for name in ("material harness", "render"):
        assert not checks[name].passed, result.table()
        assert checks[name].points == 0, result.table()
    assert "row independence" in checks["material harness"].message, result.table()
    assert "brighter" in checks["render"].message, result.table()
    # It is right in small calls: the checks made of them still say so (nothing else fails).
    assert result.score == 5, result.table()


def test_a_material_that_gives_no_direction_fails_ptlab_grade(attack, capsys):
    path = attack("harness_null.py")
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    out = capsys.readouterr().out
    assert "FAILED: reflectance" in out, out
    assert "sample returns no direction with a positive pdf" in " ".join(out.split()), out


@pytest.mark.parametrize(("number", "name"), [(6, "06_diffuse.py"), (9, "09_microfacet.py")])
def test_a_material_that_gives_no_direction_gets_nothing(attack, number, name):
    result = grade(chapter(number), attack("harness_null.py", name))
    assert result.score == 0, result.table()
    harness = [c for c in result.results if "harness" in c.name]
    # (Its own verdict, or the gate before it: "not graded until 'sample' passes".)
    assert harness, result.table()
    assert all("reflects nothing" in c.message or "not graded until" in c.message for c in harness), (
        result.table()
    )


def test_a_black_material_passes_ptlab_grade_with_a_warning(attack, capsys):
    path = attack("harness_black.py")
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 0
    out = capsys.readouterr().out
    assert verdict_lines(out)[-1] == "PASSED, with warnings: reflectance", out
    assert "reflects nothing: albedo 0 for every probe" in " ".join(out.split()), out


@pytest.mark.parametrize(("number", "name"), [(6, "06_diffuse.py"), (9, "09_microfacet.py")])
def test_a_black_material_earns_no_harness_points(attack, number, name):
    result = grade(chapter(number), attack("harness_black.py", name))
    harness = [c for c in result.results if "harness" in c.name]
    assert harness, result.table()
    assert all(not c.passed and c.points == 0 for c in harness), result.table()
    assert all("reflects nothing" in c.message or "not graded until" in c.message for c in harness), (
        result.table()
    )
