"""Transforms on meshes (ptlab.transforms, and the `scale`, `rotate`, `translate` and `matrix`
keys of a scene's [[mesh]]): where the corners go, what becomes of normals, uv and the front
face, and one clear line for every bad transform."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import ptlab
from ptlab.errors import SceneError
from ptlab.lights import triangle_normals
from ptlab.scene_file import load_dict
from ptlab.transforms import Transform, rotation

ROOT = Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell-box"

# --- the transform itself ---------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(5))
def test_a_rotation_is_scipys_rotation_by_the_same_axis_and_angle(seed):
    # SciPy's from_rotvec is an independent statement of the right-handed rotation.
    rng = np.random.default_rng(seed)
    axis, degrees = rng.normal(size=3) * 10.0 ** rng.uniform(-3, 3), rng.uniform(-360, 360)
    expected = Rotation.from_rotvec(axis / np.linalg.norm(axis) * math.radians(degrees)).as_matrix()
    np.testing.assert_allclose(rotation(axis, degrees), expected, atol=1e-12)


def test_a_quarter_turn_about_z_takes_x_to_y():
    # Counter-clockwise seen from the axis' tip, as pbrt's and Mitsuba's `rotate`.
    np.testing.assert_allclose(rotation([0, 0, 1], 90) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    # A tiny or huge axis is only a direction.
    np.testing.assert_allclose(rotation([0, 0, 1e-300], 90), rotation([0, 0, 1e300], 90))


def test_scale_then_rotations_in_turn_then_translate():
    turn_z, turn_x = rotation([0, 0, 1], 90), rotation([1, 0, 0], 90)
    transform = Transform.compose(np.array([2.0, 1, 1]), [turn_z, turn_x], np.array([0.0, 0, 5]))
    # (1, 0, 0): scaled (2, 0, 0), about z (0, 2, 0), about x (0, 0, 2), moved (0, 0, 7).
    np.testing.assert_allclose(transform.points(np.array([1.0, 0, 0])), [0, 0, 7], atol=1e-12)
    # Any other order puts it elsewhere.
    other = Transform.compose(np.array([2.0, 1, 1]), [turn_x, turn_z], np.array([0.0, 0, 5]))
    assert np.abs(other.points(np.array([1.0, 0, 0])) - [0, 0, 7]).max() > 1


def test_normals_stay_perpendicular_to_the_transformed_surface():
    rng = np.random.default_rng(1)
    triangles = rng.normal(size=(50, 3, 3))
    normals = np.repeat(triangle_normals(triangles)[:, None], 3, axis=1)
    transform = Transform.compose(np.array([3.0, 0.2, 1.5]), [rotation([1, 2, 3], 40)], np.array([1.0, 2, 3]))
    moved, _, turned = transform.mesh(triangles, None, normals)
    np.testing.assert_allclose(np.linalg.norm(turned, axis=2), 1, rtol=1e-12)
    for edge in (moved[:, 1] - moved[:, 0], moved[:, 2] - moved[:, 0]):
        assert np.abs(np.einsum("ij,ij->i", turned[:, 0], edge)).max() < 1e-9
    # ... and on the same side as the winding's normal (no mirror here).
    np.testing.assert_allclose(turned[:, 0], triangle_normals(moved), atol=1e-9)


@pytest.mark.parametrize("scale", [[-1, 1, 1], [1, 1, -2], [-1, -1, -1]], ids=str)
def test_a_mirror_keeps_a_closed_meshs_front_faces_outside(scale):
    sphere = trimesh.creation.icosphere(subdivisions=1)
    triangles = sphere.vertices[sphere.faces] + [3.0, 0, 0]
    uv = triangles[:, :, :2].copy()  # (a uv that says where each corner came from)
    normals = np.repeat(triangle_normals(triangles)[:, None], 3, axis=1)
    transform = Transform.compose(np.array(scale, dtype=float), [], np.zeros(3))
    assert transform.swaps_handedness
    moved, moved_uv, turned = transform.mesh(triangles, uv, normals)
    centre = transform.points(np.array([3.0, 0, 0]))
    outward = np.einsum("ij,ij->i", triangle_normals(moved), moved.mean(axis=1) - centre)
    assert (outward > 0).all()
    np.testing.assert_allclose(turned[:, 0], triangle_normals(moved), atol=1e-12)
    # Each corner keeps its own uv through the swap: the uv was its x and y before.
    np.testing.assert_allclose(moved_uv, moved[..., :2] / np.array(scale[:2], dtype=float), atol=1e-12)


# --- the keys of a [[mesh]] ---------------------------------------------------------------------

TETRAHEDRON = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
SCENE = """
[camera]
position = [0, 0, 10]
look_at = [0, 0, 0]

[materials.white]
type = "diffuse"

[materials.lamp]
type = "diffuse"
emission = 1

[[mesh]]
file = "tetrahedron.obj"
material = "white"
{transform}

