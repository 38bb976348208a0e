"""A scene built in Python (``ptlab.load_dict``): the scene file's tables as a dict give the
file's scene, to the bit; a notebook's values (arrays, tuples, paths, meshes as arrays or a
trimesh, ptlab materials) are taken; a bad dict is one line naming the key. And what the
reader does with a mesh file's own materials and an image albedo, in files and dicts alike."""

from __future__ import annotations

import copy
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.ndimage import binary_erosion

import ptlab
from ptlab.errors import SceneError
from ptlab.materials import Diffuse
from ptlab.scene_file import builtin_scene_names, builtin_scenes_dir, load_dict, load_scene
from ptlab.textures import Checkerboard

ROOT = Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell-box"


def cornell_data() -> dict:
    return tomllib.loads((CORNELL / "scene.toml").read_text())


def assert_same_scene(a: ptlab.Scene, b: ptlab.Scene) -> None:
    """Everything a render reads of a scene is equal, to the bit."""
    for name in ("triangles", "material_ids", "uvs", "normals"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)
    assert a.material_names == b.material_names
    assert [repr(m) for m in a.materials] == [repr(m) for m in b.materials]
    for m, n in zip(a.materials, b.materials, strict=True):
        np.testing.assert_array_equal(
            m.emission if m.emission is not None else [], n.emission if n.emission is not None else []
        )
    for name in ("position", "forward", "up"):
        np.testing.assert_array_equal(getattr(a.camera, name), getattr(b.camera, name))
    assert a.camera.fov_y == b.camera.fov_y
    assert repr(a.point_lights) == repr(b.point_lights)
    assert repr(a.sky) == repr(b.sky)
    assert a.defaults == b.defaults
    assert a.name == b.name


# --- the same scene as its file ---------------------------------------------------------------


@pytest.mark.parametrize("name", builtin_scene_names())
def test_a_built_in_scenes_tables_as_a_dict_give_its_scene_and_its_image(name):
    folder = builtin_scenes_dir() / name
    data = tomllib.loads((folder / "scene.toml").read_text())
    from_file, from_dict = load_scene(name), load_dict(data, folder, name=name)
    assert_same_scene(from_file, from_dict)
    options = dict(spp=2, res=(12, 9), seed=5, workers=1, max_depth=3)
    np.testing.assert_array_equal(ptlab.render(from_dict, **options), ptlab.render(from_file, **options))


def test_a_notebooks_values_are_the_files_values():
    data = cornell_data()
    notebook = copy.deepcopy(data)
    notebook["camera"]["position"] = np.array(data["camera"]["position"], dtype=np.float32).astype(float)
    notebook["camera"]["direction"] = tuple(data["camera"]["direction"])
    notebook["camera"]["fov"] = np.int64(40)
    notebook["materials"]["red"]["albedo"] = np.array(data["materials"]["red"]["albedo"])
    notebook["materials"]["light"]["albedo"] = np.float64(0.65)
    notebook["mesh"] = tuple({**mesh, "file": Path(mesh["file"])} for mesh in data["mesh"])
    assert_same_scene(load_dict(notebook, CORNELL), load_dict(data, CORNELL))


def test_the_dict_is_left_as_it_was():
    data = cornell_data()
    data["mesh"].append(
        {"vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]], "material": "white"}
    )
    kept = copy.deepcopy(data)
    load_dict(data, CORNELL)
    assert data == kept


def test_ptlab_exports_load_dict():
    assert ptlab.load_dict is load_dict
    assert "load_dict" in dir(ptlab)


# --- meshes and materials a notebook gives ------------------------------------------------------

CUBE_VERTICES = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
#: The cube's 12 triangles, wound counter-clockwise seen from outside.
CUBE_FACES = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]
)  # fmt: skip


def cube_scene(mesh: dict) -> dict:
    """A grey cube under a white sky, seen face on from +z, with ``mesh``'s keys."""
    return {
        "camera": {"position": [0, 0, 6], "look_at": [0, 0, 0], "fov": 40},
        "materials": {"grey": {"type": "diffuse", "albedo": 0.5}},
        "sky": {"radiance": 1.0},
        "mesh": [{"material": "grey", **mesh}],
    }


