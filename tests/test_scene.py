"""Scene files: the Cornell box as specified, and one clear error per malformed input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import ptlab
from ptlab.errors import SceneError

CORNELL = Path(__file__).resolve().parents[1] / "scenes" / "cornell-box"


def test_cornell_box_is_the_homework_scene(cornell):
    assert cornell.triangle_count == 32
    names = cornell.material_names
    albedo = {name: cornell.materials[names.index(name)].albedo for name in names}
    np.testing.assert_allclose(albedo["red"], [0.63, 0.065, 0.05])
    np.testing.assert_allclose(albedo["green"], [0.14, 0.45, 0.091])
    np.testing.assert_allclose(albedo["white"], [0.725, 0.71, 0.68])
    np.testing.assert_allclose(albedo["light"], [0.65, 0.65, 0.65])
    homework = (8 * np.array([0.747 + 0.058, 0.747 + 0.258, 0.747])
                + 15.6 * np.array([0.740 + 0.287, 0.740 + 0.160, 0.740])
                + 18.4 * np.array([0.737 + 0.642, 0.737 + 0.159, 0.737]))
    np.testing.assert_allclose(cornell.materials[names.index("light")].emission, homework)
    lights = cornell.lights
    assert lights.total_area == pytest.approx(130 * 105)
    np.testing.assert_allclose(lights.normals, [[0, -1, 0]] * 2, atol=1e-7)   # emits downward
    np.testing.assert_allclose(cornell.camera.position, [278, 273, -800])
    np.testing.assert_allclose(cornell.camera.forward, [0, 0, 1])
    assert cornell.camera.fov_y == 40
    # The red wall (x ~ 556) is on the left: the image's right points to -x.
    assert cornell.camera.right[0] < -0.99


def test_scene_loads_by_name_by_folder_and_by_file():
    for ref in ("cornell-box", CORNELL, CORNELL / "scene.toml", str(CORNELL / "scene.toml")):
        assert ptlab.load_scene(ref).triangle_count == 32


@pytest.fixture
def scene_dir(tmp_path):
    """A folder with a valid minimal scene; tests break one thing at a time."""
    (tmp_path / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    (tmp_path / "lamp.obj").write_text("v 0 0 2\nv 0 1 2\nv 1 1 2\nf 1 2 3\n")
    return tmp_path


GOOD = """
[camera]
position = [0.5, 0.5, 5]
look_at = [0.5, 0.5, 0]
fov = 30

[materials.grey]
type = "diffuse"
albedo = 0.5

[materials.lamp]
type = "diffuse"
albedo = [0, 0, 0]
emission = [1, 1, 1]

[[mesh]]
file = "quad.obj"
material = "grey"

[[mesh]]
file = "lamp.obj"
material = "lamp"
"""


def write_scene(folder: Path, text: str) -> Path:
    path = folder / "scene.toml"
    path.write_text(text)
    return path


def test_minimal_scene_loads(scene_dir):
    scene = ptlab.load_scene(write_scene(scene_dir, GOOD))
    assert scene.triangle_count == 3 and len(scene.lights) == 1


BROKEN = {
    "missing mesh file": (GOOD.replace('"quad.obj"', '"nope.obj"'), "mesh[0].file", "not found"),
    "unknown material type": (GOOD.replace('type = "diffuse"\nalbedo = 0.5',
                                           'type = "velvet"\nalbedo = 0.5'),
                              "materials.grey.type", "unknown material type"),
    "malformed toml": (GOOD.replace("fov = 30", "fov = = 30"), "scene.toml", "malformed TOML"),
    "no light": (GOOD.replace("emission = [1, 1, 1]", ""), "scene.toml", "no light"),
    "no camera": (GOOD[GOOD.index("[materials.grey]"):], "scene.toml", "no [camera]"),
    "unknown key": (GOOD.replace("fov = 30", "fov = 30\nzoom = 2"), "camera.zoom", "unknown key"),
    "undefined material": (GOOD.replace('material = "grey"', 'material = "gray"'),
                           "mesh[0].material", "no material named 'gray'"),
    "albedo above one": (GOOD.replace("albedo = 0.5", "albedo = 1.5"), "materials.grey.albedo",
                         "at most 1"),
    "negative emission": (GOOD.replace("emission = [1, 1, 1]", "emission = [1, -1, 1]"),
                          "materials.lamp.emission", "negative"),
    "bad vector": (GOOD.replace("position = [0.5, 0.5, 5]", "position = [0.5, 5]"),
                   "camera.position", "3 numbers"),
    "absurd fov": (GOOD.replace("fov = 30", "fov = 180"), "camera.fov", "between 0 and 180"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_scene_names_file_key_and_problem(scene_dir, case):
    text, key, problem = BROKEN[case]
    with pytest.raises(SceneError) as error:
        ptlab.load_scene(write_scene(scene_dir, text))
    message = str(error.value)
    assert "\n" not in message
    assert "scene.toml" in message and key in message and problem in message, message


def test_nan_vertices_are_reported_with_the_mesh(scene_dir):
    (scene_dir / "quad.obj").write_text("v 0 0 0\nv nan 0 0\nv 1 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match=r"mesh\[0\]\.file.*quad\.obj.*NaN"):
        ptlab.load_scene(write_scene(scene_dir, GOOD))


def test_zero_area_light_is_an_error(scene_dir):
    (scene_dir / "lamp.obj").write_text("v 0 0 2\nv 0 1 2\nv 0 2 2\nf 1 2 3\n")
    with pytest.raises(SceneError, match="zero-area"):
        ptlab.load_scene(write_scene(scene_dir, GOOD))


def test_degenerate_triangles_are_dropped(scene_dir):
    (scene_dir / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 2 0\nf 1 2 3\nf 1 3 4\n")
    assert ptlab.load_scene(write_scene(scene_dir, GOOD)).triangle_count == 2


def test_unknown_scene_name_lists_the_built_in_ones():
    with pytest.raises(SceneError, match="cornell-box"):
        ptlab.load_scene("no-such-scene")


MATERIALS = """
[materials.gold]
type = "microfacet"
f0 = "gold"
roughness = 0.3

