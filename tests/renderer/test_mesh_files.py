"""What a mesh file brings beyond its triangles (``ptlab.meshes``, ``ptlab.textures``, the
shading normals of ``ptlab.scene`` and ``ptlab.integrators.wavefront``): vertex normals and
smooth shading, image textures, materials from OBJ material files and glTF, PLY triangle
strips and PLY files cut short.

Every file here is written by the test (OBJ and PLY text, PLY binary, glTF JSON with its
buffers as data URIs, images through OpenImageIO), so each case is known exactly.
"""

from __future__ import annotations

import base64
import json
import os
import re
import struct
import zlib
from pathlib import Path

import colour
import numpy as np
import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)
import pytest

import ptlab
from ptlab.accel import make_accelerator
from ptlab.camera import Camera
from ptlab.errors import PtlabError, SceneError
from ptlab.integrators.path import scatter
from ptlab.integrators.wavefront import Paths, SurfaceHit, leave_surface, sees, surface_hit
from ptlab.lights import Sky
from ptlab.materials import Diffuse
from ptlab.meshes import read_mesh_data
from ptlab.scene import Scene
from ptlab.textures import ImageTexture

ROOT = Path(__file__).resolve().parents[2]

# -- files written here ------------------------------------------------------------------------


def write_image(path: Path, pixels: np.ndarray) -> Path:
    """Write (H, W, C) ``pixels`` (uint8, uint16 or float32, row 0 the top) with OpenImageIO."""
    kind = {np.dtype(np.uint8): oiio.UINT8, np.dtype(np.uint16): oiio.UINT16}.get(pixels.dtype, oiio.FLOAT)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], kind))
    assert out.write_image(np.ascontiguousarray(pixels))
    out.close()
    return path


def uv_sphere(rings: int = 10, segments: int = 20) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(T, 3, 3) triangles of a unit sphere (latitude-longitude, y up, fronts outward), their
    (T, 3, 2) uv and (T, 3, 3) exact normals (the corners' positions)."""
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, segments + 1)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    points = np.stack([np.sin(t) * np.cos(p), np.cos(t), -np.sin(t) * np.sin(p)], axis=-1)
    uv = np.stack([p / (2 * np.pi), 1 - t / np.pi], axis=-1)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    i, j = i.ravel(), j.ravel()
    quads = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
    corners = [(quads[0], quads[1], quads[2]), (quads[0], quads[2], quads[3])]
    triangles = np.concatenate([np.stack([points[a] for a in c], axis=1) for c in corners])
    uvs = np.concatenate([np.stack([uv[a] for a in c], axis=1) for c in corners])
    area = np.linalg.norm(
        np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
    )
    keep = area > 1e-12  # (the poles' slivers)
    triangles, uvs = triangles[keep], uvs[keep]
    return triangles, uvs, triangles / np.linalg.norm(triangles, axis=2, keepdims=True)


def data_uri(data: bytes, kind: str = "application/octet-stream") -> str:
    return f"data:{kind};base64,{base64.b64encode(data).decode()}"


def gltf(
    path: Path,
    positions,
    indices,
    normals=None,
    uv=None,
    material: dict | None = None,
    node: dict | None = None,
    images: list | None = None,
    mode: int = 4,
) -> Path:
    """Write a glTF file of one primitive (its buffer a data URI) to ``path``."""
    blobs, views, accessors = [], [], []

    def add(array: np.ndarray, component: int, kind: str) -> int:
        offset = sum(len(b) for b in blobs)
        blobs.append(array.tobytes())
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": array.nbytes})
        accessors.append(
            {"bufferView": len(views) - 1, "componentType": component, "count": len(array), "type": kind}
        )
        return len(accessors) - 1

    attributes = {"POSITION": add(np.asarray(positions, np.float32), 5126, "VEC3")}
    if normals is not None:
        attributes["NORMAL"] = add(np.asarray(normals, np.float32), 5126, "VEC3")
    if uv is not None:
        attributes["TEXCOORD_0"] = add(np.asarray(uv, np.float32), 5126, "VEC2")
    primitive = {
        "attributes": attributes,
        "indices": add(np.asarray(indices, np.uint16).ravel(), 5123, "SCALAR"),
    }
    primitive["mode"] = mode
    document = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, **(node or {})}],
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": sum(len(b) for b in blobs), "uri": data_uri(b"".join(blobs))}],
    }
    if material is not None:
        primitive["material"] = 0
        document["materials"] = [material]
    if images:
        document["images"] = images
        document["textures"] = [{"source": k} for k in range(len(images))]
    path.write_text(json.dumps(document))
    return path


QUAD = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
TILTED = np.array([[0.6, 0, 0.8], [0, 0.6, 0.8], [-0.6, 0, 0.8], [0, -0.6, 0.8]])

# -- vertex normals, format by format ----------------------------------------------------------


def test_obj_vertex_normals_are_read_at_every_corner_of_every_triangle(tmp_path):
    # A quad (cut into (1, 2, 3) and (3, 4, 1)) and a triangle, in both forms that give normals.
    text = (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "vn 0.6 0 0.8\nvn 0 0.6 0.8\nvn -0.6 0 0.8\nvn 0 -0.6 0.8\n"
        "f 1/1/1 2/2/2 3/3/3 4/4/4\n"
        "f 1//4 2//1 4//2\n"
    )
    (tmp_path / "m.obj").write_text(text)
    data = read_mesh_data(tmp_path / "m.obj")
    expected = TILTED[[[0, 1, 2], [2, 3, 0], [3, 0, 1]]]
    np.testing.assert_allclose(data.normals, expected, atol=1e-12)
    assert data.unused == []


@pytest.mark.parametrize(
    ("faces", "problem"),
    [("f 1//1 2//2 3//3\nf 1 3 4\n", "some faces give none"), ("f 1//1 2//2 3//9\n", "does not exist")],
)
def test_obj_normals_that_cannot_be_used_are_named_not_made_up(tmp_path, faces, problem):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\n" + faces)
    data = read_mesh_data(path)
    assert data.normals is None
    assert any("vertex normals" in u and problem in u for u in data.unused), data.unused


def test_obj_smoothing_groups_without_normals_are_named(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\ns 1\nf 1 2 3\n")
    data = read_mesh_data(path)
    assert data.normals is None
    assert any("smoothing groups" in u for u in data.unused)


PLY_HEADER = (
    "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\n{normals}element face 2\nproperty list uchar int vertex_indices\nend_header\n"
)
NORMAL_PROPERTIES = "property float nx\nproperty float ny\nproperty float nz\n"


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
@pytest.mark.parametrize("with_normals", [True, False])
def test_ply_normals_are_read_only_where_the_file_has_them(tmp_path, encoding, with_normals):
    header = PLY_HEADER.format(format=encoding, normals=NORMAL_PROPERTIES if with_normals else "")
    rows = [np.concatenate([q, n]) if with_normals else q for q, n in zip(QUAD, TILTED, strict=True)]
    faces = [(0, 1, 2), (0, 2, 3)]
    if encoding == "ascii":
        body = "".join(" ".join(map(str, r)) + "\n" for r in rows) + "".join(
            f"3 {a} {b} {c}\n" for a, b, c in faces
        )
        data = (header + body).encode()
    else:
        body = b"".join(np.asarray(r, "<f4").tobytes() for r in rows)
        body += b"".join(struct.pack("<B3i", 3, *f) for f in faces)
        data = header.encode() + body
    (tmp_path / "m.ply").write_bytes(data)
    mesh = read_mesh_data(tmp_path / "m.ply")
    if with_normals:
        np.testing.assert_allclose(mesh.normals, TILTED[[[0, 1, 2], [0, 2, 3]]], atol=1e-6)
    else:  # (trimesh would compute some: ptlab must not use those)
        assert mesh.normals is None


def test_gltf_normals_and_positions_follow_the_node_transform(tmp_path):
    # Rotated 90 degrees about z (the quaternion's w = cos 45, z = sin 45) and moved by (5, 0, 0).
    s = np.sqrt(0.5)
    node = {"rotation": [0, 0, s, s], "translation": [5, 0, 0]}
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], normals=TILTED, node=node)
    mesh = read_mesh_data(tmp_path / "m.gltf")
    rotate = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    np.testing.assert_allclose(
        mesh.triangles, (QUAD @ rotate.T + [5, 0, 0])[[[0, 1, 2], [0, 2, 3]]], atol=1e-6
    )
    np.testing.assert_allclose(mesh.normals, (TILTED @ rotate.T)[[[0, 1, 2], [0, 2, 3]]], atol=1e-6)