def test_a_cube_given_as_arrays_renders():
    scene = load_dict(cube_scene({"vertices": CUBE_VERTICES, "faces": CUBE_FACES}))
    assert scene.triangle_count == 12
    winding = np.cross(
        scene.triangles[:, 1] - scene.triangles[:, 0], scene.triangles[:, 2] - scene.triangles[:, 0]
    )
    assert (np.einsum("ij,ij->i", winding, scene.triangles.mean(axis=1)) > 0).all()  # (outward)
    image = ptlab.render(scene, spp=16, res=16, seed=0, workers=1)
    # The face toward the camera sees the sky's whole hemisphere and nothing else: its
    # radiance is the albedo times the sky's, 0.5 (measured over seeds: a pixel's standard
    # deviation 0.04, the 16 pixels' mean's 0.01; the bounds are 4 and 5 of those); the sky
    # all around it.
    face = image[6:10, 6:10]
    assert abs(face.mean() - 0.5) < 0.04
    assert np.abs(face - 0.5).max() < 0.2
    np.testing.assert_allclose(image[0, 0], 1.0, rtol=1e-6)


def test_nested_lists_and_arrays_give_the_same_mesh():
    lists = load_dict(cube_scene({"vertices": CUBE_VERTICES.tolist(), "faces": CUBE_FACES.tolist()}))
    arrays = load_dict(
        cube_scene({"vertices": CUBE_VERTICES.astype(np.float32), "faces": CUBE_FACES.astype(np.int32)})
    )
    assert_same_scene(lists, arrays)


def test_a_trimesh_is_a_mesh_flat_unless_given_normals():
    box = trimesh.creation.box(extents=(2, 2, 2))
    box.vertex_normals  # noqa: B018 (asked for: trimesh now holds normals it made up, which ptlab leaves)
    scene = load_dict(cube_scene({"trimesh": box}))
    np.testing.assert_array_equal(scene.triangles, box.vertices[box.faces])
    assert scene.normals is None
    sphere = trimesh.creation.icosphere(subdivisions=2)
    smooth = load_dict(cube_scene({"trimesh": sphere, "normals": sphere.vertices}))
    np.testing.assert_allclose(smooth.normals, sphere.vertices[sphere.faces], atol=1e-12)


def test_a_zero_normal_is_its_faces_as_in_a_file():
    # trimesh gives a vertex no face uses a zero normal; a file's zero normal is its face's:
    # a dict's is too, so trimesh's normals load (an unused vertex is harmless) and a face
    # whose normals are all zero is flat.
    import trimesh

    box = trimesh.creation.box()
    unused = np.vstack([box.vertices, [[5.0, 5.0, 5.0]]])
    normals = np.vstack([box.vertices / np.linalg.norm(box.vertices, axis=1, keepdims=True), [[0, 0, 0]]])
    smooth = load_dict(cube_scene({"vertices": unused, "faces": box.faces, "normals": normals}))
    assert np.isfinite(smooth.normals).all()
    flat = load_dict(
        cube_scene({"vertices": CUBE_VERTICES, "faces": CUBE_FACES, "normals": CUBE_VERTICES * 0})
    )
    faces = np.repeat(flat.face_normals[:, None, :], 3, axis=1)
    np.testing.assert_allclose(flat.normals, faces, atol=1e-6)


def test_ptlab_materials_stand_for_tables_and_names():
    data = cube_scene({"vertices": CUBE_VERTICES, "faces": CUBE_FACES})
    shared = Diffuse(albedo=(0.2, 0.4, 0.6))
    board = Checkerboard([[1, 1, 1], [0, 0, 0]], scale=2)
    data["materials"]["grey"] = Diffuse(albedo=0.5)
    data["materials"]["board"] = {"type": "diffuse", "albedo": board}
    data["mesh"] = [
        {"vertices": CUBE_VERTICES, "faces": CUBE_FACES[:6], "material": shared},
        {"vertices": CUBE_VERTICES, "faces": CUBE_FACES[6:], "material": shared},
        {"vertices": CUBE_VERTICES + 3, "faces": CUBE_FACES, "material": data["materials"]["grey"]},
    ]
    scene = load_dict(data)
    assert scene.materials[0] is data["materials"]["grey"]
    assert scene.materials[1].albedo is board
    assert scene.materials[2] is shared
    assert scene.material_names[2] == "mesh[0].material"
    assert len(scene.materials) == 3  # (the shared one once, the named one under its name)
    np.testing.assert_array_equal(scene.material_ids, [2] * 12 + [0] * 12)


