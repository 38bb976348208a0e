"""Textures (``ptlab.textures``): the checkerboard at known uvs, and uvs carried from a scene
file's quad or an OBJ file's ``vt`` lines through the renderer to the material."""

from __future__ import annotations

import numpy as np
import pytest

import ptlab
from ptlab.errors import SceneError
from ptlab.textures import Checkerboard

A, B = (0.8, 0.1, 0.0), (0.2, 0.6, 0.9)


def test_checkerboard_colours_at_known_uvs():
    board = Checkerboard([A, B], scale=5)  # Homework 5's: squares of side 0.1
    uv = np.array(
        [
            [0.05, 0.05],
            [0.15, 0.05],
            [0.05, 0.15],
            [0.15, 0.15],
            [0.55, 0.05],
            [0.95, 0.95],
            [0.999, 0.001],
            [1.05, 0.05],
            [-0.05, 0.05],
        ]
    )
    # pattern = (frac(5u) > 0.5) xor (frac(5v) > 0.5): B where it is 1.
    expected = [A, B, B, A, B, A, B, A, B]
    colours = board(uv)
    assert colours.shape == (len(uv), 3)
    assert colours.dtype == np.float32
    np.testing.assert_array_equal(colours, np.array(expected, dtype=np.float32))


TEXTURED = """
[camera]
position = [0, 0, 2]
look_at = [0, 0, 0]
fov = 90

[sky]
radiance = 1

[materials.board]
type = "diffuse"
albedo = {{ checkerboard = [[0.8, 0.1, 0.0], [0.2, 0.6, 0.9]], scale = 1 }}

[[mesh]]
{shape}
material = "board"
"""

#: The quad x, y in [-1, 1] at z = 0, facing the camera, with u from 0 to 2 along x and v from
#: 0 to 1 along y: four squares across, two up (a u-v swap would give two across, four up).
QUAD = (
    "quad = { corners = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], "
    "uv = [[0, 0], [2, 0], [2, 1], [0, 1]] }"
)
OBJ = """v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vt 0 0
vt 2 0
vt 2 1
vt 0 1
f 1/1 2/2 4/4
f 2/2 3/3 4/4
"""


def albedo_image(folder, shape: str) -> np.ndarray:
    path = folder / "scene.toml"
    path.write_text(TEXTURED.format(shape=shape))
    return ptlab.render(path, spp=4, res=64, integrator="albedo", workers=1)


def test_uvs_from_a_quad_and_from_obj_vt_lines_colour_the_right_squares(tmp_path):
    (tmp_path / "board.obj").write_text(OBJ)
    from_quad = albedo_image(tmp_path, QUAD)
    from_obj = albedo_image(tmp_path, 'file = "board.obj"')
    # At z = 0 the view spans [-2, 2]: pixel (16 (x + 2), 16 (2 - y)) looks at (x, y).
    for x in (-0.75, -0.25, 0.25, 0.75):
        for y in (-0.5, 0.5):
            u, v = x + 1, (y + 1) / 2
            expected = B if ((u % 1) > 0.5) ^ ((v % 1) > 0.5) else A
            pixel = from_quad[int(16 * (2 - y)), int(16 * (x + 2))]
            np.testing.assert_allclose(pixel, expected, atol=1e-6, err_msg=f"at x={x}, y={y}")
    np.testing.assert_allclose(from_obj, from_quad, atol=1e-6)
    # Outside the quad the camera rays escape: the albedo view shows nothing there.
    assert (from_quad[2, 2] == 0).all()


def test_a_textured_material_needs_texture_coordinates(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(TEXTURED.format(shape="sphere = { center = [0, 0, 0], radius = 1 }"))
    with pytest.raises(SceneError, match=r"mesh\[0\]\.sphere.*'board' is textured.*no texture"):
        ptlab.load_scene(path)