[[mesh]]
quad = {{ corners = [[-1, -1, 5], [1, -1, 5], [1, 1, 5], [-1, 1, 5]] }}
material = "lamp"
"""


def scene_with(folder: Path, transform: str) -> ptlab.Scene:
    (folder / "tetrahedron.obj").write_text(TETRAHEDRON)
    path = folder / "scene.toml"
    path.write_text(SCENE.format(transform=transform))
    return ptlab.load_scene(path)


def test_translate_rotate_and_scale_place_a_mesh_file(tmp_path):
    plain = scene_with(tmp_path, "").triangles[:4]
    placed = scene_with(
        tmp_path,
        "scale = [2, 1, 1]\n"
        "rotate = [{ axis = [0, 0, 1], angle = 90 }, { axis = [1, 0, 0], angle = 30 }]\n"
        "translate = [1, 2, 3]",
    ).triangles[:4]
    turn = Rotation.from_rotvec([math.radians(30), 0, 0]) * Rotation.from_rotvec([0, 0, math.pi / 2])
    expected = turn.apply((plain * [2, 1, 1]).reshape(-1, 3)).reshape(-1, 3, 3) + np.array([1, 2, 3])
    np.testing.assert_allclose(placed, expected, atol=1e-12)
    # The same transform as one matrix (row-major; the last row 0 0 0 1).
    matrix = np.eye(4)
    matrix[:3, :3] = turn.as_matrix() @ np.diag([2, 1, 1])
    matrix[:3, 3] = [1, 2, 3]
    rows = ", ".join(f"[{', '.join(map(repr, row))}]" for row in matrix.tolist())
    np.testing.assert_allclose(scene_with(tmp_path, f"matrix = [{rows}]").triangles[:4], expected, atol=1e-12)


def test_one_rotation_needs_no_list(tmp_path):
    one = scene_with(tmp_path, "rotate = { axis = [0, 1, 0], angle = 45 }").triangles
    listed = scene_with(tmp_path, "rotate = [{ axis = [0, 1, 0], angle = 45 }]").triangles
    np.testing.assert_array_equal(one, listed)


def test_a_scale_alone_multiplies_the_coordinates_exactly_as_before(tmp_path):
    # games101-hw6's bunny is `scale = 60`: its triangles are 60 times the file's, to the bit.
    plain = scene_with(tmp_path, "").triangles[:4]
    np.testing.assert_array_equal(scene_with(tmp_path, "scale = 60").triangles[:4], plain * 60)
    np.testing.assert_array_equal(scene_with(tmp_path, "scale = [60, 60, 60]").triangles[:4], plain * 60)


def cornell_data(**mesh_keys) -> dict:
    """The Cornell box's tables, with ``mesh_keys`` added to every mesh."""
    data = tomllib.loads((CORNELL / "scene.toml").read_text())
    for mesh in data["mesh"]:
        mesh.update(mesh_keys)
    return data


def test_spheres_and_quads_are_transformed_too():
    data = cornell_data()
    data["materials"]["light"]["albedo"] = {
        "checkerboard": [0.5, 0.1]
    }  # (a textured light: the scene keeps uv)
    data["mesh"] = [
        {
            "sphere": {"center": [0, 0, 0], "radius": 1, "subdivisions": 2},
            "material": "white",
            "scale": [1, 3, 1],
        },
        {
            "quad": {
                "corners": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
                "uv": [[0, 0], [1, 0], [1, 1], [0, 1]],
            },
            "material": "light",
            "rotate": {"axis": [1, 0, 0], "angle": 90},
            "translate": [0, 5, 0],
        },
    ]
    scene = load_dict(data)
    ellipsoid, quad = scene.triangles[:-2], scene.triangles[-2:]
    np.testing.assert_allclose(np.ptp(ellipsoid.reshape(-1, 3), axis=0), [2, 6, 2], rtol=1e-9)
    # The unit square in z = 0 turned about x lies in y = 5, z from 0 to 1, facing -y.
    np.testing.assert_allclose(quad[..., 1], 5)
    np.testing.assert_allclose(triangle_normals(quad), [[0, -1, 0]] * 2, atol=1e-12)
    # Each corner keeps its uv (here its original x and y): u is x, v is the new z.
    np.testing.assert_allclose(scene.uvs[-2:], quad[..., [0, 2]], atol=1e-12)


def test_a_mirrored_cornell_box_renders_the_mirror_image():
    # Mirrored in x with its camera, the box shows the red wall on the other side, and its
    # light still shines down into it: the light's front face stayed on its side.
    original = tomllib.loads((CORNELL / "scene.toml").read_text())
    mirrored = cornell_data(scale=[-1, 1, 1])
    mirrored["camera"]["position"][0] *= -1
    scene = load_dict(mirrored, CORNELL)
    np.testing.assert_allclose(scene.area_lights.normals, [[0, -1, 0]] * 2, atol=1e-7)
    options = dict(spp=16, res=24, seed=3, workers=1)
    image = ptlab.render(load_dict(original, CORNELL), **options)
    flipped = ptlab.render(scene, **options)[:, ::-1]
    # 6 x 6-pixel blocks of 576 samples each: noise of a few per cent; a light facing the
    # ceiling would make the mirrored box several times darker, a wall unmirrored swaps red.
    blocks = [im.reshape(4, 6, 4, 6, 3).mean(axis=(1, 3)) for im in (image, flipped)]
    np.testing.assert_allclose(blocks[1], blocks[0], rtol=0.2, atol=0.02)


