"""``ptlab.measure.mitsuba_export``, ``mitsuba_render`` and ``against_mitsuba``: Mitsuba's
scene says what the scene file says, what it cannot say is an error, the command's options
are the module's, and (where Mitsuba is installed) both renderers draw the same picture."""

from __future__ import annotations

import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import numpy as np
import pytest
from helpers import load_script

from ptlab.camera import Camera
from ptlab.errors import PtlabError
from ptlab.image import write_image
from ptlab.lights import PointLights, Sky
from ptlab.materials import Diffuse, Mirror
from ptlab.measure.against_mitsuba import ComparisonOptions, compare
from ptlab.measure.mitsuba_export import SCENE_XML, scene_xml, write_mitsuba_scene
from ptlab.measure.mitsuba_render import MitsubaRenderer, _probe_failure, import_mitsuba
from ptlab.rendering import render_result
from ptlab.scene import RenderDefaults, Scene
from ptlab.scene_file import find_scene_file, load_scene
from ptlab.textures import Checkerboard

REPOSITORY = Path(__file__).resolve().parents[2]


# -- the exported scene -----------------------------------------------------------------------


def _vector(text: str) -> np.ndarray:
    return np.array([float(v) for v in text.split(",")])


def _obj_triangles(path: Path) -> np.ndarray:
    """(T, 3, 3) triangles of an OBJ file of ``v`` and ``f`` lines (1-based indices)."""
    lines = [line.split() for line in path.read_text().splitlines() if line and line[0] in "vf"]
    vertices = np.array([[float(x) for x in line[1:]] for line in lines if line[0] == "v"])
    faces = np.array([[int(i) - 1 for i in line[1:]] for line in lines if line[0] == "f"])
    return vertices[faces]


@pytest.fixture(scope="module")
def cornell_export(tmp_path_factory) -> tuple[Scene, dict, ElementTree.Element, Path]:
    """The Cornell box, its scene file (read here with tomllib, not by ptlab), and the
    exported XML at 64 x 48 with the folder it is in."""
    scene = load_scene("cornell-box")
    scene_file = tomllib.loads(find_scene_file("cornell-box").read_text())
    folder = tmp_path_factory.mktemp("mitsuba")
    xml = write_mitsuba_scene(scene, folder, 64, 48)
    assert xml == folder / SCENE_XML
    return scene, scene_file, ElementTree.parse(xml).getroot(), folder


def test_the_camera_is_the_scene_files(cornell_export):
    _, scene_file, root, _ = cornell_export
    camera = scene_file["camera"]
    sensor = root.find("sensor")
    assert sensor.get("type") == "perspective"
    assert float(sensor.find("float[@name='fov']").get("value")) == camera["fov"]
    # The field of view is the vertical one, as ptlab's.
    assert sensor.find("string[@name='fov_axis']").get("value") == "y"
    look_at = sensor.find("transform/lookat")
    origin = _vector(look_at.get("origin"))
    np.testing.assert_array_equal(origin, camera["position"])
    np.testing.assert_allclose(_vector(look_at.get("target")) - origin, camera["direction"], atol=1e-12)
    np.testing.assert_allclose(_vector(look_at.get("up")), camera["up"], atol=1e-12)
    film = sensor.find("film")
    assert (
        film.find("integer[@name='width']").get("value"),
        film.find("integer[@name='height']").get("value"),
    ) == ("64", "48")
    # ptlab jitters each sample uniformly inside its pixel: a box filter.
    assert film.find("rfilter").get("type") == "box"


def test_nothing_lies_beyond_the_far_clipping_plane(cornell_export):
    scene, _, root, _ = cornell_export
    far = float(root.find("sensor/float[@name='far_clip']").get("value"))
    assert far > np.linalg.norm(scene.triangles - scene.camera.position, axis=-1).max()


