"""grade-all's pairs of alike students (``ptlab.course.alike``, ``ptlab.course.batch``):
honest answers written apart are not reported, copies with the names changed and the code
reordered are, and the report is printed after the grades and written to its own CSV."""

from __future__ import annotations

import csv
import shutil
from itertools import combinations
from pathlib import Path

import pytest
from alike_corpus import EXERCISES, copied, honest

from ptlab.cli import main
from ptlab.course import all_chapters, chapter
from ptlab.course.alike import MAX_COMPARED_BYTES, MIN_SHARED, THRESHOLD, alike_pairs, fingerprints

CHAPTERS = [c.number for c in all_chapters()]
#: How far above every honest pair written apart (of at least MIN_SHARED shared
#: fingerprints) the threshold must stay: measured, 0.24 (ptlab.course.alike's docstring).
HONEST_MARGIN = 0.2


def _prints(source: str) -> frozenset[int]:
    found = fingerprints({"file.py": source.encode()})
    assert found is not None
    return found


def _similarity(first: frozenset[int], second: frozenset[int]) -> float:
    return len(first & second) / min(len(first), len(second))


@pytest.mark.parametrize("number", CHAPTERS)
def test_honest_answers_written_apart_are_not_reported(number):
    submissions = honest(number)
    prints = {h.label: _prints(h.source) for h in submissions}
    authors = {h.label: h.author for h in submissions}
    for pair in alike_pairs(prints):
        assert authors[pair.first] == authors[pair.second], pair  # (one author's files: alike)
    for first, second in combinations(submissions, 2):
        shared = len(prints[first.label] & prints[second.label])
        if first.author != second.author and shared >= MIN_SHARED:
            score = _similarity(prints[first.label], prints[second.label])
            assert score <= THRESHOLD - HONEST_MARGIN, (first.label, second.label, score)


@pytest.mark.parametrize("number", CHAPTERS)
def test_a_copy_with_the_names_changed_and_the_code_reordered_is_reported(number):
    copies = 0
    for seed, submission in enumerate(honest(number)):
        original = _prints(submission.source)
        if len(original) < MIN_SHARED:
            continue  # (chapters 2, 4 and 10: too small to tell copying from the formula)
        dressed = copied(submission.source, seed)
        assert dressed != submission.source
        (pair,) = alike_pairs({"original": original, "copy": _prints(dressed)})
        assert pair.similarity == 1.0, (submission.label, pair)
        copies += 1
    assert copies or number in (2, 4, 10)


def test_the_score_is_the_share_of_the_smaller_submission_found_in_the_other():
    mine = frozenset(range(100))
    padded = mine | frozenset(range(1000, 1400))  # a copy with four times as much of its own
    assert alike_pairs({"a": mine, "b": padded})[0].similarity == 1.0
    four_fifths = frozenset(range(80)) | frozenset(range(2000, 2020))
    (pair,) = alike_pairs({"a": mine, "b": four_fifths})
    assert (pair.similarity, pair.shared, pair.sizes) == (0.8, 80, (100, 100))
    assert alike_pairs({"a": mine, "b": frozenset(range(79)) | frozenset(range(2000, 2021))}) == []
    # Too few shared fingerprints say nothing, however alike.
    small = frozenset(range(MIN_SHARED - 1))
    assert alike_pairs({"a": small, "b": small}) == []
    # The most similar first, each pair once.
    found = alike_pairs({"a": mine, "b": four_fifths, "c": mine, "d": frozenset(range(500, 600))})
    assert [(p.first, p.second, p.similarity) for p in found] == [
        ("a", "c", 1.0),
        ("a", "b", 0.8),
        ("b", "c", 0.8),
    ]


def test_what_the_exercise_file_gives_is_no_evidence():
    template = chapter(7).template.read_text()
    assert fingerprints({"07_path_tracing.py": template.encode()}) == frozenset()


def test_submissions_that_cannot_be_read_are_not_compared():
    right = (EXERCISES / "07_right_own_code.py").read_bytes()
    assert fingerprints({"a.py": right})
    assert fingerprints({"a.py": right, "b.py": b"def f(:\n"}) is None
    assert fingerprints({"a.py": right + b"#" * MAX_COMPARED_BYTES}) is None


# -- in grade-all ------------------------------------------------------------------------------