# --- one line for a bad dict ---------------------------------------------------------------------

#: name: (what replaces the cube's mesh keys, the key, a fragment of the problem)
BAD_MESHES = {
    "vertices of two coordinates": ({"vertices": CUBE_VERTICES[:, :2]}, "mesh[0].vertices", "(N, 3) array"),
    "ragged vertices": ({"vertices": [[0, 0, 0], [1, 0]]}, "mesh[0].vertices", "(N, 3) array of numbers"),
    "vertices as text": ({"vertices": [["a", "b", "c"]] * 8}, "mesh[0].vertices", "array of numbers"),
    "NaN vertex": ({"vertices": np.where(CUBE_VERTICES == 1, math.nan, 0)}, "mesh[0].vertices", "finite"),
    "vertex beyond float32": ({"vertices": CUBE_VERTICES * 1e11}, "mesh[0].vertices", "within +-1e+10"),
    "no faces": ({"faces": None}, "mesh[0].faces", "missing"),
    "faces of floats": ({"faces": CUBE_FACES + 0.5}, "mesh[0].faces", "(N, 3) array of integers"),
    "faces of quads": ({"faces": np.zeros((2, 4), int)}, "mesh[0].faces", "(N, 3)"),
    "face beyond the vertices": ({"faces": CUBE_FACES + 1}, "mesh[0].faces", "refers to vertex 8"),
    "no faces at all": ({"faces": np.zeros((0, 3), int)}, "mesh[0].faces", "empty"),
    "flat faces": ({"faces": [[0, 0, 1]]}, "mesh[0].faces", "zero area"),
    "normals too few": ({"normals": CUBE_VERTICES[:3]}, "mesh[0].normals", "3 rows for 8 vertices"),
    "uv of three numbers": ({"uv": CUBE_VERTICES}, "mesh[0].uv", "(N, 2)"),
    "faces beside a file": ({"vertices": None, "file": "x.obj"}, "mesh[0].faces", "goes with vertices"),
    "unknown material": ({"material": "gray"}, "mesh[0].material", "no material named 'gray'"),
    "material a number": ({"material": 3}, "mesh[0].material", "must be the name"),
    "no material": ({"material": None}, "mesh[0].material", "missing"),
    "a trimesh that is not": (
        {"vertices": None, "faces": None, "trimesh": [1]},
        "mesh[0].trimesh",
        "trimesh.Trimesh",
    ),
    "faces beside a trimesh": (
        {"vertices": None, "trimesh": trimesh.creation.box()},
        "mesh[0].faces",
        "goes with vertices, not trimesh",
    ),
    "a material with negative emission": (
        {"material": Diffuse(emission=[1, -1, 1])},
        "mesh[0].material.emission",
        "from 0 to",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_MESHES))
def test_a_bad_mesh_in_a_dict_is_one_line_naming_its_key(case):
    changes, key, problem = BAD_MESHES[case]
    mesh = {"vertices": CUBE_VERTICES, "faces": CUBE_FACES, "material": "grey"}
    mesh.update(changes)
    data = cube_scene({})
    data["mesh"] = [{name: value for name, value in mesh.items() if value is not None}]
    with pytest.raises(SceneError) as error:
        load_dict(data)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"scene dict: {key}: "), message
    assert problem in message, message


def test_bad_dicts_are_one_line_too():
    with pytest.raises(
        SceneError, match=r"^scene dict: must be a dict of the scene file's tables, got \[1\]$"
    ):
        load_dict([1])  # type: ignore[arg-type]
    with pytest.raises(SceneError, match=r"^scene dict: mesh: must be an array of tables"):
        load_dict({**cube_scene({}), "mesh": {"file": "x.obj"}})
    with pytest.raises(SceneError, match=r"^scene dict: materials: a material's name must be text, got 1$"):
        load_dict({**cube_scene({}), "materials": {1: {"type": "diffuse"}}})
    with pytest.raises(SceneError, match=r"^scene dict: materials\.grey\.emission: must be 3 numbers"):
        load_dict(
            {
                **cube_scene({"vertices": CUBE_VERTICES, "faces": CUBE_FACES}),
                "materials": {"grey": Diffuse(emission=math.inf)},
            }
        )
    with pytest.raises(SceneError, match=r"^scene dict: folder must be a path, got 5$"):
        load_dict(cube_scene({}), folder=5)  # type: ignore[arg-type]
    bright = cube_scene({"vertices": CUBE_VERTICES, "faces": CUBE_FACES})
    bright["materials"]["grey"] = {"type": "diffuse", "albedo": Checkerboard([[5, 5, 5], [0, 0, 0]])}
    with pytest.raises(SceneError, match=r"albedo\.colours\[0\]\.colour: must be at most 1"):
        load_dict(bright)
    looped = cube_scene({})
    looped["sky"]["radiance"] = looped
    with pytest.raises(SceneError, match=r"^scene dict: nested too deeply"):
        load_dict(looped)
    with pytest.raises(
        SceneError, match=r"^scene dict: mesh\[0\]\.file: mesh file not found: .*nowhere\.obj$"
    ):
        load_dict(cube_scene({"file": "nowhere.obj"}), folder=CORNELL)