def test_gltf_without_normals_has_none_and_a_mirror_keeps_the_front_face(tmp_path):
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], node={"scale": [1, 1, -1]})
    mesh = read_mesh_data(tmp_path / "m.gltf")
    assert mesh.normals is None
    # Mirrored in z, the quad's front (+z, counter-clockwise seen from +z) must face -z.
    front = np.cross(mesh.triangles[:, 1] - mesh.triangles[:, 0], mesh.triangles[:, 2] - mesh.triangles[:, 0])
    assert (front[:, 2] < 0).all()


@pytest.mark.parametrize("mode", [5, 6])
def test_gltf_strips_and_fans_give_every_triangle_facing_one_way(tmp_path, mode):
    # A strip 0 1 2 3 and a fan 0 1 2 3 over the unit square's corners, all facing +z.
    order = [1, 2, 0, 3] if mode == 5 else [0, 1, 2, 3]
    gltf(tmp_path / "m.gltf", QUAD, order, mode=mode)
    mesh = read_mesh_data(tmp_path / "m.gltf")
    front = np.cross(mesh.triangles[:, 1] - mesh.triangles[:, 0], mesh.triangles[:, 2] - mesh.triangles[:, 0])
    assert len(mesh.triangles) == 2
    assert (front[:, 2] > 0).all()


def test_stl_and_off_files_have_no_normals(tmp_path):
    (tmp_path / "m.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert read_mesh_data(tmp_path / "m.off").normals is None


# -- smooth shading -----------------------------------------------------------------------------


def sphere_scene(smooth: bool, texture=None) -> Scene:
    triangles, uv, normals = uv_sphere()
    material = Diffuse(texture if texture is not None else 0.7)
    camera = Camera.look_at((0, 0.5, 3), (0, 0, 0), fov_y=45)
    return Scene(
        triangles,
        np.zeros(len(triangles), np.intp),
        [material],
        camera,
        uvs=uv,
        normals=normals if smooth else None,
        sky=Sky(np.ones(3)),
    )


def camera_hits(scene: Scene, backend: str = "embree") -> SurfaceHit:
    """The vertices where a fan of rays from the camera meets the scene."""
    rng = np.random.default_rng(3)
    count = 4000
    target = rng.uniform(-0.7, 0.7, (count, 3)) * [1, 1, 0]
    origins = np.tile(scene.camera.position, (count, 1)).astype(np.float32)
    dirs = target - scene.camera.position
    dirs = (dirs / np.linalg.norm(dirs, axis=1, keepdims=True)).astype(np.float32)
    paths = Paths.camera(origins, dirs, np.arange(count), np.arange(count, dtype=np.uint64))
    accel = make_accelerator(scene.triangles, backend)
    return surface_hit(scene, paths, accel.intersect(paths.origins, paths.dirs))


def angles_to_sphere_normal(hit: SurfaceHit, normals: np.ndarray) -> np.ndarray:
    exact = hit.p / np.linalg.norm(hit.p, axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.sum(normals * exact, axis=1), -1, 1)))


def test_a_smooth_spheres_shading_normal_is_closer_to_the_true_normal_than_the_flat_one():
    flat_hit, smooth_hit = camera_hits(sphere_scene(False)), camera_hits(sphere_scene(True))
    flat = angles_to_sphere_normal(flat_hit, flat_hit.n)
    smooth = angles_to_sphere_normal(smooth_hit, smooth_hit.n)
    # 10 x 20 facets are up to 18 degrees apart: flat normals err by several degrees, the
    # interpolated ones by a fraction (a wrong interpolation, or the face normal, would not).
    assert flat.mean() > 3
    assert smooth.mean() < 0.15 * flat.mean()
    assert smooth.max() < 0.5 * flat.max()
    # The geometric normal is still the face's, and every normal faces the camera's ray.
    assert np.allclose(smooth_hit.ng, flat_hit.n, atol=1e-6)
    assert (np.sum(smooth_hit.n * smooth_hit.wo, axis=1) >= 0).all()
    assert flat_hit.ng is flat_hit.n
    assert not flat_hit.smooth


def test_the_normals_view_shows_the_shading_normal():
    scene = sphere_scene(True)
    image = ptlab.render(scene, spp=1, res=24, seed=0, integrator="normals", workers=1)
    flat = ptlab.render(sphere_scene(False), spp=1, res=24, seed=0, integrator="normals", workers=1)
    # Flat facets show as patches of one colour; smooth shading varies from pixel to pixel.
    inside = image.sum(axis=2) > 0
    assert len(np.unique(image[inside].round(4), axis=0)) > 2 * len(np.unique(flat[inside].round(4), axis=0))


def test_a_textured_smooth_mesh_renders_alike_on_both_backends():
    texture = ImageTexture.from_array(
        (np.indices((8, 16)).sum(axis=0) % 2 * 200 + 30).astype(np.uint8), "grid"
    )
    scene = sphere_scene(True, texture)
    images = {
        backend: ptlab.render(scene, spp=4, res=32, seed=2, backend=backend, workers=1)
        for backend in ("embree", "numpy")
    }
    # The two backends' barycentrics differ by float32 rounding: the same paths, values equal
    # to a few ulps (a path that the rounding sends elsewhere would show as one far pixel).
    difference = np.abs(images["embree"] - images["numpy"])
    assert np.quantile(difference, 0.99) < 1e-4
    assert abs(images["embree"].mean() - images["numpy"].mean()) < 1e-3 * images["numpy"].mean()
    normals = {
        backend: ptlab.render(scene, spp=1, res=32, seed=2, backend=backend, integrator="normals", workers=1)
        for backend in ("embree", "numpy")
    }
    assert np.quantile(np.abs(normals["embree"] - normals["numpy"]), 0.99) < 1e-4


def test_corner_normals_against_the_winding_turn_the_triangle_to_them():
    # One triangle wound toward -z, with normals toward +z: its front becomes +z (the normals
    # decide, as in pbrt-v4 and Mitsuba 3), and its uv turn with its corners.
    triangle = np.array([[[0, 0, 0], [0, 1, 0], [1, 0, 0]]], dtype=float)
    uv = np.array([[[0, 0], [0, 1], [1, 0]]], dtype=float)
    normals = np.tile([0.0, 0.0, 1.0], (1, 3, 1))
    scene = Scene(triangle, [0], [Diffuse()], Camera.look_at((0, 0, 1), (0, 0, 0)), uvs=uv, normals=normals)
    assert scene.face_normals[0, 2] == pytest.approx(1)
    assert {tuple(v) for v in scene.triangles[0]} == {tuple(v) for v in triangle[0]}
    for corner in range(3):  # (each corner keeps its uv)
        k = [tuple(v) for v in triangle[0]].index(tuple(scene.triangles[0, corner]))
        assert np.array_equal(scene.uvs[0, corner], uv[0, k])


