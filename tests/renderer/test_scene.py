"""Scene files: the Cornell box as specified, and one clear error per malformed input."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ptlab
import ptlab.scene_file
from ptlab.errors import SceneError

CORNELL = Path(__file__).resolve().parents[2] / "scenes" / "cornell-box"


def test_cornell_box_is_the_homework_scene(cornell):
    assert cornell.triangle_count == 32
    names = cornell.material_names
    albedo = {name: cornell.materials[names.index(name)].albedo for name in names}
    np.testing.assert_allclose(albedo["red"], [0.63, 0.065, 0.05])
    np.testing.assert_allclose(albedo["green"], [0.14, 0.45, 0.091])
    np.testing.assert_allclose(albedo["white"], [0.725, 0.71, 0.68])
    np.testing.assert_allclose(albedo["light"], [0.65, 0.65, 0.65])
    homework = (
        8 * np.array([0.747 + 0.058, 0.747 + 0.258, 0.747])
        + 15.6 * np.array([0.740 + 0.287, 0.740 + 0.160, 0.740])
        + 18.4 * np.array([0.737 + 0.642, 0.737 + 0.159, 0.737])
    )
    np.testing.assert_allclose(cornell.materials[names.index("light")].emission, homework)
    lights = cornell.area_lights
    assert lights.total_area == pytest.approx(130 * 105)
    np.testing.assert_allclose(lights.normals, [[0, -1, 0]] * 2, atol=1e-7)  # emits downward
    np.testing.assert_allclose(cornell.camera.position, [278, 273, -800])
    np.testing.assert_allclose(cornell.camera.forward, [0, 0, 1])
    assert cornell.camera.fov_y == 40
    # The red wall (x ~ 556) is on the left: the image's right points to -x.
    assert cornell.camera.right[0] < -0.99


def test_scene_loads_by_name_by_folder_and_by_file():
    for ref in ("cornell-box", CORNELL, CORNELL / "scene.toml", str(CORNELL / "scene.toml")):
        assert ptlab.load_scene(ref).triangle_count == 32


@pytest.mark.subprocess
def test_the_scene_knows_nothing_of_scene_files():
    # ptlab.scene_file imports ptlab.scene: the way back (a forwarder of load_scene and its
    # constants) would be a circle. A fresh interpreter, since this one has both loaded.
    code = (
        "import sys, ptlab.scene\n"
        "print('ptlab.scene_file' in sys.modules, hasattr(ptlab.scene, 'load_scene'))"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.split() == ["False", "False"]
    assert ptlab.load_scene is ptlab.scene_file.load_scene


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
    assert scene.triangle_count == 3
    assert len(scene.area_lights) == 1


def test_students_files_written_with_the_old_names_still_run(cornell):
    # Chapter 7 first told students to call scene.lights.sample(u), which gave a LightSample.
    from ptlab.lights import LightSample, ShapeSample

    assert cornell.lights is cornell.area_lights
    assert LightSample is ShapeSample
    with pytest.raises(AttributeError):
        cornell.lights = None
    assert cornell.area_lights is not None


BROKEN = {
    "missing mesh file": (GOOD.replace('"quad.obj"', '"nope.obj"'), "mesh[0].file", "not found"),
    "a folder as the mesh file": (
        GOOD.replace('"quad.obj"', '"."'),
        "mesh[0].file",
        "is a folder, not a mesh file",
    ),
    "unknown material type": (
        GOOD.replace('type = "diffuse"\nalbedo = 0.5', 'type = "velvet"\nalbedo = 0.5'),
        "materials.grey.type",
        "unknown material type",
    ),
    "malformed toml": (GOOD.replace("fov = 30", "fov = = 30"), "scene.toml", "malformed TOML"),
    "no light": (GOOD.replace("emission = [1, 1, 1]", ""), "scene.toml", "no light"),
    "no camera": (GOOD[GOOD.index("[materials.grey]") :], "scene.toml", "no [camera]"),
    "unknown key": (GOOD.replace("fov = 30", "fov = 30\nzoom = 2"), "camera.zoom", "unknown key"),
    "undefined material": (
        GOOD.replace('material = "grey"', 'material = "gray"'),
        "mesh[0].material",
        "no material named 'gray'",
    ),
    "albedo above one": (GOOD.replace("albedo = 0.5", "albedo = 1.5"), "materials.grey.albedo", "at most 1"),
    "negative emission": (
        GOOD.replace("emission = [1, 1, 1]", "emission = [1, -1, 1]"),
        "materials.lamp.emission",
        "negative",
    ),
    "bad vector": (
        GOOD.replace("position = [0.5, 0.5, 5]", "position = [0.5, 5]"),
        "camera.position",
        "3 numbers",
    ),
    "absurd fov": (GOOD.replace("fov = 30", "fov = 180"), "camera.fov", "between 0 and 180"),
}


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_broken_scene_names_file_key_and_problem(scene_dir, case):
    text, key, problem = BROKEN[case]
    with pytest.raises(SceneError) as error:
        ptlab.load_scene(write_scene(scene_dir, text))
    message = str(error.value)
    assert "\n" not in message
    assert "scene.toml" in message, message
    assert key in message, message
    assert problem in message, message


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


def test_the_scenes_size_and_place_are_those_of_all_its_meshes(scene_dir):
    # The scene is as wide as the box around all its meshes, however small each one is; the
    # mesh named as too far out is the one farthest from the origin, on whichever side.
    tiny = "v 0 0 {z}\nv 0 1e-7 {z}\nv 1e-7 1e-7 {z}\nf 1 2 3\n"
    (scene_dir / "quad.obj").write_text(tiny.format(z=0))
    (scene_dir / "lamp.obj").write_text(tiny.format(z=2))
    assert ptlab.load_scene(write_scene(scene_dir, GOOD)).triangle_count == 2
    (scene_dir / "lamp.obj").write_text(tiny.format(z="1e-7"))
    with pytest.raises(SceneError, match="the scene is only 1e-07 wide"):
        ptlab.load_scene(write_scene(scene_dir, GOOD))
    (scene_dir / "quad.obj").write_text("v -1000 0 0\nv -999 0 0\nv -999 1 0\nf 1 2 3\n")
    (scene_dir / "lamp.obj").write_text("v -1001 0 1\nv -1000 0 1\nv -1000 1 1\nf 1 2 3\n")
    with pytest.raises(SceneError, match=r"mesh\[1\]\.file: a vertex lies 1001 from the origin"):
        ptlab.load_scene(write_scene(scene_dir, GOOD))


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
    text = (
        GOOD
        + MATERIALS
        + """
