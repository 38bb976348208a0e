"""``ptlab exercise render``: a scene rendered with a student's functions, beside the
library's render of it, and their difference (``ptlab.course.side_by_side``)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from ptlab.cli import main
from ptlab.course import all_chapters, chapter
from ptlab.image import read_image

WRONG = Path(__file__).parents[1] / "exercises"
#: A small render: a few seconds per command, the student's process included.
SMALL = ["--res", "40x30", "--spp", "1", "--quiet"]


def _pictures(folder: Path, stem: str) -> dict[str, np.ndarray]:
    return {name: read_image(folder / f"{stem}-{name}.png")[0] for name in ("yours", "library", "difference")}


@pytest.mark.subprocess
def test_a_right_answer_renders_the_librarys_picture_and_a_wrong_one_shows_its_mistake(tmp_path, capsys):
    right = WRONG / "01_right_own_code.py"
    assert main(["exercise", "render", "1", str(right), *SMALL, "--out", str(tmp_path / "right")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("0.0% of the pixels differ"), out
    pictures = _pictures(tmp_path / "right", "01-cornell-box")
    assert pictures["yours"].shape == (30, 40, 3)
    assert np.array_equal(pictures["yours"], pictures["library"])
    assert pictures["difference"].max() == 0
    # Rows taken as going up: the picture upside down, where the difference shows it.
    wrong = tmp_path / "01_cameras.py"
    text = right.read_text(encoding="utf-8")
    flipped = text.replace(
        "y = (1 - 2 * (pixel_y + u[:, 1]) / height)", "y = (2 * (pixel_y + u[:, 1]) / height - 1)"
    )
    assert flipped != text
    wrong.write_text(flipped, encoding="utf-8")
    assert main(["exercise", "render", "1", str(wrong), *SMALL, "--out", str(tmp_path / "wrong")]) == 0
    share = float(capsys.readouterr().out.split("%")[0])
    assert share > 30
    pictures = _pictures(tmp_path / "wrong", "01-cornell-box")
    assert (pictures["difference"].max(axis=2) > 0).mean() > 0.3


@pytest.mark.subprocess
def test_render_says_what_went_wrong_in_one_line(tmp_path, capsys):
    template = tmp_path / "04_bounding_boxes.py"
    shutil.copyfile(chapter(4).template, template)
    whitted = WRONG / "03_wrong_eta_inverted.py"
    for arguments, code, message in [
        (["4", str(template)], 1, "not written yet"),
        (["3", str(whitted), "--scene", "cornell-box"], 1, "no mirror and no glass"),
        (["99", str(template)], 2, "no such chapter"),
        (["4", str(tmp_path / "missing.py")], 2, "no such file"),
        (["4", str(template), "--res", "wide"], 2, "expected N or WxH"),
        (["4", str(template), "--spp", "0"], 2, "--spp 0"),
        (["4", str(template), "--scene", "no-such-scene"], 2, "no-such-scene"),
    ]:
        assert main(["exercise", "render", *SMALL, "--out", str(tmp_path), *arguments]) == code, arguments
        error = capsys.readouterr().err
        assert message in error, (arguments, error)
        assert error.count("\n") == 1, error
    assert not list(tmp_path.glob("*.png"))


#: Chapters whose functions change no picture: 11's decide where a render's samples go.
WITHOUT_RENDER = {11}


def test_every_chapter_says_what_its_render_shows():
    from ptlab.scene_file import builtin_scene_names

    for found in all_chapters():
        if found.number in WITHOUT_RENDER:
            assert found.render is None
            continue
        assert found.render is not None, found.number
        assert found.render.scene in builtin_scene_names()


def test_a_chapter_without_a_render_says_so_in_one_line(tmp_path):
    from ptlab.course.side_by_side import render_side_by_side
    from ptlab.errors import PtlabError

    with pytest.raises(PtlabError, match=r"^chapter 11 has no render to set beside the library's: "):
        render_side_by_side(chapter(11), WRONG / "11_right_own_code.py", lang="en")
