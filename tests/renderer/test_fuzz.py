"""Bad input, generated and fixed: scene files, their meshes and the command line's options.

Whatever it is given, ``ptlab`` must either render (here a 4x4 image, every pixel finite) or
fail the way every user error fails: exit code 2, one line ``ptlab: error: FILE: KEY: problem``
on stderr, no traceback and no image. Hypothesis generates the inputs from the real format:
the Cornell box's scene file and meshes with one thing changed (a value, a key, a line, a
byte, a vertex or a face), small scenes made up from scratch, and option values. The fixed
cases further down are the crashes and silent misreadings such inputs found, kept as
regressions.

The examples are derandomized and bounded (the "fixed" profile in tests/conftest.py); run
``HYPOTHESIS_PROFILE=long pytest tests/renderer/test_fuzz.py`` to search further.
"""

from __future__ import annotations

import copy
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import currently_in_test_context, event, given, settings
from hypothesis import strategies as st

from ptlab.cli import main
from ptlab.image import read_image
from ptlab.meshes import check_obj_lines, parse_obj, read_mesh_triangles, read_obj

ROOT = Path(__file__).resolve().parents[2]
CORNELL = ROOT / "scenes" / "cornell-box"
CORNELL_TOML = (CORNELL / "scene.toml").read_text()
CORNELL_DATA = tomllib.loads(CORNELL_TOML)
MESH_NAMES = sorted(p.name for p in (CORNELL / "meshes").glob("*.obj"))
TINY = ["--res", "4", "--spp", "1", "--workers", "1", "--quiet"]
#: What ``ptlab render`` says of an image that saw no light (a camera that sees nothing lit).
BLACK = (
    "ptlab: warning: the image is black: no camera ray saw or received any light "
    "(do the lights face the scene?)\n"
)
#: Problems of the whole scene, which name no key.
SCENE_LEVEL = ("has no light", "lights have zero area", "lights' total power")