def test_a_chapters_surface_hit_has_one_normal_for_both():
    count = 3
    n = np.tile(np.array([[0, 0, 1]], np.float32), (count, 1))
    p = np.zeros((count, 3), np.float32)
    hit = SurfaceHit(
        prim=np.zeros(count, np.intp),
        p=p,
        n=n,
        wo=n,
        front=np.ones(count, bool),
        offset=np.full(count, 1e-3, np.float32),
        materials=[(None, Diffuse())],
        delta=np.zeros(count, bool),
        t=np.ones(count, np.float32),
        paths=Paths.camera(p, -n, np.arange(count), np.arange(count, dtype=np.uint64)),
    )
    assert hit.ng is hit.n
    assert not hit.smooth
    assert (leave_surface(hit.p, hit.n, hit.offset, hit.n)[:, 2] > 0).all()


def smooth_quad_hit(tilt: float, count: int = 1) -> tuple[Scene, SurfaceHit]:
    """``count`` camera rays straight down onto the middle of a big quad z = 0 whose corner
    normals all lean ``tilt`` toward +x."""
    corners = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], dtype=float)
    triangles = corners[[[0, 1, 2], [0, 2, 3]]]
    normal = np.array([np.sin(tilt), 0, np.cos(tilt)])
    scene = Scene(
        triangles,
        [0, 0],
        [Diffuse()],
        Camera.look_at((0, 0, 3), (0, 0, 0)),
        normals=np.tile(normal, (2, 3, 1)),
    )
    origins = np.tile(np.array([[0.1, 0.2, 3]], np.float32), (count, 1))
    origins[:, 0] += np.linspace(0, 1, count, dtype=np.float32)
    dirs = np.tile(np.array([[0, 0, -1]], np.float32), (count, 1))
    paths = Paths.camera(origins, dirs, np.arange(count), np.arange(count, dtype=np.uint64))
    return scene, surface_hit(
        scene, paths, make_accelerator(scene.triangles).intersect(paths.origins, paths.dirs)
    )


def test_new_rays_leave_by_the_geometric_normal_on_the_side_they_go_to():
    # The shading normal leans 60 degrees, so that a fair share of the directions drawn
    # around it go below the surface (z < 0): those must start below it, the others above.
    scene, hit = smooth_quad_hit(np.radians(60), count=500)
    np.testing.assert_allclose(hit.ng, np.tile([0, 0, 1], (500, 1)), atol=1e-6)
    np.testing.assert_allclose(hit.n[0], [np.sqrt(0.75), 0, 0.5], atol=1e-6)
    u = np.random.default_rng(4).random((500, 2), dtype=np.float32)
    paths = scatter(scene, hit, u, np.ones(500, bool))
    below = paths.dirs[:, 2] < 0
    assert 0.05 < below.mean() < 0.5
    assert ((paths.origins[:, 2] < 0) == below).all()
    # A light point below the surface, above the shading normal: the shadow ray starts below
    # too and reaches it (from above the surface, the quad itself would block it).
    light = np.array([[5.0, 0.2, -1.0]], np.float32)
    assert np.dot(light[0] - hit.p[0], hit.n[0]) > 0
    assert sees(make_accelerator(scene.triangles), hit, np.arange(1), light)[0]


# -- image textures -----------------------------------------------------------------------------

#: A 2 x 2 image: red, green on the top row; blue, white below.
TEXELS = np.array([[[255, 0, 0], [0, 255, 0]], [[0, 0, 255], [255, 255, 255]]], np.uint8)
RED, GREEN, BLUE, WHITE = np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], np.ones(3)


def test_texel_centres_give_their_colour_with_v_up():
    texture = ImageTexture.from_array(TEXELS, "2x2")
    uv = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25]])
    np.testing.assert_allclose(texture(uv), [RED, GREEN, BLUE, WHITE], atol=1e-6)


def test_lookups_blend_bilinearly_and_repeat_past_the_edges():
    texture = ImageTexture.from_array(TEXELS, "2x2")
    uv = np.array(
        [
            [0.5, 0.75],  # halfway between red and green
            [0.5, 0.5],  # the four texels' mean
            [0.375, 0.75],  # a quarter of the way from red to green
            [0.0, 0.75],  # the left edge: halfway between green (repeated) and red
            [1.25, 1.75],  # one period on: red
            [-0.75, -0.25],  # one period back: red
        ]
    )
    expected = [
        (RED + GREEN) / 2,
        (RED + GREEN + BLUE + WHITE) / 4,
        0.75 * RED + 0.25 * GREEN,
        (RED + GREEN) / 2,
        RED,
        RED,
    ]
    np.testing.assert_allclose(texture(uv), expected, atol=1e-6)
    assert texture(uv).dtype == np.float32


def test_8_and_16_bit_images_are_decoded_from_srgb_float_images_are_not(tmp_path):
    levels = np.arange(256, dtype=np.uint8)
    image = np.repeat(levels[None, :, None], 3, axis=2)  # one row, every 8-bit level
    uv = np.stack([(np.arange(256) + 0.5) / 256, np.full(256, 0.5)], axis=1)
    for path, pixels, scale in [
        (tmp_path / "levels.png", image, 255),
        (tmp_path / "levels16.png", image.astype(np.uint16) * 257, 65535),
    ]:
        values = ImageTexture(write_image(path, pixels))(uv)[:, 0]
        np.testing.assert_allclose(values, colour.models.eotf_sRGB(pixels[0, :, 0] / scale), atol=2e-6)
    linear = (np.arange(256, dtype=np.float32) / 255)[None, :, None].repeat(3, axis=2)
    values = ImageTexture(write_image(tmp_path / "linear.exr", linear))(uv)[:, 0]
    np.testing.assert_allclose(values, linear[0, :, 0], rtol=1e-6)


def test_grey_and_rgba_images_are_colours(tmp_path):
    grey = write_image(tmp_path / "grey.png", np.full((2, 2, 1), 128, np.uint8))
    rgba = write_image(
        tmp_path / "rgba.png", np.concatenate([TEXELS, np.full((2, 2, 1), 7, np.uint8)], axis=2)
    )
    half = colour.models.eotf_sRGB(128 / 255)
    np.testing.assert_allclose(ImageTexture(grey)(np.array([[0.3, 0.3]])), [[half] * 3], atol=1e-6)
    np.testing.assert_allclose(ImageTexture(rgba)(np.array([[0.25, 0.75]])), [RED], atol=1e-6)


def test_a_tint_multiplies_and_the_repr_tells_images_apart(tmp_path):
    texture = ImageTexture.from_array(TEXELS, "2x2")
    tinted = texture.tinted([0.5, 1, 0.25])
    np.testing.assert_allclose(tinted(np.array([[0.75, 0.25]])), [[0.5, 1, 0.25]], atol=1e-6)
    other = ImageTexture.from_array(TEXELS[::-1], "2x2")
    assert repr(texture) != repr(other) != repr(tinted)