[materials.tinted]
type = "microfacet"
f0 = [0.9, 0.6, 0.3]
alpha = 0.1
kd = [0.2, 0.2, 0.2]
ks = 0.5
sampling = "hemisphere"

[materials.mirror]
type = "mirror"
reflectance = 0.9
fresnel = true

[materials.glass]
type = "dielectric"
eta = 1.33
"""


def test_every_material_type_and_spheres_load(scene_dir):
    text = GOOD + MATERIALS + """
[[mesh]]
sphere = { center = [0.5, 0.5, 0.5], radius = 0.25, subdivisions = 2 }
material = "glass"
"""
    scene = ptlab.load_scene(write_scene(scene_dir, text))
    kinds = {name: type(m).__name__ for name, m in zip(scene.material_names, scene.materials,
                                                       strict=True)}
    assert kinds == {"grey": "Diffuse", "lamp": "Diffuse", "gold": "Microfacet",
                     "tinted": "Microfacet", "mirror": "Mirror", "glass": "Dielectric"}
    tinted = scene.materials[scene.material_names.index("tinted")]
    assert tinted.alpha == 0.1 and tinted.sampling == "hemisphere"
    assert scene.materials[scene.material_names.index("gold")].alpha == pytest.approx(0.09)
    assert scene.triangle_count == 3 + 320                   # icosphere, 2 subdivisions
    assert np.isfinite(ptlab.render(scene, spp=1, res=8, workers=1)).all()


@pytest.mark.parametrize("good, bad, key, problem", [
    ("roughness = 0.3", "roughness = 0", "materials.gold", "alpha"),
    ('f0 = "gold"', 'f0 = "unobtainium"', "materials.gold", "unknown metal"),
    ("eta = 1.33", 'eta = "water"', "materials.glass.eta", "number"),
    ("fresnel = true", "fresnel = 1", "materials.mirror.fresnel", "true or false"),
])
def test_bad_material_values_name_the_material(scene_dir, good, bad, key, problem):
    with pytest.raises(SceneError) as error:
        ptlab.load_scene(write_scene(scene_dir, GOOD + MATERIALS.replace(good, bad)))
    assert key in str(error.value) and problem in str(error.value), str(error.value)


def test_a_mesh_needs_a_file_or_a_sphere(scene_dir):
    text = GOOD + '\n[[mesh]]\nmaterial = "grey"\n'
    with pytest.raises(SceneError, match=r"mesh\[2\]: give exactly one of `file` and `sphere`"):
        ptlab.load_scene(write_scene(scene_dir, text))


def test_the_microfacet_cornell_box_loads():
    scene = ptlab.load_scene("cornell-box-microfacet")
    assert {type(m).__name__ for m in scene.materials} == {"Diffuse", "Microfacet"}