def examples(count: int) -> settings:
    """``count`` examples under the fixed profile (whose max_examples is 100), and as many
    more as the loaded profile asks for (the long one's 2000: 20 times as many)."""
    return settings(max_examples=count * settings().max_examples // 100)


# --- running the command and judging what it did -------------------------------------------


def run_cli(args: list[str], capsys) -> tuple[int, str]:
    """``ptlab ARGS`` in this process: its exit code and its stderr.

    A NumPy RuntimeWarning (an overflow, a division by zero) is raised as an error, so that
    a scene that computes garbage fails the test instead of rendering it.
    """
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            code = main(args)
        except SystemExit as usage_error:  # argparse exits by itself
            code = usage_error.code
    return code, capsys.readouterr().err


def assert_one_line_error(code: int, err: str, starts: str = "ptlab") -> None:
    assert code == 2, (code, err)
    assert err.count("\n") == 1, err
    assert err.endswith("\n"), err
    assert "Traceback" not in err, err
    assert ": error: " in err, err
    assert err.startswith(starts), err


def render_or_fail_cleanly(scene: Path, capsys) -> str:
    """Render ``scene`` tiny; assert it rendered a finite image or failed cleanly, naming
    the scene file and writing nothing. Returns stderr ("" after a render, or the one line
    that says a black image saw no light)."""
    out = scene.parent / "out.png"
    code, err = run_cli(["render", str(scene), *TINY, "--out", str(out)], capsys)
    if currently_in_test_context():  # (for --hypothesis-show-statistics)
        event("renders" if code == 0 else "fails")
    if code == 0:
        image, _ = read_image(out)
        # (What a mesh file brought that ptlab ignores: one warning line each, naming the mesh.)
        said = [
            line
            for line in err.splitlines(keepends=True)
            if not line.startswith(f"ptlab: warning: {scene}: mesh[")
        ]
        assert "".join(said) == ("" if (image > 0).any() else BLACK), err
        assert image.shape == (4, 4, 3)
        assert np.isfinite(image).all()
        out.unlink()
    else:
        assert_one_line_error(code, err, starts=f"ptlab: error: {scene}: ")
        assert not out.exists()
    return err


def cornell_copy(base: Path) -> Path:
    """A fresh copy of the Cornell box in a new folder under ``base``; its scene file."""
    folder = Path(tempfile.mkdtemp(dir=base)) / "box"
    shutil.copytree(CORNELL, folder)
    return folder / "scene.toml"


# --- TOML, written back from parsed data ----------------------------------------------------


def toml_string(text: str) -> str:
    return '"' + "".join(c if c >= " " and c not in '"\\\x7f' else f"\\u{ord(c):04x}" for c in text) + '"'


def toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else toml_string(key)


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)  # nan, inf and 1e+39 are TOML too
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(toml_value, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    return value.isoformat()  # dates


def to_toml(data: dict) -> str:
    """A TOML document with every top-level key on one line (tables written inline)."""
    return "".join(f"{toml_key(k)} = {toml_value(v)}\n" for k, v in data.items())


def test_the_toml_writer_round_trips_the_cornell_box():
    assert tomllib.loads(to_toml(CORNELL_DATA)) == CORNELL_DATA
    odd = {"k": ['a"\\\n\x7f', -0.0, 10**30, {"": [True]}]}
    assert tomllib.loads(to_toml(odd)) == odd


def value_paths(data, prefix: tuple = ()) -> list[tuple]:
    """The path (keys and list indices) of every value in parsed TOML."""
    paths = []
    for key, value in data.items() if isinstance(data, dict) else enumerate(data):
        paths.append((*prefix, key))
        if isinstance(value, dict | list):
            paths.extend(value_paths(value, (*prefix, key)))
    return paths


def replaced(data: dict, path: tuple, value) -> dict:
    data = copy.deepcopy(data)
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    return data


# --- wrong values of every kind ---------------------------------------------------------------

EDGE_NUMBERS = [
    0,
    -0.0,
    -1,
    1,
    0.5,
    3,
    180,
    1e-45,
    1e-300,
    5e-324,
    1e10,
    1e12,
    1e39,
    1e300,
    2**63,
    10**400,
    -(10**400),
    math.inf,
    -math.inf,
    math.nan,
]
numbers = st.one_of(st.sampled_from(EDGE_NUMBERS), st.integers(), st.floats())
NAMES = [
    "diffuse",
    "microfacet",
    "mirror",
    "dielectric",
    "gold",
    "vndf",
    "hemisphere",
    "white",
    "light",
    "red",
    "meshes/light.obj",
    "meshes/nope.obj",
    "meshes",
    "scene.toml",
    "",
    "x" * 300,
]
words = st.one_of(st.sampled_from(NAMES), st.text(max_size=10))
KEYS = [
    "camera",
    "materials",
    "mesh",
    "position",
    "look_at",
    "direction",
    "up",
    "fov",
    "type",
    "emission",
    "albedo",
    "f0",
    "roughness",
    "alpha",
    "kd",
    "ks",
    "sampling",
    "reflectance",
    "fresnel",
    "eta",
    "transmittance",
    "file",
    "sphere",
    "material",
    "center",
    "radius",
    "subdivisions",
    "quad",
    "corners",
    "uv",
    "scale",
    "checkerboard",
    "point_light",
    "intensity",
    "sky",
    "radiance",
    "render",
    "res",
    "max_depth",
]
scalars = st.one_of(numbers, words, st.booleans(), st.dates())
plausible = st.one_of(
    st.floats(0, 1),
    st.lists(st.floats(0, 1), min_size=3, max_size=3),
    st.lists(st.floats(-1000, 1000), min_size=3, max_size=3),
    st.floats(1, 179),
)
toml_values = st.one_of(
    plausible,
    scalars,
    st.lists(numbers, max_size=5),  # vectors of the wrong length, or wrong
    st.recursive(
        scalars,
        lambda inner: (
            st.lists(inner, max_size=3)
            | st.dictionaries(st.one_of(st.sampled_from(KEYS), st.text(max_size=6)), inner, max_size=3)
        ),
        max_leaves=6,
    ),
)


# --- the Cornell box's scene file, changed ---------------------------------------------------


@examples(70)
@given(path=st.sampled_from(value_paths(CORNELL_DATA)), value=toml_values)
def test_cornell_box_with_a_value_changed_renders_or_names_the_key(path, value, tmp_path, capsys):
    scene = cornell_copy(tmp_path)
    scene.write_text(to_toml(replaced(CORNELL_DATA, path, value)))
    err = render_or_fail_cleanly(scene, capsys)
    # The error names the changed value's section, or is about the whole scene (no light
    # left), or names the mesh that lies farthest out (the scene's size and place).
    assert (
        not err
        or section_of(path) in err
        or any(p in err for p in SCENE_LEVEL)
        or (path[0] == "mesh" and "nearer the origin" in err)
    ), (path, value, err)


def section_of(path: tuple) -> str:
    """The key an error about the value at ``path`` names: camera, materials.NAME, mesh[i]."""
    if len(path) > 1 and path[0] == "materials":
        return f"materials.{path[1]}"
    if len(path) > 1 and path[0] == "mesh":
        return f"mesh[{path[1]}]"
    return path[0]


@examples(30)
@given(
    path=st.sampled_from([p for p in value_paths(CORNELL_DATA) if isinstance(p[-1], str)]),
    new_key=st.one_of(st.none(), st.sampled_from(KEYS), st.text(max_size=8)),
)
def test_cornell_box_with_a_key_renamed_or_removed_renders_or_fails_cleanly(path, new_key, tmp_path, capsys):
    data = copy.deepcopy(CORNELL_DATA)
    parent = data
    for key in path[:-1]:
        parent = parent[key]
    value = parent.pop(path[-1])
    if new_key is not None:
        parent[new_key] = value
    scene = cornell_copy(tmp_path)
    scene.write_text(to_toml(data))
    render_or_fail_cleanly(scene, capsys)


@st.composite
def garbled_text(draw, text: str) -> bytes:
    """``text`` with a line dropped, repeated or replaced, or a byte changed."""
    lines = text.split("\n")
    i = draw(st.integers(0, len(lines) - 1))
    change = draw(st.sampled_from(["drop", "repeat", "replace", "byte"]))
    if change == "drop":
        del lines[i]
    elif change == "repeat":
        lines.insert(i, lines[i])
    elif change == "replace":
        lines[i] = draw(
            st.one_of(
                st.text(max_size=30),
                st.sampled_from(
                    [
                        "[camera]",
                        "[[mesh]]",
                        "[materials]",
                        "[materials.red]",
                        'type = "mirror"',
                        "fov = 0",
                        'file = "meshes/floor.obj"',
                        "up = [0, 0, 1]",
                        "= 1",
                        "[mesh]",
                    ]
                ),
            )
        )
    data = bytearray("\n".join(lines).encode())
    if change == "byte":
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
    return bytes(data)


@examples(50)
@given(data=garbled_text(CORNELL_TOML))
def test_cornell_box_with_a_line_or_byte_garbled_renders_or_fails_cleanly(data, tmp_path, capsys):
    scene = cornell_copy(tmp_path)
    scene.write_bytes(data)
    render_or_fail_cleanly(scene, capsys)


# --- the Cornell box's meshes, changed -------------------------------------------------------

number_words = numbers.map(lambda x: repr(x) if isinstance(x, float) else str(x))
junk = st.text(st.characters(blacklist_categories=["Cs", "Zs", "Cc"]), min_size=1, max_size=4)
references = st.builds(
    lambda v, t, n, form: form.format(v=v, t=t, n=n),
    st.integers(-14, 14),
    st.integers(-2, 2),
    st.integers(-2, 2),
    st.sampled_from(["{v}", "{v}/{t}", "{v}//{n}", "{v}/{t}/{n}"]),
)
OTHER_FORMATS = [
    b"",
    b"\n \n",
    b"\x00" * 84,
    CORNELL_TOML.encode(),
    b"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
    b"endloop\nendfacet\nendsolid s\n",
    b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    b"property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    b"0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n",
]


@st.composite
def mutated_obj(draw) -> tuple[str, bytes]:
    """One Cornell mesh file with a vertex, a face, a line, a byte or the whole file changed."""
    name = draw(st.sampled_from(MESH_NAMES))
    lines = (CORNELL / "meshes" / name).read_text().split("\n")
    vertices = [k for k, line in enumerate(lines) if line.startswith("v ")]
    faces = [k for k, line in enumerate(lines) if line.startswith("f ")]
    change = draw(st.sampled_from(["vertex", "face", "insert", "layout", "byte", "truncate", "replace"]))
    if change == "vertex":
        tokens = draw(
            st.one_of(
                st.lists(st.floats(-600, 600).map(repr), min_size=3, max_size=4),
                st.lists(st.one_of(number_words, junk), max_size=8),
            )
        )
        lines[draw(st.sampled_from(vertices))] = " ".join(["v", *tokens])
    elif change == "face":
        tokens = draw(
            st.one_of(
                st.lists(
                    st.one_of(st.integers(1, len(vertices)), st.integers(-len(vertices), -1)).map(str),
                    min_size=3,
                    max_size=5,
                ),
                st.lists(references, max_size=6),
            )
        )
        lines[draw(st.sampled_from(faces))] = " ".join(["f", *tokens])
    elif change == "insert":
        lines.insert(
            draw(st.integers(0, len(lines))),
            draw(
                st.sampled_from(
                    [
                        "vt 0 0",
                        "vn 0 0 1",
                        "vn 0 1",
                        "usemtl m",
                        "o part",
                        "s 1",
                        "l 1 2",
                        "# note",
                        "mtllib nope.mtl",
                        "v 1 2 3",
                        "v 1 2 3 1",
                        "f 1 2 3 4",
                        "f 1 2",
                        "f 1 1 2",
                        "f -1 -2 -3",
                        "\\",
                        "v 1 2 \\",
                    ]
                )
            ),
        )
    elif change == "layout":
        k = draw(st.sampled_from(vertices + faces))
        lines[k] = (
            draw(st.sampled_from(["\t", " ", ""]))
            + lines[k].replace(" ", draw(st.sampled_from([" ", "\t", "  "])), 1)
            + draw(st.sampled_from(["", " # note", " ", "\r"]))
        )
    data = "\n".join(lines).encode()
    if change == "byte":
        data = bytearray(data)
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
        data = bytes(data)
    elif change == "truncate":
        data = data[: draw(st.integers(0, len(data)))]
    elif change == "replace":
        data = draw(st.one_of(st.sampled_from(OTHER_FORMATS), st.binary(max_size=120)))
    return name, data


def obj_triangles(text: str) -> list[tuple]:
    """The triangles an OBJ file describes, read the plain way: each face a fan from its
    first vertex, negative indices counted back from their own line."""
    vertices, faces = [], []
    for line in text.replace("\r\n", "\n").replace("\\\n", "").split("\n"):
        words = line.split()
        if words[:1] == ["v"]:
            vertices.append(tuple(float(x) for x in words[1:4]))
        elif words[:1] == ["f"]:
            indices = [int(w.split("/")[0]) for w in words[1:]]
            faces.append([i - 1 if i > 0 else len(vertices) + i for i in indices])
    return [(vertices[f[0]], vertices[f[k]], vertices[f[k + 1]]) for f in faces for k in range(1, len(f) - 1)]


def canonical(triangles) -> list[tuple]:
    """Triangles that are not degenerate, each rotated to start at its least vertex (which
    keeps its winding), sorted."""
    result = []
    for triangle in triangles:
        a, b, c = (np.array(v) for v in triangle)
        if np.linalg.norm(np.cross(b - a, c - a)) > 1e-9 * max(1.0, np.abs([a, b, c]).max()) ** 2:
            k = min(range(3), key=lambda i: tuple(triangle[i]))
            result.append(tuple(tuple(map(float, triangle[(k + i) % 3])) for i in range(3)))
    return sorted(result)


@examples(110)
@given(change=mutated_obj())
def test_cornell_box_with_a_mesh_changed_renders_what_the_file_says_or_fails_cleanly(
    change, tmp_path, capsys
):
    name, data = change
    scene = cornell_copy(tmp_path)
    mesh = scene.parent / "meshes" / name
    mesh.write_bytes(data)
    err = render_or_fail_cleanly(scene, capsys)
    if err:
        index = CORNELL_DATA["mesh"].index(
            next(m for m in CORNELL_DATA["mesh"] if m["file"] == f"meshes/{name}")
        )
        assert f"mesh[{index}].file" in err or "has no light" in err, err
    else:
        # trimesh read the file as it is written: no vertex shifted, no face lost.
        assert canonical(read_mesh_triangles(mesh).tolist()) == canonical(obj_triangles(data.decode())), data


@examples(150)
@given(change=mutated_obj())
def test_obj_files_ptlab_accepts_read_as_trimesh_reads_them(change):
    # ptlab reads OBJ text itself (faster, and sparing trimesh's and SciPy's imports): the
    # triangles, in their order and each vertex's, must be trimesh's, so that images stay the
    # same.
    import trimesh

    _, data = change
    try:
        vertices, faces, _ = read_obj(data)
    except ValueError:
        return
    # (trimesh skips a record whose keyword a tab follows, which the format allows and ptlab
    # reads: it is given the line with a space there.)
    spaced = re.sub(rb"(?m)^(v[tn]?|f)\t", rb"\1 ", data)
    try:
        mesh = trimesh.load(trimesh.util.wrap_as_stream(spaced), file_type="obj", force="mesh", process=False)
    except ValueError:
        # E.g. a line `f\x011 2 3`, whose keyword is `f\x01` to ptlab (which skips it, as an
        # unknown record) and `f` to trimesh, whose reading of the rest then fails.
        event("accepted, but trimesh fails")
        return
    event("accepted")
    ours, theirs = vertices[faces], np.asarray(mesh.vertices)[np.asarray(mesh.faces)]
    if b"usemtl" in data:
        # trimesh gathers the faces of each material; ptlab keeps the file's order (as it did
        # before it read OBJ files itself, and as trimesh does without materials).
        ours, theirs = (np.array(sorted(t.reshape(len(t), -1).tolist(), key=repr)) for t in (ours, theirs))
    assert np.array_equal(ours, theirs, equal_nan=True)  # (a NaN vertex is reported later)


@examples(200)
@given(change=mutated_obj())
def test_the_quick_obj_scan_accepts_only_what_the_line_by_line_check_accepts(change):
    _, data = change
    try:
        text = data.decode("utf-8").replace("\r\n", "\n")
    except UnicodeDecodeError:
        return
    records = parse_obj(text.encode())
    plain = records is not None and records.plain
    event("plain" if plain else "looked at line by line")
    if plain:
        check_obj_lines(text)


# --- small scenes made up from scratch -------------------------------------------------------

jitter = st.floats(-0.5, 0.5)
points = st.lists(st.floats(-3, 3), min_size=3, max_size=3)


def near(point: tuple[float, float, float]):
    """Points within half a unit of ``point`` (each coordinate)."""
    return st.tuples(jitter, jitter, jitter).map(lambda d: [p + e for p, e in zip(point, d, strict=True)])


far_points = st.lists(st.sampled_from([0.0, 1e-300, 1e9, 1e11, -1e12, 1e300]), min_size=3, max_size=3)
colours = st.one_of(st.floats(0, 1), st.lists(st.floats(0, 1), min_size=3, max_size=3))
bad_colours = st.sampled_from([-0.1, 1.5, [1, 2], math.nan, "red", [0.5, 0.5, 1e39]])


def made_up_camera(draw, pick) -> dict:
    """A scene's camera for ``made_up_scenes``; ``pick(valid, absurd)`` draws each value."""
    camera = {
        "position": pick(near((0, 0, 10)), far_points),
        "fov": pick(
            st.one_of(st.floats(20, 90), st.sampled_from([1e-6, 179.999])),
            st.sampled_from([0, 180, -5, math.inf, 1e400]),
        ),
        "up": pick(near((0, 1, 0)), st.sampled_from([[0, 0, 0], [0, 1e300, 0], [0, 0, 1]])),
    }
    if draw(st.booleans()):
        camera["look_at"] = pick(near((0, 0, 0)), far_points)
    else:
        camera["direction"] = pick(
            near((0, 0, -1)), st.sampled_from([[0, 0, 0], [1e300, 1e300, 0], [1e-300, 0, 0], [0, 1]])
        )
    return camera


def made_up_materials(draw, pick) -> dict:
    """A scene's materials for ``made_up_scenes``: one to three of any type, a lamp, a board."""
    kinds = {
        "diffuse": lambda: {"albedo": pick(colours, bad_colours)},
        "mirror": lambda: {
            "reflectance": pick(colours, bad_colours),
            "fresnel": pick(st.booleans(), st.sampled_from([0, "yes"])),
        },
        "dielectric": lambda: {
            "eta": pick(st.floats(1, 3), st.sampled_from([0.001, 1e30, 1e-30, 0, -1.5, 101]))
        },
        "microfacet": lambda: {
            "roughness": pick(st.floats(0.05, 1), st.sampled_from([0, -0.5, 2, 1e-3])),
            "f0": pick(
                st.one_of(colours, st.sampled_from(["gold", "silver"])),
                st.sampled_from(["unobtainium", 1.5, []]),
            ),
            "kd": pick(st.just(0.0), bad_colours),
            "sampling": pick(st.sampled_from(["vndf", "hemisphere"]), st.just("best")),
        },
    }
    materials = {}
    for k in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(sorted(kinds)))
        materials[f"m{k}"] = {"type": kind, **kinds[kind]()}
    materials["lamp"] = {
        "type": "diffuse",
        "albedo": 0.5,
        "emission": pick(
            st.one_of(st.floats(0.1, 50), st.just([1, 0, 0])), st.sampled_from([0, 1e-300, 1e16])
        ),
    }
    materials["board"] = {
        "type": "diffuse",
        "albedo": {
            "checkerboard": pick(
                st.lists(colours, min_size=2, max_size=2),
                st.sampled_from([[0.5], [0.5, 2], "red", [[0.5, 0.5], 0.5]]),
            ),
            "scale": pick(st.floats(0.1, 10), st.sampled_from([0, -1, math.inf, "5"])),
        },
    }
    return materials


