"""Mesh files: the triangles of an OBJ, STL, PLY, OFF or glTF file, read and checked, with
what the file says of their surface.

Each format has its reader: OBJ files ptlab's own (``ptlab.meshes.obj``, with their material
files, ``mtl``), PLY files ptlab's own (``ply``, text or binary, read against their header:
``ply_elements``), glTF files ptlab's own (``gltf``), STL and OFF files trimesh. Every reader
gives vertices and the faces that index them (``IndexedMesh``); ``read_mesh_data`` then
checks what came out (three coordinates per vertex, faces that refer to existing vertices,
nothing NaN or infinite), drops triangles of zero area, which no ray can hit, and returns one
row per triangle (``MeshData``): the triangles, and where the file gives them their texture
coordinates, vertex normals and materials, and what else it brought that ptlab does not use.

What each format gives (docs/scene-format.md, "Mesh files"):

====== ===================== ============================ =====================================
format vertex normals        texture coordinates          materials
====== ===================== ============================ =====================================
OBJ    ``vn`` (``f v/vt/vn``) ``vt``                       ``mtllib`` / ``usemtl``: Kd, map_Kd
PLY    ``nx ny nz``          ``u v`` / ``s t``, texcoord  ``comment TextureFile``
glTF   ``NORMAL``            ``TEXCOORD_n``               baseColorFactor, baseColorTexture
STL    (none)                (none)                       (none)
OFF    (none)                (none)                       (none)
====== ===================== ============================ =====================================
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ptlab.errors import SceneError
from ptlab.meshes.base import (
    UV_LIMIT,
    FileMaterial,
    IndexedMesh,
    MeshData,
    has_area,
    unit_corner_normals,
)
from ptlab.meshes.gltf import read_gltf
from ptlab.meshes.obj import ObjRecords, check_obj_lines, parse_obj, read_obj, read_obj_mesh
from ptlab.meshes.ply import read_ply

__all__ = [
    "MESH_FORMATS",
    "FileMaterial",
    "MeshData",
    "ObjRecords",
    "check_obj_lines",
    "drop_zero_area",
    "has_area",
    "parse_obj",
    "read_mesh",
    "read_mesh_data",
    "read_mesh_triangles",
    "read_obj",
]

#: The mesh formats ptlab reads (by file extension).
MESH_FORMATS = ("obj", "stl", "ply", "off", "glb", "gltf")


def read_mesh_triangles(path: Path, where: str | None = None, limit: float = math.inf) -> np.ndarray:
    """(T, 3, 3) float64 triangles of a mesh file (``read_mesh``)."""
    return read_mesh(path, where, limit)[0]


def read_mesh(
    path: Path, where: str | None = None, limit: float = math.inf
) -> tuple[np.ndarray, np.ndarray | None]:
    """The (T, 3, 3) triangles of a mesh file and their (T, 3, 2) texture coordinates (or
    None): ``read_mesh_data`` without the normals and materials."""
    data = read_mesh_data(path, where, limit, surface=False)
    return data.triangles, data.uv


def read_mesh_data(
    path: Path, where: str | None = None, limit: float = math.inf, surface: bool = True
) -> MeshData:
    """What ptlab reads of a mesh file: its triangles, and where the file gives them, their
    texture coordinates, vertex normals and materials (``MeshData``).

    Args:
        path: an OBJ, STL, PLY, OFF, glTF or GLB file (by its extension).
        where: what messages call the place that names the file (a scene file and key).
        limit: every vertex that a face uses must lie within +-``limit``.
        surface: False reads the triangles and texture coordinates only (an OBJ file's
            material files are not opened).

    Raises ``SceneError`` (naming ``where``) for a file that cannot be read or would be
    misread, an empty mesh, NaN or infinite vertices, coordinates beyond +-``limit``, and
    texture coordinates that are NaN, infinite or beyond ``UV_LIMIT``. Triangles
    of zero area are then dropped.
    """
    path = Path(path)
    where = where or str(path)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in MESH_FORMATS:
        raise SceneError(
            where, f"mesh {path.name}: unknown mesh format {path.suffix!r} (use .{', .'.join(MESH_FORMATS)})"
        )
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SceneError(where, f"cannot read mesh {path.name}: {error.strerror}") from None
    if not data or data.isspace():  # (bytes.strip would copy the file)
        raise SceneError(where, f"mesh {path.name} is empty")
    try:
        mesh = _read(data, path, fmt, surface, where)
    except ValueError as error:
        raise SceneError(where, f"mesh {path.name}: {error}") from None
    return _checked(mesh, where, path.name, limit)


def _read(data: bytes, path: Path, fmt: str, surface: bool, where: str) -> IndexedMesh:
    """The mesh of a file's bytes, by the reader of its format; ``ValueError`` if unreadable."""
    if fmt == "obj" and not surface:
        vertices, faces, uv = read_obj(data)
        return IndexedMesh(vertices, faces, uv)
    if fmt == "obj":
        return read_obj_mesh(data, path.parent)
    if fmt == "ply":
        return read_ply(data, path.parent)
    if fmt in ("gltf", "glb"):
        return read_gltf(data, path.parent, binary=fmt == "glb")
    mesh = _read_with_trimesh(path, where, fmt)
    vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
    return IndexedMesh(vertices, np.asarray(getattr(mesh, "faces", ())), _texture_coordinates(mesh))