# --- an image albedo, and a mesh file's own materials ---------------------------------------------

QUAD_SCENE = """
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
fov = 30

[materials.lamp]
type = "diffuse"
emission = 1

[[mesh]]
quad = { corners = [[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]] }
material = "surface"

[[mesh]]
quad = { corners = [[-5, -5, 6], [-5, 5, 6], [5, 5, 6], [5, -5, 6]] }
material = "lamp"
"""


def write_uniform_image(path: Path, value: float) -> None:
    from ptlab.image import write_image

    path.parent.mkdir(parents=True, exist_ok=True)
    write_image(path, np.full((4, 4, 3), value, dtype=np.float32))


def test_an_image_albedo_is_read_relative_to_the_scene_and_shades_as_its_colour(tmp_path):
    # A float image of 0.5 everywhere is the albedo 0.5 (linear: no sRGB decoding).
    write_uniform_image(tmp_path / "textures" / "grey.exr", 0.5)
    (tmp_path / "scene.toml").write_text(
        QUAD_SCENE + '\n[materials.surface]\ntype = "diffuse"\nalbedo = { image = "textures/grey.exr" }\n'
    )
    textured = load_scene(tmp_path / "scene.toml")
    assert type(textured.materials[1].albedo).__name__ == "ImageTexture"
    data = tomllib.loads(QUAD_SCENE)
    data["materials"]["surface"] = {"type": "diffuse", "albedo": 0.5}
    plain = load_dict(data)
    options = dict(spp=4, res=8, seed=1, workers=1)
    np.testing.assert_allclose(ptlab.render(textured, **options), ptlab.render(plain, **options), rtol=1e-6)
    # A dict names it relative to its folder.
    from_dict = load_dict(tomllib.loads((tmp_path / "scene.toml").read_text()), tmp_path, name=tmp_path.name)
    assert_same_scene(from_dict, textured)


@pytest.mark.parametrize(
    ("albedo", "key", "problem"),
    [
        ({"image": "nowhere.png"}, "materials.surface.albedo.image", "nowhere.png: not found"),
        ({"image": 3}, "materials.surface.albedo.image", "must be the image's file name"),
        ({"imgae": "wood.png"}, "materials.surface.albedo", "{ image = FILE }"),
        ({"image": "wood.png", "scale": 2}, "materials.surface.albedo.scale", "unknown key"),
    ],
)
def test_a_bad_image_albedo_is_one_line_naming_its_key(tmp_path, albedo, key, problem):
    data = tomllib.loads(QUAD_SCENE)
    data["materials"]["surface"] = {"type": "diffuse", "albedo": albedo}
    with pytest.raises(SceneError) as error:
        load_dict(data, tmp_path)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"scene dict: {key}: "), message
    assert problem in message, message


#: A box's OBJ with an .mtl: one face without a material, two red ones, two of wood (an image).
BOX_OBJ = """mtllib box.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1 2/2 3/3
usemtl red
f 1/1 3/3 4/4
f 1/1 2/2 4/4
usemtl wood
f 2/2 3/3 4/4
f 1/1 2/2 3/3
"""
BOX_MTL = """newmtl red
Kd 0.8 0.1 0.1
Ks 0.5 0.5 0.5

newmtl wood
Kd 0.5 0.5 0.5
map_Kd wood.exr
"""