@st.composite
def made_up_scenes(draw) -> tuple[dict, dict[str, str]]:
    """A scene's data and its OBJ files: a camera, materials of every type, spheres, quads
    and meshes, point lights, a sky, render defaults; valid, but for (often) one value drawn
    from the absurd instead."""
    spots = iter(range(1000))
    broken = draw(st.one_of(st.just(-1), st.integers(0, 40)))  # which value is absurd

    def pick(valid, absurd):
        return draw(absurd if next(spots) == broken else valid)

    camera = made_up_camera(draw, pick)
    materials = made_up_materials(draw, pick)
    names = sorted(materials)
    meshes, files = [], {}
    for k in range(draw(st.integers(1, 3))):
        material = draw(st.sampled_from(names))
        shape = draw(st.sampled_from(["sphere", "quad", "file"]))
        if shape == "quad":
            centre = draw(points)
            corners = [
                [centre[0] + x, centre[1] + y, centre[2]] for x, y in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            ]
            quad = {
                "corners": pick(
                    st.just(corners),
                    st.sampled_from(
                        [corners[:3], [[0, 0, 0]] * 4, "square", [corners[0]] * 3 + [[1e11, 0, 0]]]
                    ),
                )
            }
            if draw(st.booleans()):
                quad["uv"] = pick(
                    st.lists(st.lists(st.floats(-2, 2), min_size=2, max_size=2), min_size=4, max_size=4),
                    st.sampled_from(
                        [
                            [[0, 0]] * 3,
                            [[0, 0, 0]] * 4,
                            [[math.nan, 0]] * 4,
                            "uv",
                            [[0, 0], [1, 0], [1, 1], ["a", 1]],
                        ]
                    ),
                )
            meshes.append({"quad": quad, "material": material})
        elif shape == "sphere":
            sphere = {
                "center": pick(points, far_points),
                "radius": pick(st.floats(0.1, 5), st.sampled_from([1e-200, 1e11, 0, -1])),
                "subdivisions": pick(st.integers(0, 2), st.sampled_from([-1, 8, 1.5])),
            }
            meshes.append({"sphere": sphere, "material": material})
        else:
            # The corners of a polygon (no three in a line) at a place of its own.
            count = draw(st.integers(3, 6))
            centre = draw(points)
            corners = [
                (
                    centre[0] + math.cos(2 * math.pi * i / count),
                    centre[1] + math.sin(2 * math.pi * i / count),
                    centre[2],
                )
                for i in range(count)
            ]
            vertex_lines = [
                " ".join(["v", *map(repr, pick(st.just(corner), far_points))]) for corner in corners
            ]
            face_lines = [
                "f "
                + " ".join(
                    map(
                        str,
                        pick(
                            st.lists(st.integers(1, count), min_size=3, max_size=4, unique=True),
                            st.lists(st.integers(-count - 1, count + 1), max_size=4),
                        ),
                    )
                )
                for _ in range(2)
            ]
            files[f"part{k}.obj"] = "\n".join(vertex_lines + face_lines) + "\n"
            meshes.append({"file": f"part{k}.obj", "material": material})
            if draw(st.booleans()):
                meshes[-1]["scale"] = pick(st.floats(0.1, 10), st.sampled_from([0, -2, 1e300, 1e-300]))
    data = {"camera": camera, "materials": materials, "mesh": meshes}
    if draw(st.booleans()):
        meshes.append(
            {
                "sphere": {"center": pick(points, far_points), "radius": 1.0, "subdivisions": 0},
                "material": "lamp",
            }
        )
    lights = [
        {
            "position": pick(points, far_points),
            "intensity": pick(
                st.one_of(st.floats(0.1, 100), st.lists(st.floats(0, 10), min_size=3, max_size=3)),
                st.sampled_from([-1, 0, [1, -1, 1], "bright", 1e16, [1, 2], math.nan]),
            ),
        }
        for _ in range(draw(st.integers(0, 2)))
    ]
    if lights:
        data["point_light"] = lights
    if draw(st.booleans()):
        data["sky"] = {
            "radiance": pick(
                colours,
                st.sampled_from([-0.1, "blue", [1, 2], math.nan, 1e16, {"r": 1}, [0.1, 0.2, math.inf]]),
            )
        }
    if draw(st.booleans()):
        data["render"] = {
            "res": pick(
                st.sampled_from([4, [4, 3]]), st.sampled_from([0, [4], [4, 3, 2], "4x3", 10**6, 1.5])
            ),
            "max_depth": pick(st.integers(0, 6), st.sampled_from([-1, 1.5, 10**6, "5"])),
        }
    return data, files


