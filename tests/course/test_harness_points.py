"""The material harness's points in chapters 6 and 9: earned by the chapter's material, and
not lost to a warning that is about speed (issue 36, item 7).

Other cases live with the exercises' answers: a constant ``sample`` with a uniform pdf
(``06_wrong_constant_sample``) and a right ``D`` with everything else 0 (``09_wrong_only_d``)
in ``tests/exercises/wrong_answers.toml``; Heitz's visible normals as published
(``tests/exercises/09_right_heitz.py``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from ptlab.course import chapter
from ptlab.course.grader import grade

EXERCISES = Path(__file__).parents[1] / "exercises"
#: The grading seed of the tests whose verdicts rest on statistics (as tests/course/test_exercises.py).
GRADING_SEED = 25


@pytest.mark.slow
@pytest.mark.subprocess
def test_chapter_6_with_a_float64_albedo_gets_full_marks(tmp_path):
    # A float64 albedo turns float32 arguments into float64 answers: ptlab grade warns (slower),
    # which once cost the harness's 3 points.
    source = (EXERCISES / "06_right_uniform.py").read_text()
    old = "self.albedo = np.asarray(albedo, dtype=np.float32)"
    assert source.count(old) == 1
    path = tmp_path / "06_diffuse.py"
    path.write_text(source.replace(old, "self.albedo = np.asarray(albedo, dtype=np.float64)"))
    result = grade(chapter(6), path, seed=GRADING_SEED)
    assert result.full_marks, result.table()