def test_an_image_that_cannot_be_read_is_one_line_naming_it(tmp_path):
    with pytest.raises(PtlabError, match=r"missing\.png: not found"):
        ImageTexture(tmp_path / "missing.png")
    (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n not really")
    with pytest.raises(PtlabError, match=r"broken\.png") as error:
        ImageTexture(tmp_path / "broken.png")
    assert "\n" not in str(error.value)


# -- materials in mesh files ---------------------------------------------------------------------

MTL = """# two materials
newmtl red
Kd 0.8 0.1 0.05
Ks 0.5 0.5 0.5
Ns 30
illum 2
newmtl wood
Kd 1 1 1
map_Kd -s 2 2 1 textures/wood.png
map_Bump bump.png
d 1
"""


def test_obj_materials_are_given_per_face_from_the_material_file(tmp_path):
    (tmp_path / "m.mtl").write_text(MTL)
    obj = (
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
        "f 1 2 5\n"  # before any usemtl: none
        "usemtl wood\nf 1 2 3 4\n"  # a quad: two triangles
        "usemtl red\nf 2 3 5\n"
        "usemtl wood\nf 3 4 5\n"
        "usemtl nowhere\nf 1 4 5\n"
    )
    (tmp_path / "m.obj").write_text(obj)
    data = read_mesh_data(tmp_path / "m.obj")
    names = [m.name for m in data.materials]
    assert names == ["wood", "red"]
    assert data.material_ids.tolist() == [-1, 0, 0, 1, 0, -1]
    red, wood = data.materials[1], data.materials[0]
    np.testing.assert_array_equal(red.albedo, [0.8, 0.1, 0.05])
    assert red.texture is None
    assert wood.texture == tmp_path / "textures" / "wood.png"
    assert wood.defined_in == "m.mtl, line 7"
    for phrase in (
        "specular colour (Ks)",
        "specular exponent (Ns)",
        "bump map (map_Bump)",
        "-s 2 2 1",
        "nowhere",
    ):
        assert any(phrase in u for u in data.unused), (phrase, data.unused)
    # Quiet: what a Lambertian surface could not show anyway (illum), or changes nothing (d 1).
    assert not any("illum" in u or "(d)" in u for u in data.unused)


def test_a_missing_material_file_is_named_and_the_faces_have_none(tmp_path):
    (tmp_path / "m.obj").write_text("mtllib gone.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n")
    data = read_mesh_data(tmp_path / "m.obj")
    assert data.materials == []
    assert data.material_ids.tolist() == [-1]
    assert f"material library 'gone.mtl' (not found in {tmp_path})" in data.unused
    # A name with a space that is not there is one name, not two.
    (tmp_path / "m.obj").write_text(
        "mtllib my materials.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"
    )
    said = [u for u in read_mesh_data(tmp_path / "m.obj").unused if u.startswith("material library")]
    assert said == [f"material library 'my materials.mtl' (not found in {tmp_path})"]


def test_blenders_material_file_is_named_for_what_shows_and_no_more(tmp_path):
    # Blender writes Ni (an index of refraction) for every material: it changes nothing on an
    # opaque one, and is named only where the material lets light through.
    (tmp_path / "m.mtl").write_text(
        "newmtl X\nNs 250\nKa 1 1 1\nKd .8 .8 .8\nKs .5 .5 .5\nKe 0 0 0\nNi 1.45\nd 1\nillum 2\n"
        "newmtl Glassy\nKd .8 .8 .8\nNi 1.5\nd 0.5\n"
    )
    (tmp_path / "m.obj").write_text(
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl X\nf 1 2 3\nusemtl Glassy\nf 1 3 4\n"
    )
    from ptlab.meshes.mtl import read_mtl

    (_, opaque_unused), (_, glassy_unused) = read_mtl(tmp_path / "m.mtl")
    assert opaque_unused == ["specular exponent (Ns)", "specular colour (Ks)"]
    assert "index of refraction (Ni)" in glassy_unused
    assert "transparency (d)" in glassy_unused


def test_a_malformed_material_file_names_its_line(tmp_path):
    (tmp_path / "m.mtl").write_text("newmtl a\nKd red\n")
    (tmp_path / "m.obj").write_text("mtllib m.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError, match=r"m.obj: m.mtl, line 2: `Kd` needs 1 or 3 numbers"):
        read_mesh_data(tmp_path / "m.obj")


def png_bytes(tmp_path: Path, pixels: np.ndarray) -> bytes:
    return write_image(tmp_path / "embedded.png", pixels).read_bytes()


def test_gltf_base_colour_factor_and_embedded_texture(tmp_path):
    pixels = np.array([[[10, 20, 30], [40, 50, 60]]], np.uint8)
    material = {
        "name": "painted",
        "pbrMetallicRoughness": {
            "baseColorFactor": [0.725, 0.71, 0.68, 1.0],
            "baseColorTexture": {"index": 0},
            "metallicFactor": 0.0,
            "roughnessFactor": 0.5,
        },
        "normalTexture": {"index": 0},
    }
    images = [{"uri": data_uri(png_bytes(tmp_path, pixels), "image/png")}]
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], uv=QUAD[:, :2], material=material, images=images)
    data = read_mesh_data(tmp_path / "m.gltf")
    (found,) = data.materials
    assert found.name == "painted"
    # Exactly the file's numbers (trimesh's reader rounds them to 8 bits: 0.7254902).
    assert found.albedo.tolist() == [0.725, 0.71, 0.68]
    np.testing.assert_array_equal(found.texture, pixels)
    assert data.material_ids.tolist() == [0, 0]
    # glTF's uv origin is the image's top-left: (0, 0) in the file is (0, 1) in ptlab's.
    np.testing.assert_allclose(data.uv[0], [[0, 1], [1, 1], [1, 0]])
    assert "glTF metallic-roughness" in data.unused
    assert "normal map (normalTexture)" in data.unused


def test_gltf_texture_files_are_found_beside_it(tmp_path):
    material = {
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 1}
    }
    gltf(
        tmp_path / "m.gltf",
        QUAD,
        [[0, 1, 2]],
        uv=QUAD[:, :2],
        material=material,
        images=[{"uri": "my%20wood.png"}],
    )
    (found,) = read_mesh_data(tmp_path / "m.gltf").materials
    assert found.texture == tmp_path / "my wood.png"
    assert found.albedo.tolist() == [1.0, 1.0, 1.0]  # (glTF's default factor)


def test_a_gltf_image_lands_where_the_uv_says(tmp_path):
    # The file's uv (0.25, 0.25) is a quarter of the way in from the image's top-left corner:
    # the top-left texel of a 2 x 2 image, red; ptlab's lookup must give red there.
    images = [{"uri": data_uri(png_bytes(tmp_path, TEXELS), "image/png")}]
    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0}}
    uv = np.full((4, 2), 0.25)
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2]], uv=uv, material=material, images=images)
    data = read_mesh_data(tmp_path / "m.gltf")
    texture = ImageTexture.from_array(data.materials[0].texture)
    np.testing.assert_allclose(texture(data.uv[0]), [RED] * 3, atol=1e-6)


def test_the_spot_model_brings_normals_a_texture_and_nothing_else(tmp_path):
    data = read_mesh_data(ROOT / "scenes" / "spot" / "meshes" / "spot.obj")
    assert data.normals is not None
    assert data.uv is not None
    (spot,) = data.materials
    assert data.unused == []
    assert (data.material_ids == 0).all()
    texture = ImageTexture(spot.texture)
    assert (texture.width, texture.height) == (256, 256)


# -- PLY strips and PLY files cut short ---------------------------------------------------------

STRIP_HEADER = (
    "ply\nformat {format} 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
    "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
)
#: Two strips over a row of points (x, y): 0 1 2 3 (two triangles), then -1, then 3 2 4 5... (a
#: second strip 2 3 4 5: two more), all facing +z.
STRIP_POINTS = np.array([[0, 1, 0], [0, 0, 0], [1, 1, 0], [1, 0, 0], [2, 1, 0], [2, 0, 0]], dtype=float)
STRIPS = [0, 1, 2, 3, -1, 2, 3, 4, 5]


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_ply_triangle_strips_are_read(tmp_path, encoding):
    header = STRIP_HEADER.format(format=encoding)
    if encoding == "ascii":
        body = "".join(" ".join(map(str, p)) + "\n" for p in STRIP_POINTS)
        data = (header + body + f"{len(STRIPS)} " + " ".join(map(str, STRIPS)) + "\n").encode()
    else:
        data = (
            header.encode()
            + STRIP_POINTS.astype("<f4").tobytes()
            + np.array([len(STRIPS), *STRIPS], "<i4").tobytes()
        )
    (tmp_path / "strips.ply").write_bytes(data)
    triangles = read_mesh_data(tmp_path / "strips.ply").triangles
    assert len(triangles) == 4
    front = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    assert (front[:, 2] < 0).all() or (front[:, 2] > 0).all()  # (all facing one way)
    np.testing.assert_allclose(np.abs(front[:, 2]), 1)  # (each a half square: none lost)