@examples(60)
@given(made_up=made_up_scenes())
def test_made_up_scenes_render_or_fail_cleanly(made_up, tmp_path, capsys):
    data, files = made_up
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    for name, text in files.items():
        (folder / name).write_text(text)
    scene = folder / "scene.toml"
    scene.write_text(to_toml(data))
    render_or_fail_cleanly(scene, capsys)


# --- the command line's options --------------------------------------------------------------

option_values = st.one_of(
    st.text(max_size=8),
    number_words,
    st.sampled_from(
        [
            "0",
            "-1",
            "1",
            "2",
            "4x3",
            "4x",
            "x4",
            "0x4",
            "nan",
            "inf",
            "-inf",
            "1e-45",
            "throughput",
            "",
            " 1",
            "1.5",
        ]
    ),
)
RENDER_OPTIONS = [
    "--res",
    "--spp",
    "--seed",
    "--rr",
    "--rr-depth",
    "--max-depth",
    "--workers",
    "--preview-every",
    "--out",
    "--checkpoint",
    "--resume",
    "--integrator",
    "--strategy",
    "--heuristic",
    "--sampling",
    "--backend",
]
#: The most each option may ask for here, so that a valid render stays quick.
CHEAP_LIMITS = {"--spp": 4, "--workers": 1, "--res": 8}


