"""OBJ files as ptlab reads them (ptlab/meshes.py): trimesh's triangles and texture
coordinates for any valid file, the quick scan taken by common files, one named line for
malformed ones.

The Hypothesis examples are derandomized and bounded (tests/conftest.py's "fixed" profile);
the malformed files that tests/renderer/test_fuzz.py makes from the Cornell box's meshes are tested
there.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st

from ptlab.errors import SceneError
from ptlab.meshes import parse_obj, read_mesh, read_obj

ROOT = Path(__file__).resolve().parents[2]
SHIPPED_OBJ = sorted((ROOT / "scenes").glob("*/meshes/*.obj"))

#: How a number may be written: Python's repr (exponents included), fixed point, integers.
number_texts = st.one_of(
    st.floats(-1e4, 1e4, allow_nan=False).map(repr),
    st.floats(-1e4, 1e4, allow_nan=False).map(lambda x: f"{x:.6f}"),
    st.floats(1e-30, 1e30).map(lambda x: f"{x:e}"),
    st.integers(-1000, 1000).map(str),
)
separators = st.sampled_from([" ", "  ", "\t", " \t"])


@st.composite
def valid_obj(draw) -> tuple[bytes, bool]:
    """A valid OBJ file (bytes) of random vertices, texture coordinates and polygons, laid out
    in any of the ways the format allows, and whether its faces give texture coordinates."""
    n_vertices = draw(st.integers(3, 12))
    n_texture = draw(st.integers(1, 6))
    v_size = draw(st.sampled_from([3, 3, 4, 6]))
    vt_size = draw(st.sampled_from([2, 2, 1, 3]))
    form = draw(st.sampled_from(["{v}", "{v}/{t}", "{v}//{n}", "{v}/{t}/{n}"]))
    gap = draw(separators)
    lines = ["# made up", "o part"] if draw(st.booleans()) else []
    vertex_numbers = st.lists(number_texts, min_size=v_size, max_size=v_size)
    texture_numbers = st.lists(number_texts, min_size=vt_size, max_size=vt_size)
    lines += ["v " + gap.join(draw(vertex_numbers)) for _ in range(n_vertices)]
    lines += ["vt " + " ".join(draw(texture_numbers)) for _ in range(n_texture)]
    lines.append("vn 0 0 1")
    negative = draw(st.booleans())  # (after every vertex: trimesh counts from the end)
    for _ in range(draw(st.integers(1, 8))):
        size = draw(st.integers(3, 6))
        vertices = draw(st.lists(st.integers(1, n_vertices), min_size=size, max_size=size))
        textures = draw(st.lists(st.integers(1, n_texture), min_size=size, max_size=size))
        references = [
            form.format(v=v - n_vertices - 1 if negative else v, t=t, n=1)
            for v, t in zip(vertices, textures, strict=True)
        ]
        lines.append("f " + gap.join(references) + draw(st.sampled_from(["", " ", "\t"])))
        if draw(st.integers(0, 4)) == 0:
            lines.append(draw(st.sampled_from(["g group", "s 1", "", "# a comment", "  # indented"])))
    text = "\n".join(lines) + draw(st.sampled_from(["", "\n"]))
    if draw(st.integers(0, 3)) == 0:
        text = text.replace("\n", "\r\n")
    return text.encode(), "{t}" in form


def trimesh_reading(data: bytes) -> tuple[np.ndarray, np.ndarray | None]:
    """(T, 3, 3) triangles and (T, 3, 2) texture coordinates (or None) as trimesh reads them,
    each face's triangles one after another.

    (Where every face is a quad, trimesh puts the first triangle of every quad before all the
    second ones; ptlab's reader keeps each face's two together, as trimesh does wherever the
    faces are of several sizes, and as ptlab read such files before.)
    """
    mesh = trimesh.load(trimesh.util.wrap_as_stream(data), file_type="obj", force="mesh", process=False)
    faces = np.asarray(mesh.faces)
    if all(len(line.split()) == 5 for line in data.decode().splitlines() if line.startswith("f ")):
        faces = np.stack(np.split(faces, 2), axis=1).reshape(-1, 3)
    uv = getattr(mesh.visual, "uv", None)
    if uv is not None:
        uv = np.asarray(uv)[faces]
        uv = np.pad(uv[..., :2], ((0, 0), (0, 0), (0, 2 - min(2, uv.shape[-1]))))
    return np.asarray(mesh.vertices)[faces], uv


@given(obj=valid_obj())
def test_valid_obj_files_read_as_trimesh_reads_them(obj):
    # Bit for bit, in trimesh's order: the images of OBJ scenes stay what they were when
    # trimesh read these files.
    data, textured = obj
    vertices, faces, uv = read_obj(data)
    triangles, trimesh_uv = trimesh_reading(data)
    assert np.array_equal(vertices[faces], triangles)
    assert (uv is not None) == textured
    if textured:
        assert np.array_equal(uv, trimesh_uv)


def test_obj_files_written_the_common_way_take_the_quick_scan(tmp_path):
    # The line-by-line check is for files it must explain: a shipped mesh or a trimesh export
    # that took it would still read right, only far slower.
    for path in SHIPPED_OBJ:
        assert parse_obj(path.read_bytes()).plain, path
    sphere = trimesh.creation.icosphere(subdivisions=3)
    assert parse_obj(trimesh.exchange.obj.export_obj(sphere).encode()).plain
    textured = trimesh.creation.box()
    textured.visual = trimesh.visual.TextureVisuals(uv=np.random.default_rng(0).random((8, 2)))
    assert parse_obj(trimesh.exchange.obj.export_obj(textured).encode()).plain


QUAD = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"


@pytest.mark.parametrize(
    ("faces", "problem"),
    [
        ("f 1/1 2/2 3//3\n", "line 9: the face mixes reference forms"),
        ("f 1/1 2/2 3/3 4\n", "line 9: the face mixes reference forms"),
        ("f 1///1 2 3\n", "line 9: '1///1' is not a vertex reference"),
        ("f 1/ 2/ 3/\n", "line 9: '1/' is not a vertex reference"),
        ("f 1 2 +3\n", "line 9: '+3' is not a vertex reference"),
        ("f 1 2 99999999999999999999\n", "line 9: vertex 99999999999999999999 does not exist"),
        ("f 1/1 2/1 3/1 4/1\nf 1 2 3 4 1 2 3 4\n", "line 10: this face (i) and line 9's (i/i)"),
        ("f 1 2 3 # a comment\n", "line 9: a comment after the data"),
        ("f 1 2 3\n\tf 1 2 3\n", "line 10: write `f` at the very start of the line"),
        ("f 1 2 3\nvt 0 0 0 0\n", "line 10: `vt` needs 1 to 3 numbers, got 4"),
        ("f 1 2 3\nv 1 2 3e\n", "line 10: '3e' is not a number"),
    ],
)
def test_malformed_faces_and_records_are_named_by_their_line(faces, problem):
    with pytest.raises(ValueError, match=f"^{re.escape(problem)}"):
        read_obj((QUAD + faces).encode())


def test_texture_coordinates_some_faces_lack_are_none_as_in_trimesh():
    # trimesh keeps such a mesh's triangles and drops its texture coordinates; so does ptlab
    # (a textured material then says the mesh has none). A face's `vt` that does not exist is
    # an error naming its line (test_mesh_files.py).
    _vertices, triangles, uv = read_obj((QUAD + "f 1 2 3\nf 1/1 2/2 3/3\n").encode())
    assert uv is None
    assert len(triangles) == 2


def test_a_vertex_beyond_the_limit_is_an_error_only_where_a_face_uses_it(tmp_path):
    # read_mesh looks at the vertices first and at the triangles' corners only to name the
    # one beyond: a vertex that no face uses is no part of the scene, wherever it lies.
    path = tmp_path / "far.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 -7\nf 1 2 3\n")
    triangles, _ = read_mesh(path, limit=5)
    np.testing.assert_array_equal(triangles, [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 -7\nf 1 2 3\nf 1 2 4\n")
    with pytest.raises(SceneError, match=r"far.obj has a vertex at \[0.0, 0.0, -7.0\]: .* within \+-5$"):
        read_mesh(path, limit=5)


@pytest.mark.subprocess
def test_loading_obj_scenes_imports_no_trimesh(tmp_path):
    # Start-up: trimesh, and SciPy through it, cost a render about a second; OBJ files, with
    # texture coordinates or without, are read without them.
    (tmp_path / "board.obj").write_text(QUAD + "f 1/1 2/2 3/3 4/4\n")
    scene = (
        (ROOT / "scenes" / "cornell-box" / "scene.toml")
        .read_text()
        .replace('"meshes/', f'"{ROOT}/scenes/cornell-box/meshes/')
        + '\n[[mesh]]\nfile = "board.obj"\nmaterial = "board"\n'
        '\n[materials.board]\ntype = "diffuse"\n'
        "albedo = { checkerboard = [[0.8, 0.1, 0], [0.2, 0.6, 0.9]] }\n"
    )
    (tmp_path / "scene.toml").write_text(scene)
    code = (
        "import sys, ptlab\n"
        f"assert ptlab.load_scene({str(tmp_path / 'scene.toml')!r}).uvs is not None\n"
        "print([m for m in ('trimesh', 'scipy') if m in sys.modules])\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


def test_a_big_obj_file_is_read_within_a_bounded_memory_per_triangle():
    # tracemalloc counts NumPy's arrays, so the peak is the same on any machine: about 200
    # bytes a triangle (the file's text is 37), where a reader that kept a Python string per
    # line took 500, and one that gathered every face's numbers into new arrays 310.
    sphere = trimesh.creation.icosphere(subdivisions=6)  # 81 920 triangles
    data = trimesh.exchange.obj.export_obj(sphere).encode()
    tracemalloc.start()
    try:
        _, faces, _ = read_obj(data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(faces) == len(sphere.faces)
    assert peak / len(faces) < 260, f"{peak / len(faces):.0f} bytes a triangle"