#: An honest chapter-1 answer written apart from tests/exercises/01_right_own_code.py, in
#: the homework's way (Renderer.cpp's scale and imageAspectRatio).
HOMEWORK_STYLE = """
import math

import numpy as np


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    scale = math.tan(math.radians(camera.fov_y * 0.5))
    image_aspect_ratio = width / height
    x = (2 * (pixel_x + u[:, 0]) / width - 1) * image_aspect_ratio * scale
    y = (1 - 2 * (pixel_y + u[:, 1]) / height) * scale
    directions = np.outer(x, camera.right) + np.outer(y, camera.up) + camera.forward
    lengths = np.sqrt(np.einsum("ij,ij->i", directions, directions))
    origins = np.broadcast_to(camera.position, directions.shape)
    return np.array(origins, dtype=np.float32), (directions / lengths[:, None]).astype(np.float32)
"""


def _class(tmp_path: Path) -> Path:
    """alice: a right answer; bob (a folder): alice's, names changed and code reordered;
    carol: a right answer written apart; dave: the exercise file as handed out."""
    folder = tmp_path / "class"
    (folder / "bob").mkdir(parents=True)
    right = (EXERCISES / "01_right_own_code.py").read_text()
    (folder / "alice.py").write_text(right)
    (folder / "bob" / "01_cameras.py").write_text(copied(right, 7))
    (folder / "carol.py").write_text(HOMEWORK_STYLE)
    shutil.copyfile(chapter(1).template, folder / "dave.py")
    return folder


@pytest.mark.slow
@pytest.mark.subprocess
def test_grade_all_prints_and_writes_the_pairs_alike_after_the_grades(tmp_path, capsys):
    folder, grades = _class(tmp_path), tmp_path / "grades.csv"
    command = ["exercise", "grade-all", "1", str(folder), "--csv", str(grades), "--timeout-scale", "0.3"]
    assert main(command) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[-3:] == [
        "4 students in " + str(grades) + ": 3 with full marks",
        "alike: alice.py and bob/01_cameras.py: 1.00 (46 of 46 fingerprints; look at them)",
        f"1 pair of alike students in {tmp_path / 'grades-alike.csv'}",
    ]
    rows = list(csv.DictReader((tmp_path / "grades-alike.csv").open()))
    assert rows == [
        {
            "student_a": "alice",
            "file_a": "alice.py",
            "student_b": "bob",
            "file_b": "01_cameras.py",
            "similarity": "1.000",
            "shared": "46",
            "size_a": "46",
            "size_b": "46",
        }
    ]
    # Resumed (nobody graded again), every submission is compared again; --alike elsewhere.
    (folder / "erin.py").symlink_to(folder / "alice.py")  # (a link: no submission, no pair)
    assert main([*command, "--alike", str(tmp_path / "pairs.csv")]) == 0
    assert "alike: alice.py and bob/01_cameras.py: 1.00" in capsys.readouterr().out
    assert len(list(csv.DictReader((tmp_path / "pairs.csv").open()))) == 1


def test_an_output_that_cannot_be_written_stops_grade_all_before_it_grades(tmp_path, capsys):
    folder, grades = _class(tmp_path), tmp_path / "grades.csv"
    for alike in (tmp_path / "missing" / "pairs.csv", tmp_path, grades):
        assert (
            main(["exercise", "grade-all", "1", str(folder), "--csv", str(grades), "--alike", str(alike)])
            == 2
        )
        error = capsys.readouterr().err.strip()
        assert error.startswith(f"ptlab: error: --alike {alike}"), error
        assert "\n" not in error
        assert not grades.exists()  # (nothing graded)


def test_a_default_moved_away_from_its_if_is_the_same_code():
    """``x = None`` then ``if c: x = f()`` is one choice of a value, whatever independent
    statement a copier puts between the two (found by a reordered copy of chapter 8's
    library answer), but not past a statement that uses ``x`` or changes what the default
    reads."""
    together = "def f(a, b):\n    t = g(a)\n    x = None\n    if a > 0:\n        x = h(a)\n    return t, x\n"
    apart = "def f(a, b):\n    x = None\n    t = g(a)\n    if a > 0:\n        x = h(a)\n    return t, x\n"
    used_between = (
        "def f(a, b):\n    x = None\n    t = g(x)\n    if a > 0:\n        x = h(a)\n    return t, x\n"
    )
    assert _prints(apart) == _prints(together)
    assert _prints(used_between) != _prints(together)