def test_a_meshs_own_normals_follow_its_transform():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    normals = vertices - 0.25
    data = cornell_data()
    data["mesh"].append({"vertices": vertices, "faces": faces, "normals": normals, "material": "white"})
    linear = rotation([1, 1, 0], 50) @ np.diag([1, -3, 1])  # (a mirror)
    data["mesh"][-1]["matrix"] = np.vstack([np.column_stack([linear, [278, 100, 278]]), [0, 0, 0, 1]])
    scene = load_dict(data, CORNELL)
    given = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    expected = given @ np.linalg.inv(linear)
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    placed, turned = scene.triangles[-4:], scene.normals[-4:]
    # Corner by corner: wherever the mirror moved a corner, its normal came with it.
    for corners, corner_normals in zip(placed, turned, strict=True):
        for point, normal in zip(corners, corner_normals, strict=True):
            vertex = np.flatnonzero(np.abs(vertices @ linear.T + [278, 100, 278] - point).max(axis=1) < 1e-9)
            np.testing.assert_allclose(normal, expected[vertex[0]], atol=1e-12)
    # The winding's normal is on the side of the normals given (outside).
    assert (np.einsum("ij,ij->i", triangle_normals(placed), turned.mean(axis=1)) > 0).all()


BAD_TRANSFORMS = {
    "singular matrix": (
        {"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]},
        "mesh[0].matrix",
        "singular",
    ),
    "projective matrix": (
        {"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]},
        "mesh[0].matrix",
        "last row must be [0, 0, 0, 1]",
    ),
    "matrix of three rows": ({"matrix": np.eye(4)[:3]}, "mesh[0].matrix", "4 rows of 4 numbers"),
    "matrix with NaN": ({"matrix": np.diag([1, 1, math.nan, 1])}, "mesh[0].matrix", "finite"),
    "matrix and a translation": (
        {"matrix": np.eye(4), "translate": [1, 0, 0]},
        "mesh[0].translate",
        "either a `matrix`",
    ),
    "zero scale": ({"scale": [1, 0, 1]}, "mesh[0].scale", "must not be 0"),
    "scale of two numbers": ({"scale": [1, 2]}, "mesh[0].scale", "3 numbers"),
    "scale as text": ({"scale": "big"}, "mesh[0].scale", "a number or a list of 3"),
    "translation with NaN": ({"translate": [0, math.nan, 0]}, "mesh[0].translate", "finite"),
    "rotation without angle": ({"rotate": {"axis": [0, 1, 0]}}, "mesh[0].rotate.angle", "missing"),
    "rotation about nothing": (
        {"rotate": [{"axis": [0, 1, 0], "angle": 3}, {"axis": [0, 0, 0], "angle": 3}]},
        "mesh[0].rotate[1].axis",
        "must not be zero",
    ),
    "rotation as a number": ({"rotate": 90}, "mesh[0].rotate", "axis = [x, y, z], angle = DEGREES"),
    "rotation typo": ({"rotate": {"axis": [0, 1, 0], "angel": 3}}, "mesh[0].rotate.angel", "unknown key"),
    "scaled beyond float32": ({"scale": 1e300}, "mesh[0].file", "within +-1e+10"),
    "moved beyond float32": ({"translate": [2e10, 0, 0]}, "mesh[0].file", "within +-1e+10"),
}


@pytest.mark.parametrize("case", sorted(BAD_TRANSFORMS))
def test_a_bad_transform_is_one_line_naming_its_key(case):
    keys, key, problem = BAD_TRANSFORMS[case]
    data = cornell_data()
    data["mesh"][0].update(keys)
    with pytest.raises(SceneError) as error:
        load_dict(data, CORNELL)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"scene dict: {key}: "), message
    assert problem in message, message


def test_the_scenes_size_and_place_are_checked_after_its_transforms():
    with pytest.raises(SceneError, match=r"the scene is only 5.*e-07 wide"):
        load_dict(cornell_data(scale=1e-9), CORNELL)
    with pytest.raises(SceneError, match=r"mesh\[\d\]\.file: a vertex lies 1\.00\d+e\+06 from the origin"):
        load_dict(cornell_data(translate=[1e6, 0, 0]), CORNELL)


def test_a_bad_transform_in_a_file_names_the_file(tmp_path):
    with pytest.raises(SceneError, match=r"scene\.toml: mesh\[0\]\.matrix: is singular"):
        scene_with(tmp_path, "matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]")
