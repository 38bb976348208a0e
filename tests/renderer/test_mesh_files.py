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
import struct
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
    linear = (np.arange(256, dtype=np.float32) / 100)[None, :, None].repeat(3, axis=2)
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
    assert "material library gone.mtl (not found)" in data.unused


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