def test_a_ply_file_cut_short_says_so_in_one_line(tmp_path):
    header = PLY_HEADER.format(format="ascii", normals="")
    full = header + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"
    (tmp_path / "text.ply").write_text(full[: full.rindex("3 0 2 3")])  # (trimesh drops the face)
    binary = (
        PLY_HEADER.format(format="binary_little_endian", normals="").encode() + QUAD.astype("<f4").tobytes()
    )
    (tmp_path / "binary.ply").write_bytes(binary + struct.pack("<B3i", 3, 0, 1, 2))
    (tmp_path / "header.ply").write_bytes(binary[:60])
    for name in ("text.ply", "binary.ply", "header.ply"):
        with pytest.raises(SceneError, match=rf"{name}: truncated") as error:
            read_mesh_data(tmp_path / name)
        assert "\n" not in str(error.value)
        assert "list index" not in str(error.value)
    for name in ("text.ply", "binary.ply"):
        with pytest.raises(SceneError, match="announces 4 `vertex` and 2 `face` elements"):
            read_mesh_data(tmp_path / name)


def test_a_checkpoint_knows_a_scenes_normals():
    # Resuming a smooth render with flat normals (or others) would mix two pictures: the
    # checkpoint's fingerprint of the scene includes the normals, where there are any.
    from dataclasses import replace

    from ptlab.rendering.checkpoint import scene_digest

    smooth = sphere_scene(smooth=True)
    assert smooth.normals is not None
    flat = replace(smooth, normals=None)
    bent = replace(smooth, normals=-smooth.normals)
    assert len({scene_digest(smooth), scene_digest(flat), scene_digest(bent)}) == 3


def test_the_command_says_what_a_mesh_brought_in_one_line(tmp_path, capsys):
    # The spot cow's own material, overridden by the scene's: one "ptlab: warning:" line,
    # not Python's two lines pointing into ptlab's code.
    import shutil

    from ptlab.cli import main
    from ptlab.scene_file import builtin_scenes_dir

    folder = shutil.copytree(builtin_scenes_dir() / "spot", tmp_path / "spot")
    toml = folder / "scene.toml"
    toml.write_text(toml.read_text() + 'material = "floor"\n')
    out = tmp_path / "spot.png"
    assert (
        main(
            [
                "render",
                str(folder),
                "--res",
                "16",
                "--spp",
                "1",
                "--workers",
                "1",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith("ptlab: warning: ")
    assert "ignores its materials" in lines[0]
    assert out.exists()


# -- glTF files that are malformed, or valid in ways first read wrong (issue 39 red team, part G) --


def gltf_document(tmp_path: Path) -> dict:
    """The JSON of a glTF quad: accessors 0 POSITION, 1 NORMAL, 2 TEXCOORD_0, 3 indices
    (unsigned shorts), buffer views 0 to 3 likewise, material 0, node 0."""
    path = gltf(
        tmp_path / "m.gltf",
        QUAD,
        [[0, 1, 2], [0, 2, 3]],
        normals=TILTED,
        uv=QUAD[:, :2],
        material={"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}},
    )
    return json.loads(path.read_text())


def read_gltf_document(tmp_path: Path, document: dict):
    """``read_mesh_data`` of ``document`` written as a ``.gltf`` file."""
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps(document))
    return read_mesh_data(path)


def _primitive(d: dict) -> dict:
    return d["meshes"][0]["primitives"][0]


def _sparse(d: dict, indices: dict, count: int = 1) -> None:
    d["accessors"][0]["sparse"] = {"count": count, "indices": indices, "values": {"bufferView": 0}}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["nodes"][0].update(children=1), "nodes[0].children is 1, not a list"),
        (lambda d: d["meshes"][0].update(primitives=5), "meshes[0].primitives is 5, not a list"),
        (lambda d: d.update(asset=5), "asset is 5, not an object"),
        (lambda d: d.update(nodes={"mesh": 0}), 'nodes is {"mesh": 0}, not a list'),
        (lambda d: d.update(extensionsUsed=5), "extensionsUsed is 5, not a list"),
        (lambda d: d["buffers"][0].update(uri=5), "buffers[0].uri is 5, not a string"),
        (lambda d: d["nodes"][0].update(rotation=["a", "b", "c", "d"]), 'nodes[0].rotation[0] is "a", not a'),
        (lambda d: d["nodes"][0].update(matrix=[1, 0, 0]), "nodes[0].matrix has 3 numbers, not 16"),
        (lambda d: d["nodes"][0].update(translation=[1, 2]), "nodes[0].translation has 2 numbers, not 3"),
        (
            lambda d: _primitive(d)["attributes"].update(POSITION=True),
            "attributes.POSITION is true, not an integer",
        ),
        (lambda d: d["accessors"][2].update(type="SCALAR"), "TEXCOORD_0 is accessors[2], of type SCALAR"),
        (
            lambda d: d["accessors"][0].update(type="VEC2"),
            "POSITION is accessors[0], of type VEC2: it must be VEC3",
        ),
        (lambda d: d["accessors"][1].update(type="SCALAR"), "NORMAL is accessors[1], of type SCALAR"),
        (
            lambda d: d["accessors"][3].update(componentType=5126),
            "indices is accessors[3], of componentType 5126",
        ),
        (
            lambda d: d["accessors"][0].update(byteOffset=-12),
            "accessors[0].byteOffset is -12, not an integer of at",
        ),
        (
            lambda d: d["accessors"][0].update(count=-1),
            "accessors[0].count is -1, not an integer of at least 0",
        ),
        (lambda d: d["bufferViews"][0].update(byteStride=-12), "bufferViews[0].byteStride is -12"),
        (
            lambda d: d["materials"][0]["pbrMetallicRoughness"].update(
                baseColorTexture={"index": 0, "texCoord": "one"}
            ),
            'baseColorTexture.texCoord is "one", not an integer',
        ),
        (
            lambda d: d["buffers"][0].update(uri="data:application/octet-stream;base64,AAA"),
            "buffers[0].uri is a data URI that is not valid base64",
        ),
        (
            lambda d: _sparse(d, {"bufferView": 3, "componentType": 5123}, count=5),
            "sparse.count is 5, more than",
        ),
        (
            lambda d: d["accessors"][0].update(sparse={"count": 1, "values": {"bufferView": 0}}),
            "sparse has no indices",
        ),
        (
            lambda d: _sparse(d, {"bufferView": 3, "componentType": 5126}),
            "sparse.indices.componentType is 5126",
        ),
        # (Bytes 12 to 15 of view 0 are the float 1.0, 0x3F800000 as an unsigned int.)
        (
            lambda d: _sparse(d, {"bufferView": 0, "byteOffset": 12, "componentType": 5125}),
            "accessors[0].sparse.indices holds index 1065353216, but the accessor has 4 values",
        ),
    ],
)
def test_a_gltf_property_of_the_wrong_shape_is_named_by_its_json_path(tmp_path, capfd, change, message):
    document = gltf_document(tmp_path)
    change(document)
    with pytest.raises(SceneError) as error:
        read_gltf_document(tmp_path, document)
    assert message in str(error.value)
    assert str(error.value).startswith(f"{tmp_path / 'm.gltf'}: mesh m.gltf: ")
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize(
    ("accessor", "message"),
    [
        (0, "accessors[0] has no bufferView and a count of 3000000"),  # (POSITION, alone)
        (1, "NORMAL has 3000000 values, POSITION 4"),
        (3, "accessors[3] has no bufferView and a count of 3000000"),  # (the indices)
    ],
)
def test_gltf_counts_that_the_file_does_not_bear_out_are_refused_before_memory_is_taken(
    tmp_path, accessor, message
):
    # An accessor without a buffer view is zeros (section 3.6.2.3): a count of 3e8 took 3.5 GB.
    import tracemalloc

    document = gltf_document(tmp_path)
    del document["accessors"][accessor]["bufferView"]
    document["accessors"][accessor]["count"] = 3_000_000
    if accessor == 0:
        _primitive(document)["attributes"] = {"POSITION": 0}
    tracemalloc.start()
    try:
        with pytest.raises(SceneError) as error:
            read_gltf_document(tmp_path, document)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert message in str(error.value)
    assert peak < 3_000_000  # (the zeros alone would be 6 MB as unsigned shorts, 72 MB as positions)


