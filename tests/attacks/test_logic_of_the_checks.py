"""Attacks on the logic of the checks (docs/grading-security.md): a function that changes the
grader's inputs, a file that hangs at import in every check, one that hangs in ptlab grade.
Each earns nothing, and costs no more time than its limits."""

from __future__ import annotations

import time

import numpy as np
import pytest

import ptlab.course.sandbox.submission
from attacks.hostile import assert_honest_failure
from ptlab.cli import main
from ptlab.course import chapter
from ptlab.course.grader import grade
from ptlab.course.sandbox import ArgumentChanged, Arguments, ProcessGuard, Rules, Submission

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes


def test_changing_an_argument_it_may_only_read_fails_the_check(attack):
    result = grade(chapter(7), attack("07_writeback_survive.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert result.score == 0, result.table()
    bounce = {r.name: r for r in result.results}["indirect bounce"]
    assert "scatter changed its argument survive, which it must only read" in bounce.message


def test_only_the_arguments_a_function_writes_come_back(tmp_path):
    path = tmp_path / "student.py"
    path.write_text(
        "def step(film, u, scratch):\n"
        "    film += 1\n    scratch *= 2\n    return 0\n"
        "def cheat(film, u, scratch):\n"
        "    u[:] = 0\n    return 0\n"
    )
    arguments = Arguments(("film", "u", "scratch"), writes=("film",), scratch=("scratch",))
    rules = Rules(arguments={"step": arguments, "cheat": arguments})
    film, u, scratch = np.zeros(4), np.ones(4), np.ones(4)
    with ProcessGuard() as guard, Submission(path, guard, time_limit=30, rules=rules) as submission:
        submission.module.step(film, u, scratch)
        assert (film == 1).all()
        assert (scratch == 1).all()
        assert (u == 1).all()
        with pytest.raises(ArgumentChanged) as changed:
            submission.module.cheat(film, u, scratch)
        assert "cheat changed its argument u, which it must only read" in changed.value.describe()
        assert (u == 1).all()  # and nothing of it reached the grader


def test_a_file_that_hangs_at_import_costs_one_import_limit_not_every_check(tmp_path, monkeypatch):
    monkeypatch.setattr(ptlab.course.sandbox.submission, "IMPORT_TIME_LIMIT", 2.0)
    path = tmp_path / "06_diffuse.py"
    path.write_text("import time\ntime.sleep(3600)\n")
    start = time.monotonic()
    result = grade(chapter(6), path)  # five checks of 30 to 60 s each
    assert time.monotonic() - start < 20
    assert_honest_failure(result, "took longer than 2 s")
    assert all(r.message.startswith("not run: ") for r in result.results[1:])


def test_ptlab_grade_of_a_file_that_hangs_at_import_ends_within_the_import_limit(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.setattr(ptlab.course.sandbox.submission, "IMPORT_TIME_LIMIT", 2.0)
    path = tmp_path / "material.py"
    path.write_text("import time\ntime.sleep(3600)\n")
    start = time.monotonic()
    assert main(["grade", f"{path}:Material"]) == 2  # its whole limit is 900 s
    assert time.monotonic() - start < 20
    assert "took longer than 2 s" in capsys.readouterr().err