def box_scene(tmp_path: Path, material: str | None) -> dict:
    (tmp_path / "box.obj").write_text(BOX_OBJ)
    (tmp_path / "box.mtl").write_text(BOX_MTL)
    write_uniform_image(tmp_path / "wood.exr", 1.0)
    data = tomllib.loads(QUAD_SCENE)
    data["materials"]["surface"] = {"type": "diffuse", "albedo": 0.3}
    data["mesh"][0] = {"file": "box.obj", "translate": [-0.5, -0.5, 0]}
    if material is not None:
        data["mesh"][0]["material"] = material
    return data


def test_a_mesh_without_a_material_takes_its_files_materials(tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_dict(box_scene(tmp_path, None), tmp_path)
    names = scene.material_names
    assert names[2:] == ["mesh[0].file: no material", "mesh[0].file: red", "mesh[0].file: wood"]
    np.testing.assert_array_equal(scene.material_ids[:5], [2, 3, 3, 4, 4])
    np.testing.assert_allclose(scene.materials[2].albedo, [0.8] * 3)
    np.testing.assert_allclose(scene.materials[3].albedo, [0.8, 0.1, 0.1])
    # The image (1 everywhere) times the material's colour, as the MTL format defines map_Kd.
    np.testing.assert_allclose(scene.materials[4].albedo(np.array([[0.3, 0.6]])), [[0.5] * 3], rtol=1e-6)
    # One warning, naming the file and what ptlab leaves out of it.
    messages = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert len(messages) == 1, messages
    assert messages[0].startswith("scene dict: mesh[0].file: mesh box.obj: ptlab ignores "), messages[0]
    assert "Ks" in messages[0]
    assert np.isfinite(ptlab.render(scene, spp=1, res=8, workers=1)).all()


def test_a_meshs_material_replaces_its_files_and_says_so(tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_dict(box_scene(tmp_path, "surface"), tmp_path)
    assert scene.material_names == ["lamp", "surface"]
    assert (scene.material_ids[:5] == 1).all()
    (message,) = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert "mesh box.obj" in message
    assert "its materials (the scene's `surface` is used)" in message


def test_a_file_without_materials_is_grey_and_says_nothing(tmp_path):
    (tmp_path / "plain.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    data = tomllib.loads(QUAD_SCENE)
    data["mesh"][0] = {"file": "plain.obj"}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = load_dict(data, tmp_path)
    assert scene.material_names[-1] == "mesh[0].file: no material"
    np.testing.assert_allclose(scene.materials[-1].albedo, [0.8] * 3)


def test_a_file_material_too_bright_is_one_line_naming_it(tmp_path):
    data = box_scene(tmp_path, None)
    (tmp_path / "box.mtl").write_text(BOX_MTL.replace("Kd 0.8 0.1 0.1", "Kd 1.2 0.1 0.1"))
    with pytest.raises(SceneError, match=r"^scene dict: mesh\[0\]\.file: material 'red'.*from 0 to 1"):
        load_dict(data, tmp_path)


# --- the end: a model with normals, a texture and a transform -------------------------------


def write_ball(folder: Path) -> Path:
    """A UV sphere's OBJ with vertex normals (`vn`) and texture coordinates (`vt`), its MTL
    naming an image (red where v > 1/2, the northern half; blue in the south), and a scene
    file that turns the ball's north pole toward the camera and moves it; the scene's path."""
    from ptlab.image import write_image

    rings, segments = 16, 32
    theta = np.linspace(0, np.pi, rings + 1)  # (from the north pole, +y)
    phi = np.linspace(0, 2 * np.pi, segments + 1)  # (the seam's vertices twice, for uv)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    points = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    uv = np.stack([p / (2 * np.pi), 1 - t / np.pi], axis=-1).reshape(-1, 2)
    lines = ["mtllib ball.mtl", "usemtl ball"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in points.tolist()]
    lines += [f"vt {u!r} {v!r}" for u, v in uv.tolist()]
    lines += [f"vn {x!r} {y!r} {z!r}" for x, y, z in points.tolist()]
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j + 1, (i + 1) * (segments + 1) + j + 1
            for face in ((a, b, b + 1), (a, b + 1, a + 1)):
                lines.append("f " + " ".join(f"{k}/{k}/{k}" for k in face))
    (folder / "ball.obj").write_text("\n".join(lines) + "\n")
    (folder / "ball.mtl").write_text("newmtl ball\nKd 1 1 1\nmap_Kd ball.png\n")
    texture = np.zeros((16, 16, 3), dtype=np.float32)
    texture[:8] = [0.6, 0.05, 0.05]  # (row 0 is the image's top: v = 1)
    texture[8:] = [0.05, 0.05, 0.6]
    write_image(folder / "ball.png", texture)
    (folder / "scene.toml").write_text(
        "[camera]\nposition = [0, 0, 4]\nlook_at = [0, 0, 0]\nfov = 30\n\n[sky]\nradiance = 1\n\n"
        '[[mesh]]\nfile = "ball.obj"\nscale = 0.9\nrotate = { axis = [1, 0, 0], angle = 90 }\n'
        "translate = [0, 0, -0.5]\n"
    )
    return folder / "scene.toml"


def model_alone(path: Path) -> dict:
    """The tables of the scene file ``path`` with only its meshes from files."""
    data = tomllib.loads(path.read_text())
    data["mesh"] = [mesh for mesh in data["mesh"] if "file" in mesh]
    return data


@pytest.mark.parametrize("model", ["generated ball", "spot"])
def test_a_model_with_normals_a_texture_and_a_transform_renders_smooth_and_textured(model, tmp_path):
    path = write_ball(tmp_path) if model == "generated ball" else builtin_scenes_dir() / "spot" / "scene.toml"
    assert any(key in mesh for mesh in model_alone(path)["mesh"] for key in ("rotate", "translate", "scale"))
    scene = load_scene(path)
    assert scene.normals is not None
    # Smooth: the view of the model's shading normals bends less from pixel to pixel (second
    # differences) than that of its triangles shaded flat, made from them as arrays, whose
    # normals jump at every edge (measured: 0.35 as much for spot at this size, 0.15 for the
    # ball; flat-shaded triangles smaller than a pixel would blur into smooth ones).
    alone = load_dict(model_alone(path), path.parent)
    flat = {
        **model_alone(path),
        "materials": {"grey": {"type": "diffuse"}},
        "mesh": [
            {
                "vertices": alone.triangles.reshape(-1, 3),
                "faces": np.arange(3 * alone.triangle_count).reshape(-1, 3),
                "material": "grey",
            }
        ],
    }
    views = [
        ptlab.render(s, integrator="normals", spp=4, res=128, seed=0, workers=1)
        for s in (alone, load_dict(flat, path.parent))
    ]
    # (Runs of three pixels on the model, two pixels in from its outline: no background.)
    inside = binary_erosion((views[0] > 0).any(axis=2), iterations=2)
    runs = inside[:, 2:] & inside[:, 1:-1] & inside[:, :-2]
    bends = [np.abs(np.diff(view, n=2, axis=1))[runs].mean() for view in views]
    assert bends[0] < 0.6 * bends[1], bends
    # Textured (a diffuse surface's albedo view is exact in every sample: without the
    # texture, the model would be one 0.8 grey) and, for the ball, placed by its transform.
    # (Spot's spread measured 0.73 to 0.93 by channel.)
    albedo = ptlab.render(alone, integrator="albedo", spp=4, res=48, seed=0, workers=1)
    if model == "generated ball":
        # The north (red) half faces the camera, the south (blue) one away.
        red, _, blue = albedo[20:28, 20:28].mean(axis=(0, 1))
        assert red > 5 * blue, (red, blue)
    else:
        # Spot's white hide and black patches.
        on_model = albedo[binary_erosion((albedo > 0).any(axis=2), iterations=1)]
        spread = np.percentile(on_model, 95, axis=0) - np.percentile(on_model, 5, axis=0)
        assert spread.min() > 0.3, spread
    # Both backends, the same image: the same random numbers drive both, and only float
    # rounding in the hit points differs, which moves a few samples at the outlines.
    options = dict(spp=4, res=48, seed=2, workers=1)
    embree = ptlab.render(scene, backend="embree", **options)
    numpy_bvh = ptlab.render(scene, backend="numpy", **options)
    close = np.isclose(embree, numpy_bvh, rtol=1e-3, atol=1e-4).all(axis=2)
    assert close.mean() > 0.99, close.mean()
    np.testing.assert_allclose(embree.mean(), numpy_bvh.mean(), rtol=1e-3)
    # ... and the scene built in Python from the file's tables: the same image, to the bit.
    from_dict = load_dict(tomllib.loads(path.read_text()), path.parent, name=scene.name)
    np.testing.assert_array_equal(ptlab.render(from_dict, backend="embree", **options), embree)