def _checked(mesh: IndexedMesh, where: str, name: str, limit: float) -> MeshData:
    """``mesh`` checked and one row per triangle (``read_mesh_data``)."""
    vertices, faces = mesh.vertices, mesh.faces
    _check_faces(vertices, faces, where, name)
    triangles = vertices[faces]
    # (A closed mesh has a sixth as many vertices as corners: they are looked at first, the
    # corners only to name the vertex, or where the one beyond belongs to no face.)
    if (np.abs(vertices) > limit).any() and (beyond := np.abs(triangles).max(axis=2) > limit).any():
        vertex = triangles[beyond][0]
        raise SceneError(
            where,
            f"mesh {name} has a vertex at {vertex.tolist()}: every coordinate must lie within +-{limit:g}",
        )
    uv = _by_corner(mesh.uv, faces, len(vertices), where, f"mesh {name}: texture coordinates")
    if uv is not None and not (np.abs(uv) <= UV_LIMIT).all():  # (NaN too)
        raise SceneError(
            where,
            f"mesh {name} has texture coordinates that are NaN, infinite or beyond "
            f"+-{UV_LIMIT:.4g} (half of float32's largest)",
        )
    normals = _by_corner(mesh.normals, faces, len(vertices), where, f"mesh {name}: vertex normals")
    unused = list(mesh.unused)
    material_ids = mesh.material_ids
    if material_ids is not None and np.shape(material_ids) != (len(faces),):
        raise SceneError(where, f"mesh {name}: {np.shape(material_ids)} material ids for {len(faces)} faces")
    data = MeshData(triangles, uv, normals, material_ids, mesh.materials, unused)
    # (Only now: a vertex far out can make its triangles degenerate in float64.)
    kept = has_area(triangles)
    if not kept.any():
        raise SceneError(where, f"mesh {name} has only zero-area triangles")
    if not kept.all():  # (spares a copy)
        data = data.taken(kept)
    if data.normals is not None:
        bad = ~np.isfinite(data.normals).all(axis=2)
        if bad.any():
            unused.append(f"{int(bad.sum())} vertex normals that are NaN or infinite (flat there)")
            data.normals = np.where(bad[..., None], 0.0, data.normals)
        data.normals = unit_corner_normals(data.normals, data.triangles)
    return data


def _by_corner(values: np.ndarray | None, faces: np.ndarray, vertex_count: int, where: str, what: str):
    """(T, 3, k) per-corner ``values`` of a mesh: given per corner already, or per vertex,
    (V, k), taken at each face's vertices; None stays None."""
    if values is None or values.ndim == 3:
        return values
    if values.ndim != 2 or len(values) != vertex_count or values.shape[1] == 0:
        raise SceneError(where, f"{what} of shape {values.shape} for {vertex_count} vertices")
    return values[faces]


def _check_faces(vertices: np.ndarray, faces: np.ndarray, where: str, name: str) -> None:
    """Raise ``SceneError`` unless ``faces`` (T, 3) index ``vertices`` (V, 3), all finite."""
    if len(faces) == 0:
        raise SceneError(where, f"mesh {name} has no triangles")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise SceneError(
            where,
            f"mesh {name}: vertices must have 3 coordinates, "
            f"got {vertices.shape[-1] if vertices.ndim == 2 else 0}",
        )
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        raise SceneError(where, f"mesh {name}: trimesh returned faces of shape {faces.shape}")
    outside = faces[(faces < 0) | (faces >= len(vertices))]
    if len(outside):
        raise SceneError(
            where,
            f"mesh {name}: a face refers to vertex {int(outside[0])}, "
            f"but there are {len(vertices)} vertices (0 to "
            f"{len(vertices) - 1})",
        )
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        raise SceneError(
            where,
            f"mesh {name} has {int(bad.sum())} vertices that are NaN "
            f"or infinite (first: vertex {int(np.flatnonzero(bad)[0])})",
        )


def _texture_coordinates(mesh) -> np.ndarray | None:
    """(V, 2) uv per vertex of a trimesh mesh (v = 0 where the file gives u only), or None
    (their count is checked against the vertices' later, ``_by_corner``)."""
    uv = getattr(getattr(mesh, "visual", None), "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim != 2 or uv.shape[1] == 0:
        return uv  # (``_by_corner`` names the shape)
    return np.pad(uv[:, :2], ((0, 0), (0, max(0, 2 - uv.shape[1]))))


def _read_with_trimesh(path: Path, where: str, fmt: str):
    """The trimesh mesh of a file of any format trimesh reads."""
    import trimesh

    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except ModuleNotFoundError:
        # trimesh imports a character-set detector (an optional package) only for a file
        # that is neither valid binary data of its format nor UTF-8 text.
        raise SceneError(
            where, f"cannot read mesh {path.name}: neither a binary .{fmt} file nor UTF-8 text"
        ) from None
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise SceneError(where, f"cannot read mesh {path.name}: {error}") from None
    return mesh


def drop_zero_area(triangles: np.ndarray) -> np.ndarray:
    """(T', 3, 3) the triangles of (T, 3, 3) ``triangles`` whose area is not zero."""
    return triangles[has_area(triangles)]