def cheap(option: str, value: str) -> str:
    """``value``, or 1 where it is a number that would make a valid render slow."""
    try:
        number = int(value)
    except ValueError:
        return value
    return "1" if number > CHEAP_LIMITS.get(option, math.inf) else value


@examples(60)
@given(
    options=st.lists(st.tuples(st.sampled_from(RENDER_OPTIONS), option_values), max_size=3),
    out=st.sampled_from(["x.png", "x.exr", "x.jpg", "x.bmp", "x", "nodir/x.png", "folder.png", "."]),
)
def test_render_options_render_or_fail_cleanly(options, out, tmp_path, monkeypatch, capsys):
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    monkeypatch.chdir(folder)
    (folder / "folder.png").mkdir()
    args = ["render", "cornell-box", *TINY, "--out", out]
    for option, value in options:
        args += [option, cheap(option, value)]
    code, err = run_cli(args, capsys)
    written = sorted(p.name for p in folder.iterdir()) != ["folder.png"]
    if code == 0:
        assert err == ""
        assert written
    else:
        assert_one_line_error(code, err)
        assert not written, sorted(folder.iterdir())


bad_budgets = st.one_of(st.floats(max_value=0), st.sampled_from(["nan", "inf", "-inf", "x", ""]))
bad_counts = st.one_of(
    st.integers(max_value=0), st.integers(min_value=1 << 21), st.sampled_from(["x", "1.5", "", "1e3"])
)
bad_converge = st.one_of(
    st.tuples(st.just("--budget"), bad_budgets.map(str)),
    st.tuples(st.just("--target"), st.one_of(st.floats(max_value=0), st.just(math.inf)).map(str)),
    st.tuples(st.just("--reference-spp"), bad_counts.map(str)),
    st.tuples(st.just("--res"), st.sampled_from(["0", "-4", "4x0", "x", "99999x99999"])),
    st.tuples(st.just("--seed"), st.sampled_from(["-1", "1.5", "x"])),
    st.tuples(st.just("--workers"), st.sampled_from(["0", "-1", "9999", "x"])),
    st.tuples(
        st.just("--integrators"), st.sampled_from(["", "path,path", "bdpt", "path:x", "whitted:mis", ","])
    ),
    st.tuples(st.just("--out"), st.sampled_from(["file.txt", "file.txt/sub", "/proc/ptlab"])),
)
bad_bench = st.one_of(
    st.tuples(st.sampled_from(["--res", "--spp"]), bad_counts.map(str)),
    st.tuples(st.just("--workers"), st.sampled_from(["0", "-1", "9999", "x"])),
    st.tuples(st.sampled_from(["--backend", "--estimator"]), st.text(max_size=6)),
)