[[mesh]]
sphere = { center = [0.5, 0.5, 0.5], radius = 0.25, subdivisions = 2 }
material = "glass"
"""
    )
    scene = ptlab.load_scene(write_scene(scene_dir, text))
    kinds = {name: type(m).__name__ for name, m in zip(scene.material_names, scene.materials, strict=True)}
    assert kinds == {
        "grey": "Diffuse",
        "lamp": "Diffuse",
        "gold": "Microfacet",
        "tinted": "Microfacet",
        "mirror": "Mirror",
        "glass": "Dielectric",
    }
    tinted = scene.materials[scene.material_names.index("tinted")]
    assert tinted.alpha == 0.1
    assert tinted.sampling == "hemisphere"
    assert scene.materials[scene.material_names.index("gold")].alpha == pytest.approx(0.09)
    assert scene.triangle_count == 3 + 320  # icosphere, 2 subdivisions
    assert np.isfinite(ptlab.render(scene, spp=1, res=8, workers=1)).all()


@pytest.mark.parametrize(
    ("good", "bad", "key", "problem"),
    [
        ("roughness = 0.3", "roughness = 0", "materials.gold", "alpha"),
        ('f0 = "gold"', 'f0 = "unobtainium"', "materials.gold", "unknown metal"),
        ("eta = 1.33", 'eta = "water"', "materials.glass.eta", "number"),
        ("fresnel = true", "fresnel = 1", "materials.mirror.fresnel", "true or false"),
    ],
)
def test_bad_material_values_name_the_material(scene_dir, good, bad, key, problem):
    with pytest.raises(SceneError) as error:
        ptlab.load_scene(write_scene(scene_dir, GOOD + MATERIALS.replace(good, bad)))
    assert key in str(error.value), str(error.value)
    assert problem in str(error.value), str(error.value)


def test_a_mesh_needs_a_file_a_sphere_or_a_quad(scene_dir):
    text = GOOD + '\n[[mesh]]\nmaterial = "grey"\n'
    with pytest.raises(SceneError, match=r"mesh\[2\]: give exactly one of `file`, `sphere` and `quad`"):
        ptlab.load_scene(write_scene(scene_dir, text))


UNLIT = GOOD.replace("emission = [1, 1, 1]", "")
POINT_LIGHT = "\n[[point_light]]\nposition = [0.5, 0.5, 3]\nintensity = [1, 2, 3]\n"
SKY = "\n[sky]\nradiance = [0.1, 0.2, 0.3]\n"


@pytest.mark.parametrize("lights", [POINT_LIGHT, SKY, POINT_LIGHT + SKY])
def test_point_lights_or_a_sky_light_a_scene_without_emission(scene_dir, lights):
    scene = ptlab.load_scene(write_scene(scene_dir, UNLIT + lights))
    assert scene.area_lights is None
    kinds = [type(kind).__name__ for kind in scene.light_sampler.kinds]
    assert kinds == [name for name, text in (("PointLights", POINT_LIGHT), ("Sky", SKY)) if text in lights]
    if scene.point_lights is not None:
        np.testing.assert_allclose(scene.point_lights.intensity, [[1, 2, 3]])
    if scene.sky is not None:
        np.testing.assert_allclose(scene.sky.radiance, [0.1, 0.2, 0.3])
    assert scene.light_sampler.pmf.sum() == pytest.approx(1)
    assert np.isfinite(ptlab.render(scene, spp=1, res=8, workers=1)).all()


BROKEN_LIGHTS_AND_MESHES = {
    "negative intensity": (
        POINT_LIGHT.replace("[1, 2, 3]", "[1, -2, 3]"),
        "point_light[0].intensity",
        "must not be negative",
    ),
    "dark point light": (POINT_LIGHT.replace("[1, 2, 3]", "0"), "point_light[0].intensity", "must not be 0"),
    "point light without intensity": (
        POINT_LIGHT.replace("intensity = [1, 2, 3]", ""),
        "point_light[0].intensity",
        "missing",
    ),
    "point light far out": (
        POINT_LIGHT.replace("[0.5, 0.5, 3]", "[0.5, 0.5, 1e11]"),
        "point_light[0].position",
        "within",
    ),
    "point light typo": (
        POINT_LIGHT.replace("intensity", "intensty"),
        "point_light[0].intensty",
        "unknown key",
    ),
    "sky not a colour": (SKY.replace("[0.1, 0.2, 0.3]", '"blue"'), "sky.radiance", "colour"),
    "sky of two numbers": (SKY.replace("[0.1, 0.2, 0.3]", "[0.1, 0.2]"), "sky.radiance", "3 numbers"),
    "sky as a table": (SKY.replace("[0.1, 0.2, 0.3]", "{ r = 1 }"), "sky.radiance", "colour"),
    "negative sky": (SKY.replace("[0.1, 0.2, 0.3]", "-1"), "sky.radiance", "negative"),
    "quad uv of the wrong shape": (
        "\n[[mesh]]\nquad = { corners = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "
        'uv = [[0, 0], [1, 0], [1, 1]] }\nmaterial = "grey"\n',
        "mesh[2].quad.uv",
        "4 pairs",
    ),
    "quad uv of three numbers": (
        "\n[[mesh]]\nquad = { corners = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "
        'uv = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]] }\nmaterial = "grey"\n',
        "mesh[2].quad.uv",
        "4 pairs",
    ),
    "quad of three corners": (
        '\n[[mesh]]\nquad = { corners = [[0, 0, 0], [1, 0, 0], [1, 1, 0]] }\nmaterial = "grey"\n',
        "mesh[2].quad.corners",
        "4 points",
    ),
    "flat quad": (
        '\n[[mesh]]\nquad = { corners = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]] }\nmaterial = "grey"\n',
        "mesh[2].quad.corners",
        "zero area",
    ),
    "zero scale": (
        '\n[[mesh]]\nfile = "quad.obj"\nscale = 0\nmaterial = "grey"\n',
        "mesh[2].scale",
        "must not be 0",
    ),
    "a matrix beside a scale": (
        '\n[[mesh]]\nfile = "quad.obj"\nscale = 2\nmaterial = "grey"\n'
        "matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n",
        "mesh[2]",
        "either a `matrix`",
    ),
    "checkerboard of one colour": (
        '\n[materials.board]\ntype = "diffuse"\nalbedo = { checkerboard = [[1, 0, 0]] }\n',
        "materials.board.albedo.checkerboard",
        "two colours",
    ),
    "checkerboard too bright": (
        '\n[materials.board]\ntype = "diffuse"\nalbedo = { checkerboard = [[1, 0, 0], 2] }\n',
        "materials.board.albedo.checkerboard[1]",
        "at most 1",
    ),
    "bad render res": ("\n[render]\nres = [640]\n", "render.res", "[width, height]"),
    "bad render depth": ("\n[render]\nmax_depth = -1\n", "render.max_depth", "integer"),
}


@pytest.mark.parametrize("case", sorted(BROKEN_LIGHTS_AND_MESHES))
def test_broken_lights_and_meshes_name_file_key_and_problem(scene_dir, case):
    extra, key, problem = BROKEN_LIGHTS_AND_MESHES[case]
    with pytest.raises(SceneError) as error:
        ptlab.load_scene(write_scene(scene_dir, GOOD + extra))
    message = str(error.value)
    assert "\n" not in message
    assert "scene.toml" in message, message
    assert key in message, message
    assert problem in message, message


def test_a_scene_without_any_light_names_every_kind(scene_dir):
    with pytest.raises(SceneError, match=r"no light.*emission.*point_light.*sky"):
        ptlab.load_scene(write_scene(scene_dir, UNLIT))


def test_scale_multiplies_a_mesh_files_coordinates(scene_dir):
    scaled = GOOD.replace('file = "quad.obj"', 'file = "quad.obj"\nscale = 60')
    np.testing.assert_allclose(
        ptlab.load_scene(write_scene(scene_dir, scaled)).triangles[:2],
        60 * ptlab.load_scene(write_scene(scene_dir, GOOD)).triangles[:2],
    )


def test_render_table_gives_the_resolution_and_depth_unless_the_render_does(scene_dir):
    scene = ptlab.load_scene(write_scene(scene_dir, GOOD + "\n[render]\nres = [12, 8]\nmax_depth = 3\n"))
    assert (scene.defaults.res, scene.defaults.max_depth) == ((12, 8), 3)
    result = ptlab.render_result(scene, spp=1, workers=1)
    assert result.image.shape == (8, 12, 3)
    assert result.settings["max_depth"] == 3
    result = ptlab.render_result(scene, spp=1, res=4, max_depth=1, workers=1)
    assert result.image.shape == (4, 4, 3)
    assert result.settings["max_depth"] == 1
    assert ptlab.load_scene(write_scene(scene_dir, GOOD + "\n[render]\nres = 16\n")).defaults.res == (16, 16)


def test_the_microfacet_cornell_box_loads():
    scene = ptlab.load_scene("cornell-box-microfacet")
    assert {type(m).__name__ for m in scene.materials} == {"Diffuse", "Microfacet"}