def test_each_material_has_its_albedo_radiance_and_triangles(cornell_export):
    scene, scene_file, root, folder = cornell_export
    materials = scene_file["materials"]
    shapes = root.findall("shape")
    assert len(shapes) == len(materials)
    exported = 0
    for shape in shapes:
        # Two-sided diffuse, as ptlab's, with the normals of the triangles' winding.
        assert shape.find("bsdf").get("type") == "twosided"
        assert shape.find("bsdf/bsdf").get("type") == "diffuse"
        assert shape.find("boolean[@name='face_normals']").get("value") == "true"
        reflectance = _vector(shape.find("bsdf/bsdf/rgb[@name='reflectance']").get("value"))
        # (the scene file's albedos are all different: each names its material)
        name = next(
            name
            for name, m in materials.items()
            if np.array_equal(np.broadcast_to(m["albedo"], 3), reflectance)
        )
        emitter = shape.find("emitter")
        if "emission" in materials[name]:
            assert emitter.get("type") == "area"
            np.testing.assert_array_equal(
                _vector(emitter.find("rgb").get("value")), materials[name]["emission"]
            )
        else:
            assert emitter is None
        triangles = _obj_triangles(folder / shape.find("string[@name='filename']").get("value"))
        # The same vertices in the same order: the same front faces, which the light emits from.
        expected = scene.triangles[scene.material_ids == scene.material_names.index(name)]
        np.testing.assert_array_equal(triangles, expected)
        exported += len(triangles)
    assert exported == len(scene.triangles)


def test_the_integrator_has_no_depth_limit_and_takes_the_parameters(cornell_export):
    _, _, root, _ = cornell_export
    integrator = root.find("integrator")
    assert integrator.get("type") == "path"
    assert integrator.find("integer[@name='max_depth']").get("value") == "-1"
    assert integrator.find("integer[@name='rr_depth']").get("value") == "$rr_depth"
    sampler = root.find("sensor/sampler")
    assert sampler.get("type") == "$sampler"
    assert {d.get("name") for d in root.findall("default")} == {"sampler", "spp", "seed", "rr_depth"}


def _one_triangle(material, **scene_options) -> Scene:
    """A triangle in front of a camera, of ``material`` (named "plate")."""
    return Scene(
        triangles=np.array([[[-1.0, -1.0, 3.0], [1.0, -1.0, 3.0], [0.0, 1.0, 3.0]]]),
        material_ids=np.array([0]),
        materials=[material],
        camera=Camera.look_at((0, 0, 0), (0, 0, 1)),
        name="plate",
        material_names=["plate"],
        **scene_options,
    )


def test_the_scene_files_max_depth_is_mitsubas_plus_one():
    # ptlab's max_depth 1 is direct light; Mitsuba's 1 is the light seen directly, 2 direct light.
    scene = _one_triangle(Diffuse(0.5, emission=(1, 1, 1)), defaults=RenderDefaults(max_depth=1))
    root = ElementTree.fromstring(scene_xml(scene, {0: "plate.obj"}, 4, 4))
    assert root.find("integrator/integer[@name='max_depth']").get("value") == "2"


class _BrighterDiffuse(Diffuse):
    """A diffuse material that shades otherwise: not a plain Diffuse to Mitsuba."""

    def eval(self, wo, wi, n):
        return 2 * super().eval(wo, wi, n)


@pytest.mark.parametrize(
    ("scene", "says"),
    [
        (_one_triangle(Mirror()), "material 'plate' is a Mirror"),
        (_one_triangle(_BrighterDiffuse(0.5)), "material 'plate' is a _BrighterDiffuse"),
        (
            _one_triangle(Diffuse(Checkerboard([[0, 0, 0], [1, 1, 1]])), uvs=np.zeros((1, 3, 2))),
            "material 'plate' has a textured albedo",
        ),
        (_one_triangle(Diffuse(0.5), point_lights=PointLights([[0, 0, 1]], [[1, 1, 1]])), "point lights"),
        (_one_triangle(Diffuse(0.5), sky=Sky([1, 1, 1])), "a sky"),
        (_one_triangle(Diffuse(0.5), normals=np.tile([0.0, 0.6, 0.8], (1, 3, 1))), "vertex normals"),
    ],
    ids=["mirror", "subclass", "texture", "point-lights", "sky", "smooth"],
)
def test_what_mitsubas_scene_cannot_say_is_an_error(scene, says, tmp_path):
    with pytest.raises(PtlabError, match=says):
        write_mitsuba_scene(scene, tmp_path, 4, 4)
    # Found before anything is written, rather than a scene left half-written.
    assert not list(tmp_path.iterdir())


