"""``ptlab compare A B`` (``ptlab.measure.compare``): the figures are the metric's, the files
are read as linear values wherever they come from, a crop is placed in its image, and bad
input is one line with exit code 2. Also: a command's unknown option points at the command's
own --help (issue 39, item 7)."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from ptlab.cli import COMMANDS, build_parser, main
from ptlab.image import ImageFile, Window, read_image_file, srgb_decode, srgb_encode, write_image
from ptlab.measure.compare import compare_files
from ptlab.measure.metrics import relmse

#: A planted difference: pixel (x, y) = (5, 2), channel G, by this much.
PLANTED = (5, 2, 1, 0.5)


def reference_image() -> np.ndarray:
    """(12, 16, 3) float32, values a render has (0.02 to 3), fixed seed."""
    return np.random.default_rng(0).uniform(0.02, 3.0, (12, 16, 3)).astype(np.float32)


def changed(reference: np.ndarray) -> np.ndarray:
    """The reference with the ``PLANTED`` difference and three smaller ones elsewhere."""
    image = reference.copy()
    x, y, channel, amount = PLANTED
    image[y, x, channel] += amount
    for x, y in ((0, 0), (15, 11), (7, 9)):
        image[y, x, 2] *= 1.01
    return image


@pytest.fixture
def pair(tmp_path):
    """Paths of A (``changed``) and B (the reference), both .exr."""
    reference = reference_image()
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    write_image(a, changed(reference))
    write_image(b, reference)
    return a, b


def test_the_figures_are_the_metrics_and_find_the_planted_difference(pair):
    a, b = pair
    comparison = compare_files(a, b)
    image, reference = changed(reference_image()), reference_image()
    assert comparison.relmse == pytest.approx(relmse(image, reference), rel=1e-12)
    assert comparison.relmse > 0
    expected_ratio = image.astype(np.float64).mean(axis=(0, 1)) / reference.astype(np.float64).mean(
        axis=(0, 1)
    )
    np.testing.assert_allclose(comparison.mean_ratio, expected_ratio, rtol=1e-12)
    x, y, channel, amount = PLANTED
    value, *where = comparison.largest
    assert where == [x, y, channel]
    assert value == pytest.approx(amount, rel=1e-5)
    assert comparison.differing == 4
    assert comparison.error_map().mean() == pytest.approx(comparison.relmse, rel=1e-12)


def test_an_image_against_itself_is_identical(pair, capsys):
    _, b = pair
    assert main(["compare", str(b), str(b), "--tolerance", "0"]) == 0
    out = capsys.readouterr().out
    assert "relMSE              0\n" in out
    assert "0 of 192 (identical)" in out
    assert "R 1  G 1  B 1" in out


def test_the_command_prints_the_figures_and_exits_by_the_tolerance(pair, capsys):
    a, b = pair
    error = compare_files(a, b).relmse
    assert main(["compare", str(a), str(b)]) == 0  # (no tolerance: any difference is a report)
    out = capsys.readouterr().out
    assert f"{error:.6g}" in out
    assert "largest difference  0.5 at pixel (5, 2), G" in out
    assert "4 of 192 (2.08%)" in out
    assert main(["compare", str(a), str(b), "--tolerance", f"{error * 1.01}"]) == 0
    assert "within the tolerance" in capsys.readouterr().out
    assert main(["compare", str(a), str(b), "--tolerance", f"{error * 0.99}"]) == 1
    assert "above the tolerance" in capsys.readouterr().out


def test_json_holds_every_figure(pair, capsys):
    a, b = pair
    assert main(["compare", str(a), str(b), "--json", "--tolerance", "1e-9"]) == 1
    figures = json.loads(capsys.readouterr().out)
    comparison = compare_files(a, b)
    assert figures["relmse"] == comparison.relmse
    assert figures["largest_difference"] | {"value": 0} == {
        "value": 0,
        "x": 5,
        "y": 2,
        "channel": "G",
        "a": float(changed(reference_image())[2, 5, 1]),
        "b": float(reference_image()[2, 5, 1]),
    }
    assert figures["differing_pixels"] == 4
    assert figures["pixels"] == 192
    assert list(figures["mean_ratio"]) == ["R", "G", "B"]
    assert figures["a"] == {"path": str(a), "width": 16, "height": 12, "encoding": "linear", "window": None}
    assert figures["within_tolerance"] is False


def test_srgb_decode_inverts_the_encoding_and_is_colour_sciences():
    colour = pytest.importorskip("colour")
    encoded = np.linspace(0.0, 1.0, 1001)
    np.testing.assert_allclose(srgb_decode(encoded), colour.models.eotf_sRGB(encoded), atol=1e-12)
    np.testing.assert_allclose(srgb_encode(srgb_decode(encoded)), encoded, atol=1e-12)


def test_an_8_bit_png_is_compared_as_linear_values(tmp_path):
    # A PNG of an image in [0, 1] against the EXR of the same image: only the 8-bit rounding
    # differs. Compared as stored (sRGB-encoded) values, mid greys would look about 1.5-2
    # times too bright.
    linear = np.random.default_rng(1).uniform(0.05, 0.9, (10, 10, 3)).astype(np.float32)
    write_image(tmp_path / "a.png", linear)
    write_image(tmp_path / "b.exr", linear)
    found = read_image_file(tmp_path / "a.png")
    assert found.srgb
    assert not read_image_file(tmp_path / "b.exr").srgb
    comparison = compare_files(tmp_path / "a.png", tmp_path / "b.exr")
    np.testing.assert_allclose(comparison.mean_ratio, 1.0, atol=0.005)
    assert comparison.relmse < 1e-4
    assert comparison.a.srgb


def test_a_crop_is_compared_with_its_window_of_the_whole_image(tmp_path, capsys):
    reference = reference_image()
    window = Window(4, 3, 16, 12)
    part = reference[3:9, 4:12].copy()
    part[1, 2, 0] += 0.25  # (the whole image's pixel (6, 4))
    write_image(tmp_path / "crop.exr", part, window=window)
    write_image(tmp_path / "whole.exr", reference)
    assert read_image_file(tmp_path / "crop.exr").window == window
    for a, b in (("crop.exr", "whole.exr"), ("whole.exr", "crop.exr")):
        comparison = compare_files(tmp_path / a, tmp_path / b)
        assert comparison.image.shape == (6, 8, 3)
        assert (comparison.x, comparison.y) == (4, 3)
        assert comparison.largest[1:] == (6, 4, 0)
        assert comparison.differing == 1
    assert main(["compare", str(tmp_path / "crop.exr"), str(tmp_path / "whole.exr")]) == 0
    out = capsys.readouterr().out
    assert "8x6 window at (4, 3) of 16x12, linear" in out
    assert "compared            the 8x6 window at (4, 3)" in out
    assert main(["compare", str(tmp_path / "crop.exr"), str(tmp_path / "whole.exr"), "--json"]) == 0
    said = json.loads(capsys.readouterr().out)["a"]["window"]
    assert said == {"x": 4, "y": 3, "full_width": 16, "full_height": 12}
    # The same window of an image of another size: other pixels, said so.
    write_image(tmp_path / "other.exr", part, window=Window(4, 3, 32, 24))
    assert main(["compare", str(tmp_path / "crop.exr"), str(tmp_path / "other.exr")]) == 2
    assert "windows of images of different sizes (16x12 and 32x24)" in capsys.readouterr().err


def test_the_difference_picture_and_the_difference_values(pair, tmp_path, capsys):
    a, b = pair
    png, exr = tmp_path / "diff.png", tmp_path / "diff.exr"
    assert main(["compare", str(a), str(b), "--diff", str(png)]) == 0
    assert str(png) in capsys.readouterr().out
    picture = read_image_file(png)
    # (a false-colour map and its scale: more than the image's pixels, and coloured)
    assert picture.pixels.shape[0] > 12
    assert picture.pixels.shape[1] > 16
    assert np.ptp(picture.pixels[..., 0] - picture.pixels[..., 2]) > 0.3
    assert main(["compare", str(a), str(b), "--diff", str(exr), "--json"]) == 0
    values = read_image_file(exr).pixels
    error_map = compare_files(a, b).error_map()
    for channel in range(3):
        np.testing.assert_allclose(values[..., channel], error_map, rtol=1e-6)
    assert np.count_nonzero(values[..., 0]) == 4


@pytest.mark.parametrize(
    ("a", "b", "said"),
    [
        ("small.exr", "b.exr", "small.exr is 8x8, {tmp}/b.exr 16x12: the sizes differ"),
        ("nan.exr", "b.exr", "nan.exr: 1 pixel(s) NaN or infinite, the first at (3, 1)"),
        ("missing.exr", "b.exr", "missing.exr: no such image file"),
        (".", "b.exr", ": is a folder, not an image file"),
        ("text.exr", "b.exr", "text.exr: cannot read image"),
        ("left.exr", "right.exr", "are windows at different places of the image (0, 0) and (8, 4)"),
        ("b.exr", "negative.exr", "negative.exr: 1 pixel(s) negative, the first at (5, 2)"),
        ("b.exr", "overscan.exr", "overscan.exr: its 16x12 pixels at (0, 0) reach outside its 8x6 image"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, a, b, said):
    reference = reference_image()
    write_image(tmp_path / "b.exr", reference)
    write_image(tmp_path / "small.exr", reference[:8, :8])
    nan = reference.copy()
    nan[1, 3, 2] = np.nan
    write_image(tmp_path / "nan.exr", nan)
    (tmp_path / "text.exr").write_text("not an image")
    write_image(tmp_path / "left.exr", reference[:4, :8], window=Window(0, 0, 16, 12))
    write_image(tmp_path / "right.exr", reference[4:8, 8:16], window=Window(8, 4, 16, 12))
    negative = reference.copy()
    negative[2, 5, 1] = -0.01  # (where relMSE's (B + 0.01)^2 is 0)
    write_image(tmp_path / "negative.exr", negative)
    write_image(tmp_path / "overscan.exr", reference, window=Window(0, 0, 8, 6))
    assert main(["compare", str(tmp_path / a), str(tmp_path / b)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("ptlab: error: ")
    assert said.format(tmp=tmp_path) in err


def test_bad_options_are_one_line_and_exit_2(pair, tmp_path, capsys):
    a, b = pair
    assert main(["compare", str(a), str(b), "--tolerance", "-1"]) == 2
    assert "--tolerance -1.0: must be a relMSE, 0 or more" in capsys.readouterr().err
    assert main(["compare", str(a), str(b), "--diff", str(tmp_path / "diff.ppm")]) == 2
    assert "unsupported image format '.ppm'" in capsys.readouterr().err
    assert main(["compare", str(a), str(b), "--diff", str(tmp_path)]) == 2
    assert "is a folder; give an image file's name" in capsys.readouterr().err
    assert main(["compare", str(a), str(b), "--diff", str(tmp_path / "no" / "diff.png")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    before = a.read_bytes()
    assert main(["compare", str(a), str(b), "--diff", str(a)]) == 2  # (it would overwrite A)
    assert "is image A; write the difference elsewhere" in capsys.readouterr().err
    assert a.read_bytes() == before


def test_help_says_what_is_measured(capsys):
    with pytest.raises(SystemExit) as stopped:
        build_parser("compare").parse_args(["compare", "--help"])
    assert stopped.value.code == 0
    said = " ".join(capsys.readouterr().out.split())
    for words in (
        "relMSE",
        "(A - B)^2 / (B + 0.01)^2",
        "--diff FILE",
        "--tolerance RELMSE",
        "--json",
        "sRGB",
    ):
        assert words in said


def test_image_file_linear_keeps_float_pixels_as_they_are():
    pixels = np.full((2, 2, 3), 0.5, np.float32)
    assert ImageFile(pixels, {}, srgb=False, window=None).linear is pixels
    np.testing.assert_allclose(
        ImageFile(pixels, {}, srgb=True, window=None).linear, srgb_decode(0.5), rtol=1e-6
    )


# -- a typo'd option names the command's own --help (issue 39, item 7) ----------------------


def commands_of(parser: argparse.ArgumentParser, words: tuple[str, ...] = ()):
    """Each command line that reaches a command's parser (``render``, ``exercise check``, ...),
    its required arguments filled in, with that parser's name."""
    sub = [action for action in parser._actions if isinstance(action, argparse._SubParsersAction)]
    if not sub:
        yield [*words, *_required(parser)], parser.prog
        return
    for name, command in sub[0].choices.items():
        yield from commands_of(command, (*words, *_required(parser), name))


def _required(parser: argparse.ArgumentParser) -> list[str]:
    """Values for the parser's required arguments (positionals and required options)."""
    words: list[str] = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        value = str(action.choices[0]) if action.choices else "1,1" if action.option_strings else "7"
        if not action.option_strings and action.nargs not in ("?", "*"):
            words.append(value)
        elif action.option_strings and action.required:
            words += [action.option_strings[0], value]
    return words


def test_an_unknown_option_points_at_its_commands_help(capsys):
    found = list(commands_of(build_parser()))
    assert {prog.split()[1] for _, prog in found} == set(COMMANDS)
    assert len(found) > len(COMMANDS)  # (exercise's own commands are there)
    for words, prog in found:
        with pytest.raises(SystemExit) as stopped:
            build_parser(words[0]).parse_args([*words, "--no-such-option"])
        assert stopped.value.code == 2
        err = capsys.readouterr().err
        assert err == f"{prog}: error: unrecognized arguments: --no-such-option (see {prog} --help)\n", words