def test_a_gltf_sparse_accessor_without_a_buffer_view_is_zeros_with_its_values_in_place(tmp_path):
    # POSITION: zeros, its vertices 0, 1, 2 replaced by the quad's (view 3 begins 0, 1, 2);
    # vertex 3 stays at the origin, so triangle (0, 2, 3) has no area and is dropped.
    document = gltf_document(tmp_path)
    del document["accessors"][0]["bufferView"]
    _sparse(document, {"bufferView": 3, "componentType": 5123}, count=3)
    mesh = read_gltf_document(tmp_path, document)
    np.testing.assert_array_equal(mesh.triangles, QUAD[None, :3])


def test_gltf_integers_may_be_written_as_whole_floats(tmp_path):
    # Section 2.7 (JSON encoding), item 5: 4.0 is the integer 4 (but true is not 1, above).
    document = gltf_document(tmp_path)
    document["accessors"][0]["count"] = 4.0
    _primitive(document)["indices"] = 3.0
    assert len(read_gltf_document(tmp_path, document).triangles) == 2


@pytest.mark.parametrize("scale", [[1, 1, 0], [-1, 2, 1]])
def test_gltf_normals_under_a_scale_that_flattens_or_mirrors(tmp_path, scale):
    # Flattened onto z = 0 (glTF allows a scale of 0), the quad, already there, keeps its
    # triangles, and every normal becomes the plane's; mirrored, the normals go by the inverse
    # transpose, not turned with the triangles.
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], normals=TILTED, node={"scale": scale})
    mesh = read_mesh_data(tmp_path / "m.gltf")
    if scale[2] == 0:
        expected = np.tile([0.0, 0.0, 1.0], (4, 1))
    else:
        expected = TILTED / scale / np.linalg.norm(TILTED / scale, axis=1, keepdims=True)
    corners = [[0, 2, 1], [0, 3, 2]] if scale[0] < 0 else [[0, 1, 2], [0, 2, 3]]  # (a mirror turns them)
    np.testing.assert_allclose(mesh.triangles, (QUAD * scale)[corners], atol=1e-6)
    np.testing.assert_allclose(mesh.normals, expected[corners], atol=1e-6)


def test_a_gltf_rotation_is_normalised_and_a_zero_one_refused(tmp_path):
    # [0, 0, 2, 0] is [0, 0, 1, 0] (half a turn about z) written at twice its length: taken as
    # it stood, it would scale the quad by 4 (the rotation matrix grows with |q|^2).
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], node={"rotation": [0, 0, 2, 0]})
    mesh = read_mesh_data(tmp_path / "m.gltf")
    np.testing.assert_allclose(mesh.triangles, (QUAD * [-1, -1, 1])[[[0, 1, 2], [0, 2, 3]]], atol=1e-6)
    gltf(tmp_path / "m.gltf", QUAD, [[0, 1, 2], [0, 2, 3]], node={"rotation": [0, 0, 0, 0]})
    with pytest.raises(
        SceneError, match=r"nodes\[0\]\.rotation is \[0\.0, 0\.0, 0\.0, 0\.0\], which is no rotation"
    ):
        read_mesh_data(tmp_path / "m.gltf")


@pytest.mark.parametrize(
    ("required", "refused"),
    [(["KHR_texture_transform"], True), ([], False), (["KHR_mesh_quantization"], False)],
)
def test_gltf_extensions_required_that_ptlab_lacks_refuse_the_file_used_ones_are_named(
    tmp_path, required, refused
):
    document = gltf_document(tmp_path)
    document["extensionsUsed"] = ["KHR_texture_transform", "KHR_mesh_quantization"]
    document["extensionsRequired"] = required
    if refused:
        with pytest.raises(SceneError, match="requires the glTF extension KHR_texture_transform"):
            read_gltf_document(tmp_path, document)
    else:
        assert read_gltf_document(tmp_path, document).unused == ["the glTF extension KHR_texture_transform"]


def test_a_gltf_mesh_placed_many_times_copies_only_the_vertices_its_indices_use(tmp_path):
    # One quad (4 of 50,000 vertices in its accessor, as primitives sharing one vertex buffer
    # have) placed by 100 nodes: each copy of all 50,000 would take 120 MB in all.
    import tracemalloc

    positions = np.random.default_rng(0).random((50_000, 3))
    positions[:4] = QUAD
    path = gltf(tmp_path / "m.gltf", positions, [[0, 1, 2], [0, 2, 3]])
    document = json.loads(path.read_text())
    document["nodes"] = [{"mesh": 0, "translation": [2 * k, 0, 0]} for k in range(100)]
    document["scenes"] = [{"nodes": list(range(100))}]
    tracemalloc.start()
    try:
        mesh = read_gltf_document(tmp_path, document)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    quad = QUAD[[[0, 1, 2], [0, 2, 3]]]
    np.testing.assert_allclose(
        mesh.triangles, np.concatenate([quad + np.array([2 * k, 0, 0]) for k in range(100)])
    )
    assert peak < 20_000_000  # (the file's own 0.6 MB of vertices, its JSON and buffer)


# -- brief I (issue 39 red team): textures, OBJ and MTL files ------------------------------------

#: A scene of one OBJ mesh, ``{obj}``, in front of the camera, under a sky.
OBJ_SCENE = """
[camera]
position = [0, 0, 3]
look_at = [0, 0, 0]
[sky]
radiance = 1
[[mesh]]
file = "{obj}"
"""
#: An OBJ square with texture coordinates, and material m of m.mtl.
TEXTURED_SQUARE = (
    "mtllib m.mtl\nusemtl m\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n"
)


def textured_square_scene(folder: Path, mtl: str) -> Path:
    """A scene file in ``folder`` of the OBJ square, whose material m says ``mtl``."""
    (folder / "m.mtl").write_text(f"newmtl m\n{mtl}\n")
    (folder / "square.obj").write_text(TEXTURED_SQUARE)
    (folder / "scene.toml").write_text(OBJ_SCENE.format(obj="square.obj"))
    return folder / "scene.toml"