def test_a_builtin_scene_with_point_lights_is_refused(tmp_path):
    # games101-hw6 is diffuse but lit by point lights, which the scene would silently lose.
    with pytest.raises(PtlabError, match="games101-hw6: point lights have no Mitsuba counterpart"):
        write_mitsuba_scene(load_scene("games101-hw6"), tmp_path, 4, 4)


# -- Mitsuba, missing or failing --------------------------------------------------------------


@pytest.mark.subprocess
def test_the_modules_import_without_mitsuba():
    blocked = "import sys; sys.modules['mitsuba'] = sys.modules['drjit'] = None; "
    imports = (
        "import ptlab.measure.against_mitsuba, ptlab.measure.mitsuba_export, ptlab.measure.mitsuba_render"
    )
    done = subprocess.run([sys.executable, "-c", blocked + imports], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


@pytest.mark.subprocess
def test_missing_mitsuba_says_what_to_install(tmp_path, monkeypatch):
    # A "mitsuba" package that cannot be imported stands first on the probe's path.
    (tmp_path / "mitsuba").mkdir()
    (tmp_path / "mitsuba" / "__init__.py").write_text("raise ImportError('No module named mitsuba')\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    with pytest.raises(PtlabError, match=r"pip install mitsuba") as error:
        import_mitsuba("scalar_rgb")
    assert "\n" not in str(error.value)


def test_an_llvm_abort_is_one_line_with_a_hint():
    # What a Dr.Jit built for a newer LLVM leaves: no Python error, LLVM's lines, SIGABRT.
    stderr = (
        "LLVM ERROR: Cannot select: 0x55d: f32 = fmaxnum\n  0x55e: i64 = undef\nIn function: drjit_f37e\n"
    )
    probe = subprocess.CompletedProcess(["python"], -6, stdout="", stderr=stderr)
    message = _probe_failure(probe, "llvm_ad_rgb")
    assert message.startswith(
        "mitsuba cannot render with variant 'llvm_ad_rgb' here: LLVM ERROR: Cannot select"
    )
    assert "DRJIT_LIBLLVM_PATH" in message
    assert "\n" not in message


# -- the command ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def command():
    """``scripts/against_mitsuba.py`` as a module."""
    return load_script("against_mitsuba")


def test_the_commands_defaults_are_the_modules(command):
    assert command.options_from(command.build_parser().parse_args([])) == ComparisonOptions()


def test_the_commands_lists_are_read_once_each(command):
    args = command.build_parser().parse_args(
        [
            "--samplers",
            "ldsampler, independent,ldsampler",
            "--rr-depth",
            "3,3,2",
            "--res",
            "40x30",
            "--no-process",
        ]
    )
    options = command.options_from(args)
    assert options.samplers == ("ldsampler", "independent")
    assert options.rr_depths == (3, 2)
    assert options.res == (40, 30)
    assert not options.time_processes


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--samplers", "sobol"], "--samplers 'sobol': give a comma-separated list of independent"),
        (["--rr-depth", "5,-1"], "--rr-depth '5,-1': give non-negative integers"),
        (["--spp", "10", "--samplers", "stratified"], "Mitsuba's stratified sampler needs a square number"),
        (["--variant", "llvm_ad_spectral"], "use an RGB variant"),
        (["--res", "0"], "width and height must be positive"),
    ],
)
def test_an_option_that_cannot_work_is_exit_code_2_in_one_line(command, argv, says, capsys):
    assert command.main(argv) == 2
    error = capsys.readouterr().err
    assert error.startswith("against_mitsuba.py: error: ")
    assert says in error
    assert error.count("\n") == 1


# -- against Mitsuba itself (skipped where it is not installed) ------------------------------

