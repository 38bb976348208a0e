"""Trivial answers (docs/grading-security.md): a submission that does none of the work has
properties a check may test alone (every ray forward has unit length, a ray-triangle test
that always misses gets the parallel rays right). Each earns nothing now: the checks of the
core behaviour fail it, and the checks of secondary properties score only when those pass
(``ChapterCheck.requires``)."""

from __future__ import annotations

import pytest

from ptlab.course import chapter
from ptlab.course.chapter import Chapter, ChapterCheck, CheckFailed
from ptlab.course.grader import grade

#: Each trivial submission, and the checks that passed on it before ``requires``: they
#: pass by themselves still (a quick one says so; a render or a harness is not run), and
#: score nothing.
TRIVIAL = {
    "trivial_01_constant_rays.py": ["unit directions"],
    "trivial_02_always_miss.py": ["parallel rays"],
    "trivial_03_constants.py": ["total internal reflection"],
    "trivial_04_hit_at_tmin.py": ["starting inside", "render"],
    "trivial_05_no_work.py": ["closest hits", "render"],
    "trivial_06_zero_material.py": ["material harness"],
    "trivial_09_zero_metal.py": ["harness (hemisphere)", "harness (importance)"],
}


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.parametrize("name", sorted(TRIVIAL))
def test_a_trivial_answer_earns_nothing(attack, name):
    found = chapter(name[8:10])
    result = grade(found, attack(name))
    assert result.score == 0, result.table()
    messages = {r.name: r.message for r in result.results}
    for check in (c for c in found.checks if c.name in TRIVIAL[name]):
        assert messages[check.name].startswith("not graded until "), result.table()
        assert ("by itself it passes" in messages[check.name]) == check.quick, result.table()


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_render_right_with_any_slab_test_is_not_run_before_the_slab_test_works(attack):
    # Every ray hitting every box draws the right picture (the BVH tests every triangle):
    # it passed the render for 2 points, which is not run now.
    result = grade(chapter(4), attack("trivial_04_hit_at_tmin.py"))
    render = {r.name: r for r in result.results}["render"]
    assert render.message.startswith(
        "not graded until 'entering a box' passes; 'entering a box' says: a ray entering"
    ), result.table()
    assert render.points == 0
    assert render.seconds == 0.0


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_bvh_without_the_sah_earns_the_traversal_checks_and_none_of_the_sahs(attack):
    """A middle split with a right child_order: the traversal piece is real work, so it earns
    'near child first' (1), 'traversal order' (1), and the BVH's closest hits (2) and render
    (1), which any valid split passes and which count with the traversal piece's own check.
    The SAH's checks (costs 2, empty sides 1, best split 1, tree quality 1) it fails: 5 of 10.
    The same split with the low child always first earns 0 (trivial_05_no_work.py)."""
    result = grade(chapter(5), attack("trivial_05_middle_split.py"))
    passed = {r.name for r in result.results if r.passed}
    assert passed == {"near child first", "closest hits", "traversal order", "render"}, result.table()
    assert result.score == 5, result.table()


# -- requires= scoring, on checks of our own -------------------------------------------------

#: The checks that ran in this process (a check runs in the grader, on the student's module).
RAN: list[str] = []


def _check(name: str, passes: bool):
    def run(module) -> str:
        RAN.append(name)
        if not passes:
            raise CheckFailed(f"{name} is wrong")
        return f"{name} is right"

    return run


def _chapter(core_passes: bool) -> Chapter:
    """Chapter 1 (its template gives the rules) with checks whose verdicts are set: a core
    check, a quick one that builds on it, one built on that, a slow one built on the core,
    and one of its own."""
    return Chapter(
        number=1,
        slug="cameras",
        title="requires",
        functions=("generate_rays",),
        checks=(
            ChapterCheck("core", 3, _check("core", core_passes), timeout=30),
            ChapterCheck("secondary", 2, _check("secondary", True), timeout=30, requires=("core",)),
            ChapterCheck("chained", 1, _check("chained", False), timeout=30, requires=("secondary",)),
            ChapterCheck("slow", 4, _check("slow", True), timeout=60, requires=("core",)),
            ChapterCheck("alone", 1, _check("alone", True), timeout=30),
        ),
    )


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_check_whose_requirement_failed_scores_nothing_and_says_why(tmp_path):
    path = tmp_path / "01_cameras.py"
    path.write_text("def generate_rays(camera, width, height, pixel_x, pixel_y, u):\n    return None\n")
    RAN.clear()
    result = grade(_chapter(core_passes=False), path)
    by_name = {r.name: r for r in result.results}
    assert [r.points for r in result.results] == [0, 0, 0, 0, 1], result.table()
    assert not any(r.passed for r in result.results[:4])
    # The quick one still runs, and tells what it found by itself; the slow one is not run,
    # and tells what the check it waits for found.
    assert by_name["secondary"].message == (
        "not graded until 'core' passes; by itself it passes: secondary is right"
    )
    assert by_name["chained"].message == (
        "not graded until 'secondary' passes; by itself it fails: chained is wrong"
    )
    assert by_name["slow"].message == "not graded until 'core' passes; 'core' says: core is wrong"
    assert RAN == ["core", "secondary", "chained", "alone"]

    RAN.clear()
    result = grade(_chapter(core_passes=True), path)
    assert [r.points for r in result.results] == [3, 2, 0, 4, 1], result.table()
    assert {r.name: r.message for r in result.results}["chained"] == "chained is wrong"
    assert RAN == ["core", "secondary", "chained", "slow", "alone"]


def test_a_check_may_require_only_earlier_checks_of_its_chapter():
    core = ChapterCheck("core", 1, _check("core", True))
    for checks in [
        (ChapterCheck("secondary", 1, _check("secondary", True), requires=("core",)), core),
        (core, ChapterCheck("secondary", 1, _check("secondary", True), requires=("cor",))),
    ]:
        with pytest.raises(ValueError, match="which are not earlier checks"):
            Chapter(number=1, slug="cameras", title="x", functions=(), checks=checks)