@pytest.mark.parametrize(
    ("texels", "found"),
    [
        (np.full((2, 2, 3), -0.5, np.float32), "found -0.5 to -0.5"),
        (np.full((2, 2, 3), 50.0, np.float32), "found 50 to 50"),
        (np.array([[[0, 0.5, 1]], [[0.25, 1.01, 0]]], np.float32), "found 0 to 1.01"),
    ],
)
def test_an_albedo_image_beyond_0_to_1_is_refused_naming_it_and_the_range(tmp_path, texels, found):
    # An albedo is a reflectance, as a constant one (refused above 1) is: a float image of 50
    # rendered 50 times brighter than the light, one of -0.5 negative pixels. Every path
    # meets ImageTexture: a file (a scene's, an OBJ's map_Kd), pixels (a GLB's embedded EXR).
    path = write_image(tmp_path / "albedo.exr", texels)
    for make in (lambda: ImageTexture(path), lambda: ImageTexture.from_array(texels, "albedo.exr")):
        with pytest.raises(
            PtlabError, match=rf"^image albedo\.exr: an albedo's texels must be from 0 to 1 .*{found}$"
        ):
            make()
    scene = textured_square_scene(tmp_path, "map_Kd albedo.exr")
    with pytest.raises(SceneError, match=rf"material 'm' \(m\.mtl, line 1\): image albedo\.exr: .*{found}$"):
        ptlab.load_scene(scene)


def test_an_albedo_image_within_0_to_1_is_read_and_a_tint_beyond_is_refused():
    edges = np.array([[[0, 0, 0]], [[1, 1, 1]]], np.float32)  # (0 and 1 themselves are fine)
    texture = ImageTexture.from_array(edges, "edges")
    assert texture.tinted([0.5, 1, 1]).tint.tolist() == [0.5, 1, 1]
    for tint, found in (([1, 2, 1], "found 0 to 2"), ([1, -1, 1], "found -1 to 1")):
        with pytest.raises(PtlabError, match=rf"^image edges: .*{found} \(tinted by"):
            texture.tinted(tint)
    # An 8-bit image is within [0, 1] whatever its texels; tinted by more than 1, it is not.
    with pytest.raises(PtlabError, match=r"found 0 to 1.5"):
        ImageTexture.from_array(TEXELS, "2x2").tinted([1.5, 1, 1])


@pytest.mark.filterwarnings("error")
def test_a_lookup_at_any_float32_uv_gives_a_texel():
    # uv * width in float64 was 9e38 (or inf), whose floor mod 9 gave the index 9 (or a
    # negative one): every render of the scene crashed. Wrapped first, any uv has a texel.
    row = ImageTexture.from_array(np.arange(27, dtype=np.uint8).reshape(1, 9, 3) * 9, "row")
    big = float(np.finfo(np.float32).max)
    uv = np.array([[big, 0.5], [-big, 0.5], [2.0**20 + 0.25, 0.5], [1e17, 3e38], [np.inf, np.nan]])
    same = np.array([[0.0, 0.5], [0.0, 0.5], [0.25, 0.5], [0.0, 0.0], [0.0, 0.0]])
    np.testing.assert_array_equal(row(uv), row(same))
    np.testing.assert_array_equal(row(uv.astype(np.float32)), row(same))


def test_texture_coordinates_beyond_float32_name_their_line(tmp_path):
    (tmp_path / "m.mtl").write_text("newmtl m\nKd 1 1 1\n")
    for vt, shown in (("vt 1e39 0", "1e39 0"), ("vt 0 -inf", "0 -inf"), ("vt nan 0", "nan 0")):
        (tmp_path / "far.obj").write_text(TEXTURED_SQUARE.replace("vt 1 1", vt))
        with pytest.raises(
            SceneError, match=rf"far\.obj: line 9: `vt {shown}`: texture coordinates must be finite"
        ):
            read_mesh_data(tmp_path / "far.obj")
    # One that no face uses is no part of the scene.
    (tmp_path / "far.obj").write_text(TEXTURED_SQUARE + "vt 1e39 0\n")
    assert np.abs(read_mesh_data(tmp_path / "far.obj").uv).max() == 1


@pytest.mark.parametrize(
    ("face", "problem"),
    [
        ("f 1/1 2/2 3/9 4/4", "line 11: `vt` record 9 does not exist (the file has 4 `vt` records, 4 before"),
        ("f 1/1 2/2 3/-9 4/4", "line 11: `vt` record -9 does not exist"),
        ("f 1/0 2/2 3/3 4/4", "line 11: `vt` record index 0 (OBJ counts `vt` records from 1)"),
        ("f 1/1/1 2/2/1 3/5/1", "line 11: `vt` record 5 does not exist"),
    ],
)
def test_a_face_with_a_vt_that_does_not_exist_names_its_line(tmp_path, face, problem):
    # (It said the textured mesh had no texture coordinates, pointing at the scene.)
    obj = TEXTURED_SQUARE.replace("mtllib m.mtl", "vn 0 0 1").replace("f 1/1 2/2 3/3 4/4", face)
    (tmp_path / "bad.obj").write_text(obj)
    with pytest.raises(SceneError, match=re.escape(f"bad.obj: {problem}")):
        read_mesh_data(tmp_path / "bad.obj")


def png_chunk(kind: bytes, data: bytes) -> bytes:
    """One PNG chunk: length, kind, data and CRC (PNG specification, section 5.3)."""
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def test_an_image_that_cannot_be_read_is_one_line_and_libpng_prints_nothing(tmp_path, capfd):
    # libpng printed "libpng error: ..." on standard error beside ptlab's message, which
    # glued OpenImageIO's three lines with literal "\n".
    full = write_image(tmp_path / "full.png", np.full((64, 64, 3), 77, np.uint8)).read_bytes()
    (tmp_path / "cut.png").write_bytes(full[:60])
    header = struct.pack(">IIBBBBB", 100000, 100000, 8, 2, 0, 0, 0)  # (28 GB of RGB)
    (tmp_path / "huge.png").write_bytes(
        b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IDAT", zlib.compress(b"\0" * 99))
    )
    for name, problem in (("cut.png", "hit end of file"), ("huge.png", "exceeds the")):
        with pytest.raises(PtlabError, match=rf"^image .*{name}: cannot read it: [^\n\\]*{problem}[^\n\\]*$"):
            ImageTexture(tmp_path / name)
    assert capfd.readouterr().err == ""
    # What else lands on standard error meanwhile is written on.
    from ptlab.textures import _libpng_quiet

    with _libpng_quiet():
        os.write(2, b"libpng error: dropped\nkept\n")
    assert capfd.readouterr().err == "kept\n"


def test_a_map_kd_with_an_unclosed_quote_or_naming_a_folder_says_so(tmp_path):
    (tmp_path / "folder").mkdir()
    for statement, problem in (
        (
            'map_Kd "tex.png',
            r"square\.obj: m\.mtl, line 2: `map_Kd` \"tex\.png: the quotation mark is not closed",
        ),
        ("map_Kd folder", r"folder: is a folder, not an image$"),
    ):
        with pytest.raises(SceneError, match=problem):
            ptlab.load_scene(textured_square_scene(tmp_path, statement))


def test_a_tab_after_a_records_keyword_is_read_as_a_space(tmp_path):
    spaced = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n"
    for name, text in (("spaced.obj", spaced), ("tabbed.obj", spaced.replace(" ", "\t"))):
        (tmp_path / name).write_text(text)
    spaced_data, tabbed_data = (read_mesh_data(tmp_path / n) for n in ("spaced.obj", "tabbed.obj"))
    for field in ("triangles", "uv", "normals"):
        np.testing.assert_array_equal(getattr(tabbed_data, field), getattr(spaced_data, field))


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(
    ("vn", "unit"),
    [
        ("1e200 1e200 1e200", [3**-0.5] * 3),
        ("1e-170 1e-170 1e-170", [3**-0.5] * 3),
        ("0 -5e-324 0", [0, -1, 0]),
    ],
)
def test_huge_and_tiny_vertex_normals_are_made_unit_length(tmp_path, vn, unit):
    # Their squares overflowed (a NumPy warning, and the face's normal instead) or underflowed
    # to 0 (the face's normal: a tiny normal is a direction all the same).
    (tmp_path / "n.obj").write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn {vn}\nf 1//1 2//1 3//1\n")
    np.testing.assert_allclose(read_mesh_data(tmp_path / "n.obj").normals, [[unit] * 3])