#: Mitsuba's CPU variant that needs no LLVM: it renders wherever Mitsuba installs.
VARIANT = "scalar_rgb"


@pytest.fixture(scope="module")
def mitsuba_modules():
    pytest.importorskip("mitsuba", reason="Mitsuba is optional: pip install mitsuba")
    # Installed, the scalar variant must render: no skip here, a failure is a failure.
    return import_mitsuba(VARIANT)


def _block_means(image: np.ndarray) -> np.ndarray:
    """(4, 4, 3) means of the image's 4 x 4 blocks: a flipped or shifted picture changes them."""
    height, width, _ = image.shape
    return image.reshape(4, height // 4, 4, width // 4, 3).mean(axis=(1, 3))


@pytest.mark.subprocess
def test_mitsuba_and_ptlab_draw_the_same_cornell_box(mitsuba_modules, tmp_path):
    """Welch's t of each block mean and channel (48 of them) over 8 seeds of each renderer
    at 16 x 16, 256 spp: |t| < 7, which Student's t with 14 degrees of freedom exceeds with a
    chance of 6e-6 each, 3e-4 for the test (its false-alarm rate for the fixed seeds 0-7).
    A block mean's standard error is at most 4% of it, so a colour, a light or a camera that
    is 20% off, or a picture flipped left to right, fails."""
    mi, dr = mitsuba_modules
    scene = load_scene("cornell-box")
    mitsuba = MitsubaRenderer(mi, dr, write_mitsuba_scene(scene, tmp_path, 16, 16), [("independent", 5)])
    seeds = range(8)
    theirs = np.array([_block_means(mitsuba.render("independent", 5, 256, seed)[0]) for seed in seeds])
    ours = np.array(
        [
            _block_means(
                render_result(scene, spp=256, res=16, seed=seed, workers=1, sampler="independent").image
            )
            for seed in seeds
        ]
    )
    error = np.sqrt(theirs.var(axis=0, ddof=1) / len(seeds) + ours.var(axis=0, ddof=1) / len(seeds))
    t = (theirs.mean(axis=0) - ours.mean(axis=0)) / error
    assert np.abs(t).max() < 7, np.round(t, 1)
    # The test can see a mistake: the same images, one of them flipped left to right.
    flipped = (theirs[:, :, ::-1].mean(axis=0) - ours.mean(axis=0)) / error
    assert np.abs(flipped).max() > 7


@pytest.mark.subprocess
def test_the_comparison_runs_and_sees_references_that_differ(mitsuba_modules, tmp_path, monkeypatch):
    monkeypatch.setenv("PTLAB_CACHE", str(tmp_path / "cache"))
    # ptlab's "reference": a 1024-spp render made 20% too bright, which no noise explains.
    wrong = render_result("cornell-box", spp=1024, res=8, seed=5, workers=1).image * 1.2
    write_image(tmp_path / "wrong.exr", wrong, dict(spp=1024))
    options = ComparisonOptions(
        res=(8, 8),
        spp=16,
        repeat=2,
        samplers=("independent", "stratified"),
        rr_depths=(5,),
        ptlab_samplers=("independent",),
        workers=1,
        variant=VARIANT,
        reference_spp=1024,
        ptlab_reference=str(tmp_path / "wrong.exr"),
        time_processes=False,
        csv=str(tmp_path / "runs.csv"),
    )
    lines: list[str] = []
    assert compare(options, lines.append) is False
    said = "\n".join(lines)
    assert "the references DIFFER by more than noise" in said
    rows = [line for line in said.splitlines() if line.startswith("| ")]
    assert [row.split(" | ")[0] for row in rows[2:]] == [
        "| mitsuba independent rr_depth 5",
        "| mitsuba stratified rr_depth 5",
        "| ptlab independent nee",
    ]
    # Every run of every contender, with its seed: 3 contenders x 2 rounds.
    runs = (tmp_path / "runs.csv").read_text().splitlines()
    assert len(runs) == 1 + 3 * 2
    assert {line.split(",")[2] for line in runs[1:]} == {"0", "1"}