@examples(40)
@given(bad=st.one_of(bad_converge.map(lambda o: ("converge", o)), bad_bench.map(lambda o: ("bench", o))))
def test_bad_converge_and_bench_options_fail_at_once(bad, tmp_path, monkeypatch, capsys):
    command, (option, value) = bad
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    monkeypatch.chdir(folder)
    monkeypatch.setenv("PTLAB_CACHE", str(folder / "cache"))
    (folder / "file.txt").write_text("")
    cheap = {
        "converge": [
            "converge",
            "cornell-box",
            "--res",
            "4",
            "--budget",
            "0.01",
            "--reference-spp",
            "1",
            "--workers",
            "1",
            "--quiet",
        ],
        "bench": [
            "bench",
            "--res",
            "4",
            "--spp",
            "1",
            "--backend",
            "embree",
            "--estimator",
            "default",
            "--workers",
            "1",
        ],
    }[command]
    if ((command, option) == ("bench", "--backend") and value in ("embree", "numpy")) or (
        (command, option) == ("bench", "--estimator") and value in ("homework", "default")
    ):
        value = "x"
    code, err = run_cli([*cheap, f"{option}={value}"], capsys)
    assert_one_line_error(code, err)
    assert sorted(p.name for p in folder.iterdir()) == ["file.txt"]


# --- regressions: each input once found a crash or a silent misreading -----------------------


def cornell_with(folder: Path, toml: dict | None = None, meshes: dict | None = None) -> Path:
    """A Cornell copy with scene values replaced (``{path: value}``) and mesh files rewritten."""
    scene = cornell_copy(folder)
    data = CORNELL_DATA
    for path, value in (toml or {}).items():
        data = replaced(data, path, value)
    scene.write_text(to_toml(data))
    for name, content in (meshes or {}).items():
        (scene.parent / "meshes" / name).write_bytes(
            content if isinstance(content, bytes) else content.encode()
        )
    return scene


FLOOR = (CORNELL / "meshes" / "floor.obj").read_text()
SPHERE = {"center": [278, 100, 300], "radius": 50, "subdivisions": 1}


def sphere_with(**values) -> dict:
    return {("mesh",): [*CORNELL_DATA["mesh"], {"sphere": {**SPHERE, **values}, "material": "white"}]}


def moved(offset: float, scale: float = 1.0) -> dict:
    """Every mesh of the Cornell box, and its camera, scaled and moved, as file contents."""

    def transform(text: str) -> str:
        return re.sub(
            r"^v (.*)$",
            lambda m: "v " + " ".join(repr(float(x) * scale + offset) for x in m.group(1).split()),
            text,
            flags=re.M,
        )

    return {name: transform((CORNELL / "meshes" / name).read_text()) for name in MESH_NAMES}