# -- brief H (issue 39 red team): PLY files read by ptlab itself ---------------------------------

#: Squares side by side, facing +z, as PLY polygons: a quad, two triangles, a pentagon (the
#: third square, a point in its top edge), and faces of 0 and 2 vertices, which have no area.
PLY_POINTS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0, 0], [3, 1, 0], [2.5, 1, 0]]
)
PLY_POLYGONS = [[0, 1, 2, 3], [1, 4, 5], [], [1, 5, 2], [0, 1], [4, 6, 7, 8, 5]]
PLY_CODES = {"uchar": "B", "int": "i", "uint64": "Q", "float": "f"}


def write_ply(
    path: Path, encoding: str, faces: list, index: str = "int", texcoord: list | None = None
) -> Path:
    """A PLY file of ``PLY_POINTS`` and ``faces`` (lists of vertex indices of type ``index``),
    with a ``texcoord`` list per face where given."""
    header = (
        f"ply\nformat {encoding} 1.0\ncomment TextureFile checker.png\nelement vertex {len(PLY_POINTS)}\n"
        f"property float x\nproperty float y\nproperty float z\nelement face {len(faces)}\n"
        f"property list uchar {index} vertex_indices\n"
        + ("property list uchar float texcoord\n" if texcoord else "")
        + "end_header\n"
    )
    lists = [[face] + ([texcoord[k]] if texcoord else []) for k, face in enumerate(faces)]
    if encoding == "ascii":
        rows = [" ".join(f"{x:g}" for x in point) for point in PLY_POINTS]
        rows += [" ".join(" ".join(map(str, [len(a), *a])) for a in face) for face in lists]
        data = (header + "\n".join(rows) + "\n").encode()
    else:
        order = "<" if encoding == "binary_little_endian" else ">"
        data = header.encode() + PLY_POINTS.astype(order + "f4").tobytes()
        for face in lists:
            for values, kind in zip(face, [index, "float"], strict=False):
                data += struct.pack(f"{order}B{len(values)}{PLY_CODES[kind]}", len(values), *values)
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_ply_polygons_are_cut_as_obj_faces_are_and_faces_without_area_skipped(tmp_path, encoding):
    # trimesh refused quads ("faces of shape (1, 4)") and, in a binary file, lists of varying
    # lengths ("PLY is unexpected length!").
    triangles = read_mesh_data(write_ply(tmp_path / "m.ply", encoding, PLY_POLYGONS)).triangles
    obj = tmp_path / "m.obj"
    obj.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in PLY_POINTS)
        + "".join(f"f {' '.join(str(k + 1) for k in face)}\n" for face in PLY_POLYGONS if len(face) > 2)
    )
    np.testing.assert_array_equal(triangles, read_mesh_data(obj).triangles)
    assert len(triangles) == 7
    front = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    np.testing.assert_allclose(front[:, :2], 0)
    assert (front[:, 2] > 0).all()
    assert front[:, 2].sum() / 2 == pytest.approx(3)  # (no area lost)


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_ply_texcoord_lists_give_each_corner_its_uv_and_its_texture_file_prints_nothing(
    tmp_path, capfd, encoding
):
    # One face's list read as a number ("no len()"); trimesh printed a traceback for the
    # TextureFile. uv here are the corners' x and y: each corner must get its own.
    faces = [[0, 1, 2, 3], [1, 4, 5]]
    texcoord = [PLY_POINTS[face, :2].ravel().tolist() for face in faces]
    for chosen in ([0], [0, 1]):
        path = write_ply(
            tmp_path / "m.ply", encoding, [faces[k] for k in chosen], texcoord=[texcoord[k] for k in chosen]
        )
        mesh = read_mesh_data(path)
        np.testing.assert_allclose(mesh.uv, mesh.triangles[..., :2])
        assert [m.texture for m in mesh.materials] == [tmp_path / "checker.png"]
    assert capfd.readouterr().err == ""


SQUARE_PLY = (
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
)
SQUARE_LINES = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (SQUARE_PLY + SQUARE_LINES + "3 0 1 2\n3 0 2", r"truncated: line 15: `face` 2 of 2 has 3 numbers"),
        (
            SQUARE_PLY.replace("vertex 4", "vertex 3") + SQUARE_LINES + "3 0 1 2\n3 0 2 3\n",
            "line 15: more data",
        ),
        (SQUARE_PLY + SQUARE_LINES + "3 0 1 2\n3 0 2 3\n3 0 1 3\n", "line 16: more data than its header"),
        (
            SQUARE_PLY + SQUARE_LINES.replace("1 0 0", "1 0 0 1") + "3 0 1 2\n3 0 2 3\n",
            "line 11: `vertex` 2",
        ),
        (SQUARE_PLY + SQUARE_LINES + "3 0 1 2\n3 0 2 x\n", "line 15: `x` is not a number"),
    ],
)
def test_ply_text_that_does_not_match_its_header_names_the_line(tmp_path, text, message):
    # Each was read with a face missing (or wrong) and no word.
    (tmp_path / "m.ply").write_text(text)
    with pytest.raises(SceneError, match=message) as error:
        read_mesh_data(tmp_path / "m.ply")
    assert "\n" not in str(error.value)


def test_ply_partial_normals_lone_edges_and_huge_indices_are_said_as_the_file_has_them(tmp_path):
    path = tmp_path / "m.ply"
    header = SQUARE_PLY.replace("z\n", "z\nproperty float nx\n").replace("face 2", "face 1")
    path.write_text(header + SQUARE_LINES.replace("0\n", "0 1\n") + "3 0 1 2\n")
    mesh = read_mesh_data(path)
    assert mesh.normals is None
    assert mesh.unused == ["vertex normals (the file gives only nx)"]
    with pytest.raises(SceneError, match="has no triangles: its face has fewer than 3 vertices"):
        read_mesh_data(write_ply(path, "ascii", [[0, 1]]))
    for encoding in ("ascii", "binary_little_endian"):
        with pytest.raises(SceneError, match="refers to vertex 18446744073709551615, but there are 9"):
            read_mesh_data(write_ply(path, encoding, [[0, 1, 2**64 - 1]], index="uint64"))


# -- integrator: a quad's uv ------------------------------------------------------------------------


def test_a_quads_uv_beyond_what_the_renderer_keeps_is_one_line():
    # uv 3e38 and -3e38 are each float32, but their difference, which the renderer keeps, is not.
    scene = {
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 30},
        "materials": {"grey": {"type": "diffuse"}},
        "mesh": [
            {
                "quad": {
                    "corners": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                    "uv": [[3e38, 0], [-3e38, 0], [0, 1], [0, 0]],
                },
                "material": "grey",
            }
        ],
    }
    with pytest.raises(SceneError, match=r"mesh\[0\]\.quad\.uv: must be finite, within \+-1\.701e\+38"):
        ptlab.load_dict(scene)


def test_an_objs_lines_and_points_are_named_not_dropped_without_a_word(tmp_path):
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nl 1 2\np 3\n")
    unused = read_mesh_data(tmp_path / "m.obj").unused
    assert "lines (`l`): ptlab renders surfaces only" in unused
    assert "points (`p`): ptlab renders surfaces only" in unused
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n")
    assert read_mesh_data(tmp_path / "m.obj").unused == []
