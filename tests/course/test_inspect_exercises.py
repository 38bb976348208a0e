"""``ptlab exercise inspect`` (``ptlab.course.inspection``): a student's functions against
the library's at one pixel, and the command a failing render check suggests. Deterministic:
both sides trace the same samples, so a right answer agrees and a wrong one differs at a
vertex known in advance."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from test_exercises import WRONG, _wrong_answer_text

from ptlab.cli import main
from ptlab.course.inspect_command import suggestion
from ptlab.course.inspection import Difference, first_difference, message
from ptlab.course.messages import language
from ptlab.inspector import PixelInspection
from ptlab.inspector.records import BsdfSample, Sample, Vertex


def student_file(tmp_path, name: str, chapter_file: str):
    """The typical wrong (or right) answer ``name`` as a student's file named as the chapter's."""
    path = tmp_path / chapter_file
    path.write_text(_wrong_answer_text(name), encoding="utf-8")
    return path


@pytest.mark.subprocess
def test_wrong_mis_weights_differ_at_the_first_light_sample(tmp_path, capsys):
    path = student_file(tmp_path, "10_wrong_argument_order", "10_mis.py")
    out = tmp_path / "first.json"
    code = main(["exercise", "inspect", "10", str(path), "--pixel", "16,16", "--json", str(out)])
    assert code == 1
    printed = capsys.readouterr().out
    assert "sample 0, depth 0: your light.mis_weight" in printed
    found = json.loads(out.read_text())["first_difference"]
    assert (found["sample"], found["depth"], found["quantity"]) == (0, 0, "light.mis_weight")
    # The other strategy's weight: the power heuristic of (other, pdf), not (pdf, other).
    assert found["expected"] == pytest.approx(1.0)
    assert found["yours"] < 1e-6


@pytest.mark.subprocess
def test_a_pdf_without_walters_jacobian_is_found_where_the_path_first_meets_a_metal(tmp_path, capsys):
    path = student_file(tmp_path, "09_wrong_pdf_of_h", "09_microfacet.py")
    assert main(["exercise", "inspect", "9", str(path), "--pixel", "16,16", "--lang", "zh"]) == 1
    printed = capsys.readouterr().out
    assert printed.startswith("样本 6，深度 1：你的 bsdf.pdf 是 "), printed


@pytest.mark.subprocess
def test_a_right_answer_agrees_and_a_black_light_differs_at_the_lamp(tmp_path, capsys):
    right = tmp_path / "07_path_tracing.py"
    shutil.copyfile(WRONG / "07_right_own_code.py", right)
    out = tmp_path / "agree.json"
    assert main(["exercise", "inspect", "7", str(right), "--pixel", "16,4", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["first_difference"] is None
    assert "agree at pixel (16, 4)" in capsys.readouterr().out
    (tmp_path / "wrong").mkdir()
    wrong = student_file(tmp_path / "wrong", "07_wrong_black_light", "07_path_tracing.py")
    assert main(["exercise", "inspect", "7", str(wrong), "--pixel", "16,4"]) == 1
    # The pieces agree; the loop's sample misses the lamp's Le (47.8 in red) it sees.
    assert capsys.readouterr().out.startswith("sample 0: your contribution (2.5")


@pytest.mark.subprocess
def test_eta_the_wrong_way_up_changes_the_first_fresnel_weight(tmp_path, capsys):
    path = tmp_path / "03_whitted.py"
    shutil.copyfile(WRONG / "03_wrong_eta_inverted.py", path)
    # Pixel (30, 35) of the render check's view sees the glass block; with eta the wrong way
    # up, the Fresnel weight of the first reflected ray is the first number to differ.
    assert main(["exercise", "inspect", "3", str(path), "--pixel", "30,35"]) == 1
    assert capsys.readouterr().out.startswith("sample 0, depth 0: your reflected ray weight (")


def _inspection(*vertices: Vertex, contribution=(1.0, 1.0, 1.0)) -> PixelInspection:
    return PixelInspection(
        "scene", (0, 0), list(contribution), [Sample(0, list(contribution), list(vertices))]
    )


def _vertex(depth: int, pdf: float | None, wi=(0.0, 0.0, 1.0)) -> Vertex:
    return Vertex(
        depth,
        [0.0, 0.0, 0.0],
        3,
        "white",
        [0.0, 0.0, 1.0],
        True,
        [0.0, 0.0, 1.0],
        bsdf=BsdfSample(list(wi), pdf=pdf),
    )


def test_first_difference_compares_only_what_both_recorded():
    library = _inspection(_vertex(0, 0.318), _vertex(1, 0.2))
    assert first_difference(_inspection(_vertex(0, 0.318 * (1 + 1e-5)), _vertex(1, 0.2)), library) is None
    # A field one side did not record (a student's piece seen from outside) is not compared.
    assert first_difference(_inspection(_vertex(0, None), _vertex(1, 0.2)), library) is None
    found = first_difference(_inspection(_vertex(0, 0.318), _vertex(1, 0.1)), library)
    assert found == Difference(0, 1, "bsdf.pdf", 0.1, 0.2)
    assert message(found, (0, 0), 1) == "sample 0, depth 1: your bsdf.pdf 0.1, the library's 0.2"
    shorter = first_difference(_inspection(_vertex(0, 0.318)), library)
    assert shorter == Difference(0, 1, "vertices", 1, 2)


def test_the_suggested_pixel_is_where_the_images_differ_most():
    rng = np.random.default_rng(3)
    library = rng.random((4, 10, 12, 3))  # (passes, H, W, 3)
    student = library.copy()
    student[:, 7, 2] += 0.5  # x 2, y 7
    student[:, 1, 1, 0] = np.nan  # NaN beats everything: it is the worst pixel
    assert "--pixel 1,1 --seed 5 " in suggestion(7, student, library, 5)
    student[:, 1, 1, 0] = library[:, 1, 1, 0]
    with language("zh"):
        line = suggestion(9, student[0], library[0], 12)
    assert "ptlab exercise inspect 9 你的文件 --pixel 2,7 --seed 12" in line