REGRESSIONS = {
    # name: (scene values, mesh files, [fragments of the one-line message])
    "material type a list": (
        {("materials", "red", "type"): []},
        None,
        ["materials.red.type", "unknown material type []"],
    ),
    "material type a table": (
        {("materials", "red", "type"): {}},
        None,
        ["materials.red.type", "unknown material type {}"],
    ),
    "vertex with two coordinates": (
        None,
        {"floor.obj": FLOOR.replace("v 552.8 0 0", "v 423 330")},
        ["mesh[0].file", "floor.obj", "line 3", "needs 3 to 7 numbers, got 2"],
    ),
    "vertex beyond float32": (
        None,
        {"floor.obj": FLOOR.replace("v 552.8 0 0", "v 1e39 1e39 1e39")},
        ["mesh[0].file", "floor.obj", "1e+39", "within +-1e+10"],
    ),
    "vertices of mixed sizes": (
        None,
        {"floor.obj": FLOOR.replace("v 552.8 0 0", "v 552.8 0 0 1")},
        ["mesh[0].file", "line 4", "has 3 numbers but line 3's has 4"],
    ),
    "face of two vertices": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "f 1 3")},
        ["mesh[0].file", "line 16", "a face needs at least 3 vertices, got 2"],
    ),
    "face index 0": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "f 0 3 4")},
        ["line 16", "vertex index 0 (OBJ counts vertices from 1)"],
    ),
    "face index past the end": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "f 1 3 99")},
        ["line 16", "vertex 99 does not exist"],
    ),
    "negative index before more vertices": (
        None,
        {"floor.obj": FLOOR.replace("v 0 548.8 0\n", "v 0 548.8 0\nf -1 -2 -3\n")},
        ["line 11", "negative vertex index -3 with vertices after this line"],
    ),
    "face mixing reference forms": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "f 1/1 3 4")},
        ["line 16", "mixes reference forms"],
    ),
    "faces of other forms, as many numbers": (
        None,
        {"floor.obj": FLOOR.replace("f 1 2 3\nf 1 3 4", "f 1/1 2/1 3/1\nf 1 3 4 5 6 7\nvt 0 0")},
        ["line 16", "have as many numbers"],
    ),
    "form feed after the keyword": (
        None,
        {"floor.obj": FLOOR.replace("v 0 0 0", "v\f0 0 0")},
        ["line 4", "write `v` at the very start of the line"],
    ),
    "indented face": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "  f 1 3 4")},
        ["line 16", "write `f` at the very start of the line"],
    ),
    "comment after the data": (
        None,
        {"floor.obj": FLOOR.replace("f 1 3 4", "f 1 3 4 # quad")},
        ["line 16", "a comment after the data"],
    ),
    "CR line ends": (None, {"floor.obj": FLOOR.replace("\n", "\r")}, ["CR alone"]),
    "byte-order mark": (None, {"floor.obj": b"\xef\xbb\xbf" + FLOOR.encode()}, ["byte-order mark"]),
    "NUL bytes": (None, {"floor.obj": b"\x00\x01" * 40}, ["NUL bytes"]),
    "not UTF-8": (
        None,
        {"floor.obj": b"# caf\xe9\n" + FLOOR.encode()},
        ["is not UTF-8 text (byte 0xe9 at offset 5)"],
    ),
    "empty mesh file": (None, {"floor.obj": b""}, ["mesh[0].file", "floor.obj is empty"]),
    "an STL file named .obj": (
        None,
        {
            "floor.obj": b"solid s\nfacet normal 0 0 1\nouter loop\n"
            b"vertex 0 0 0\nendloop\nendfacet\nendsolid\n"
        },
        ["has no vertices or faces", "is it an OBJ file?"],
    ),
    "vertices but no faces": (None, {"floor.obj": "v 0 0 0\nv 1 0 0\nv 1 1 0\n"}, ["has no faces"]),
    "binary garbage named .stl": (
        {("mesh", 0, "file"): "meshes/floor.stl"},
        {"floor.stl": bytes(range(7, 256)) * 2},
        # (the problem's words depend on trimesh's optional
        # character-set detector being installed)
        ["mesh[0].file", "floor.stl"],
    ),
    "a text file as a mesh": (
        {("mesh", 0, "file"): "meshes/floor.txt"},
        {"floor.txt": FLOOR},
        ["mesh[0].file", "unknown mesh format '.txt'"],
    ),
    "PLY face past the vertices": (
        {("mesh", 0, "file"): "meshes/floor.ply"},
        {
            "floor.ply": (
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n1 1 0\n3 0 1 -1\n"
            )
        },
        ["a face refers to vertex -1, but there are 3"],
    ),
    "fov too large for a float": (
        {("camera", "fov"): 10**400},
        None,
        ["camera.fov", "must be a finite number"],
    ),
    "camera beyond float32 rays": (
        {("camera", "position"): [278, 273, -1e11]},
        None,
        ["camera.position", "within +-1e+10"],
    ),
    "camera looking at itself": (
        {("camera",): {"position": [1, 2, 3], "look_at": [1, 2, 3]}},
        None,
        ["camera.look_at", "looks nowhere"],
    ),
    "up along the view": (
        {("camera", "up"): [0, 0, -2]},
        None,
        ["camera.up", "parallel to the viewing direction"],
    ),
    "emission beyond float32": (
        {("materials", "light", "emission"): 1e39},
        None,
        ["materials.light.emission", "at most 1e+15"],
    ),
    "emission too faint for float32": (
        {("materials", "light", "emission"): 1e-300},
        None,
        ["lights' total power", "outside float32's range"],
    ),
    "negative roughness": (
        {("materials", "red"): {"type": "microfacet", "roughness": -0.5}},
        None,
        ["materials.red", "roughness must be in (0, 1]"],
    ),
    "eta beyond float32": (
        {("materials", "red"): {"type": "dielectric", "eta": 1e30}},
        None,
        ["materials.red", "eta must be an index of refraction from 0.01 to 100"],
    ),
    "sphere radius too large for a float": (
        sphere_with(radius=10**400),
        None,
        ["mesh[6].sphere.radius", "finite number"],
    ),
    "sphere too small for trimesh": (
        sphere_with(radius=1e-200),
        None,
        ["mesh[6].sphere.radius", "must be at least 1e-09"],
    ),
    "sphere too small for its place": (
        sphere_with(radius=1e-9, center=[1e9, 1e9, 1e9]),
        None,
        ["mesh[6].sphere.radius", "too small for a sphere centred"],
    ),
    "sphere beyond float32 rays": (
        sphere_with(radius=2e10),
        None,
        ["mesh[6].sphere.radius", "beyond +-1e+10"],
    ),
    "a scene too small for Embree": (None, moved(0, 1e-9), ["the scene is only", "smaller units"]),
    "a scene too far from the origin": (
        {("camera", "position"): [1e7, 1e7, 1e7]},
        moved(1e7),
        ["a vertex lies", "nearer the origin"],
    ),
    "a mesh file name too long": (
        {("mesh", 0, "file"): "x" * 300},
        None,
        ["mesh[0].file", "characters): File name too long"],
    ),
    "materials not a table": ({("materials",): 5}, None, ["materials: must be a table of"]),
    "[mesh] instead of [[mesh]]": (
        {("mesh",): {"file": "meshes/floor.obj", "material": "red"}},
        None,
        ["mesh: must be an array of tables"],
    ),
    "a newline in a material's name": (
        {("materials",): {**CORNELL_DATA["materials"], "a\nb": {"type": "velvet"}}},
        None,
        ["materials.a\\nb.type", "unknown material type"],
    ),
}


@pytest.mark.parametrize("case", sorted(REGRESSIONS))
def test_regression_is_one_line_exit_2_and_no_image(case, tmp_path, capsys):
    toml, meshes, fragments = REGRESSIONS[case]
    scene = cornell_with(tmp_path, toml, meshes)
    err = render_or_fail_cleanly(scene, capsys)
    assert err, err
    assert all(fragment in err for fragment in fragments), err


def test_nested_toml_is_malformed_not_a_recursion_error(tmp_path, capsys):
    scene = cornell_copy(tmp_path)
    scene.write_text(CORNELL_TOML + "deep = " + "[" * 2000 + "]" * 2000 + "\n")
    assert "nested too deeply" in render_or_fail_cleanly(scene, capsys)


@pytest.mark.parametrize(
    "camera",
    [
        {"position": [278, 273, -800], "direction": [0, 0, 1e300]},
        {"position": [278, 273, -800], "direction": [1e-300, 1e-300, 1e-290], "up": [0, 1e300, 0]},
        {"position": [278, 273, -800], "direction": [0, 0, 1], "fov": 1e-6},
        {"position": [278, 273, -800], "direction": [0, 0, 1], "fov": 179.999},
    ],
    ids=["huge direction", "tiny direction, huge up", "narrow fov", "wide fov"],
)
def test_extreme_but_valid_cameras_render(camera, tmp_path, capsys):
    scene = cornell_with(tmp_path, {("camera",): camera})
    assert render_or_fail_cleanly(scene, capsys) in ("", BLACK)  # (a wide fov may see nothing lit)


def test_a_scene_scaled_within_the_bounds_renders_the_same_picture(tmp_path, capsys):
    # Offsets scale with the scene: the Cornell box in units 1e7 times larger (coordinates
    # up to 8e9, just inside MAX_COORDINATE) renders the same image.
    images = []
    for scale in (1.0, 1e7):
        camera = {**CORNELL_DATA["camera"], "position": [278 * scale, 273 * scale, -800 * scale]}
        scene = cornell_with(Path(tempfile.mkdtemp(dir=tmp_path)), {("camera",): camera}, moved(0, scale))
        out = tmp_path / f"{scale:g}.exr"
        code, err = run_cli(
            [
                "render",
                str(scene),
                "--res",
                "16",
                "--spp",
                "4",
                "--workers",
                "1",
                "--quiet",
                "--out",
                str(out),
            ],
            capsys,
        )
        assert code == 0, err
        images.append(read_image(out)[0])
    np.testing.assert_allclose(images[1], images[0], rtol=1e-4, atol=1e-5)


CLI_REGRESSIONS = {
    "roulette too small for float32 uniforms": (["--rr", "1e-45"], ["russian roulette 1e-45", "2^-24"]),
    "preview every NaN seconds": (["--preview-every", "nan"], ["--preview-every"]),
    "checkpoint a folder": (["--checkpoint", "."], [".: is a folder"]),
    "output a folder": (["--out", "folder.png"], ["folder.png: is a folder"]),
    "output where nothing can be written": (["--out", "/proc/ptlab.png"], ["cannot write in /proc"]),
    "checkpoint where nothing can be written": (
        ["--checkpoint", "/proc/ptlab.npz"],
        ["cannot write in /proc"],
    ),
    "output name too long": (["--out", "x" * 300 + ".png"], ["File name too long"]),
    "checkpoint name too long": (["--resume", "x" * 300], ["File name too long"]),
    "checkpoint name with a NUL": (["--checkpoint", "\0"], ["cannot hold a NUL character"]),
}


@pytest.mark.parametrize("case", sorted(CLI_REGRESSIONS))
def test_render_option_regression_is_one_line_exit_2_and_no_output(case, tmp_path, monkeypatch, capsys):
    options, fragments = CLI_REGRESSIONS[case]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder.png").mkdir()
    code, err = run_cli(["render", "cornell-box", *TINY, *options], capsys)
    assert_one_line_error(code, err)
    assert all(fragment in err for fragment in fragments), err
    assert [p.name for p in tmp_path.iterdir()] == ["folder.png"]


SPOILT_FILES = {
    "empty": lambda data: b"",
    "truncated": lambda data: data[:300],
    "a zip of nothing": lambda data: b"PK\x03\x04" + bytes(100),
}
SPOILT_ARRAYS = {
    "identity not a table": lambda arrays: {**arrays, "identity": np.array("[1, 2]")},
    "no passes": lambda arrays: {**arrays, "passes": np.array([], dtype=np.int64)},
    "rays not one number": lambda arrays: {**arrays, "rays": np.array([1, 2])},
    "sums not numbers": lambda arrays: {**arrays, "sums": arrays["sums"].astype(str)},
}


@pytest.mark.parametrize("case", sorted(SPOILT_FILES) + sorted(SPOILT_ARRAYS))
def test_a_spoilt_checkpoint_is_one_line_exit_2(case, tmp_path, capsys):
    checkpoint = tmp_path / "box.npz"
    options = ["render", "cornell-box", *TINY, "--out", str(tmp_path / "box.png")]
    assert run_cli([*options, "--checkpoint", str(checkpoint)], capsys)[0] == 0
    if case in SPOILT_FILES:
        checkpoint.write_bytes(SPOILT_FILES[case](checkpoint.read_bytes()))
    else:
        with np.load(checkpoint) as data:
            arrays = {name: data[name] for name in data.files}
        np.savez(checkpoint, **SPOILT_ARRAYS[case](arrays))
    code, err = run_cli([*options, "--resume", str(checkpoint)], capsys)
    assert_one_line_error(code, err, starts=f"ptlab: error: {checkpoint}: ")


def test_a_seed_beyond_32_bits_is_kept_in_the_exr(tmp_path, capsys):
    out = tmp_path / "seed.exr"
    code, err = run_cli(["render", "cornell-box", *TINY, "--seed", str(2**40), "--out", str(out)], capsys)
    assert code == 0, err
    assert read_image(out)[1]["seed"] == str(2**40)


@pytest.mark.parametrize(
    ("args", "environment", "fragments"),
    [
        (["--budget", "inf"], {}, ["budget inf", "finite"]),
        (["--out", "/proc/ptlab"], {}, ["/proc/ptlab: cannot write in /proc"]),
        ([], {"PTLAB_CACHE": "/proc/ptlab"}, ["reference cache /proc/ptlab", "--no-cache"]),
    ],
    ids=["infinite budget", "unwritable output", "unwritable cache"],
)
def test_converge_regression_fails_before_rendering(
    args, environment, fragments, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    for name, value in environment.items():
        monkeypatch.setenv(name, value)
    code, err = run_cli(
        [
            "converge",
            "cornell-box",
            "--res",
            "4",
            "--budget",
            "0.01",
            "--reference-spp",
            "1",
            "--workers",
            "1",
            "--quiet",
            *args,
        ],
        capsys,
    )
    assert_one_line_error(code, err)
    assert all(fragment in err for fragment in fragments), err
    assert list(tmp_path.iterdir()) == []


# --- the same, as real processes: no traceback reaches the terminal ---------------------------


def ptlab_command() -> list[str]:
    """The installed ``ptlab`` script beside this Python, else ``python -m ptlab.cli``."""
    script = Path(sys.executable).with_name("ptlab")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "ptlab.cli"]


@pytest.mark.subprocess
@pytest.mark.parametrize(
    "command", [[sys.executable, "-m", "ptlab.cli"], ptlab_command()], ids=["python -m ptlab.cli", "ptlab"]
)
def test_processes_report_bad_meshes_without_traceback(command, tmp_path):
    scene = cornell_with(tmp_path, None, {"floor.obj": FLOOR.replace("v 552.8 0 0", "v 1e39 1e39 1e39")})
    out = tmp_path / "out.png"
    env = dict(os.environ, PYTHONWARNINGS="error::RuntimeWarning")
    result = subprocess.run(
        [*command, "render", str(scene), *TINY, "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    assert "Traceback" not in result.stderr, result.stderr
    assert "within +-1e+10" in result.stderr
    assert not out.exists()
