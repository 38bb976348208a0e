"""PLY files: the mesh their elements describe (``ptlab.meshes.ply_elements`` reads them).

ptlab reads of a PLY file: the ``vertex`` element's ``x y z``, vertex normals (``nx ny nz``),
texture coordinates per vertex (``u v``, ``s t`` or ``texture_u texture_v``) or per face
corner (a face's ``texcoord`` list: u and v of each of its vertices), a texture image
(``comment TextureFile``), faces (a ``face`` element's ``vertex_indices`` or ``vertex_index``
list), polygons cut into triangles as OBJ faces are (``ptlab.meshes.obj``), and faces given
as triangle strips (an element ``tristrips``, strips of vertex indices separated by -1, as
some scanners write). A face of fewer than 3 vertices has no area: it is skipped, as a
triangle of zero area is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ptlab.meshes.base import FileMaterial, IndexedMesh
from ptlab.meshes.obj import _by_triangle, _fan_corners
from ptlab.meshes.ply_elements import PlyData, PlyList, Properties, read_ply_elements

#: Vertex properties that colour a mesh, which ptlab does not use.
COLOUR_PROPERTIES = {"red", "green", "blue", "r", "g", "b", "diffuse_red", "diffuse_green", "diffuse_blue"}
#: The names writers give a face's list of vertices, and a vertex's texture coordinates.
INDEX_NAMES = ("vertex_indices", "vertex_index")
UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"))


def read_ply(data: bytes, folder: Path) -> IndexedMesh:
    """The mesh of a PLY file's bytes (a texture image looked for in ``folder``), or
    ``ValueError`` for a file that is not PLY, or does not match its header, or whose faces
    refer to vertices it does not have."""
    ply = read_ply_elements(data)
    if "vertex" not in ply.elements:
        raise ValueError("has no `vertex` element")
    vertex = ply.elements["vertex"]
    vertices = _columns(vertex, ("x", "y", "z"))
    if vertices is None:
        raise ValueError("its `vertex` element needs the properties x, y and z (each one number)")
    mesh = IndexedMesh(vertices, np.zeros((0, 3), np.int64))
    mesh.normals = _given(vertex, ("nx", "ny", "nz"), "vertex normals", mesh.unused)
    if COLOUR_PROPERTIES & vertex.keys():
        mesh.unused.append("vertex colours")
    mesh.faces, mesh.uv = _triangles(ply, len(vertices), mesh.unused)
    if mesh.uv is None:
        given = (_given(vertex, names, "texture coordinates", mesh.unused) for names in UV_NAMES)
        mesh.uv = next((uv for uv in given if uv is not None), None)
    if ply.header.texture_files:
        name = ply.header.texture_files[0]
        if mesh.uv is None:
            mesh.unused.append(f"texture {name} (the file has no texture coordinates)")
        else:
            mesh.materials = [FileMaterial(Path(name).stem, None, folder / name, "its header (TextureFile)")]
            mesh.material_ids = np.zeros(len(mesh.faces), dtype=np.intp)
    return mesh


def _triangles(ply: PlyData, vertex_count: int, unused: list[str]) -> tuple[np.ndarray, np.ndarray | None]:
    """(T, 3) int64 the triangles of the faces, then of the strips, and (T, 3, 2) the texture
    coordinates of their corners where the faces give them (``texcoord``), else None."""
    faces, sizes, corners = _faces(ply, vertex_count)
    uv = _corner_uv(ply, sizes, corners, unused)
    strips = ply.elements.get("tristrips", {}).get(INDEX_NAMES[0])
    if not isinstance(strips, PlyList) or not len(strips.counts):
        return faces, uv
    references = _references(ply, "tristrips", strips, vertex_count, "a strip")
    faces = np.concatenate([faces, strip_triangles(np.split(references, np.cumsum(strips.counts)[:-1]))])
    if uv is not None:
        unused.append("texture coordinates of the faces (`texcoord`), which its strips lack")
    return faces, None


def _columns(element: Properties, names: tuple[str, ...]) -> np.ndarray | None:
    """(n, len(names)) float64 the element's properties ``names`` side by side, or None
    unless it has them all, each a single number."""
    columns = [element.get(name) for name in names]
    if not all(isinstance(column, np.ndarray) for column in columns):
        return None
    return np.stack([np.asarray(column, dtype=np.float64) for column in columns], axis=1)


def _given(vertex: Properties, names: tuple[str, ...], what: str, unused: list[str]) -> np.ndarray | None:
    """(V, len(names)) float64 the vertices' properties ``names``, or None where the file
    does not give them all (``unused`` then names ``what`` and those it gives)."""
    found = _columns(vertex, names)
    if found is None and (given := [name for name in names if name in vertex]):
        unused.append(f"{what} (the file gives only {', '.join(given)})")
    return found


def _faces(ply: PlyData, vertex_count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(T, 3) int64 the triangles of the ``face`` element's polygons, in the faces' order; the
    (F,) number of vertices of each face; which of all their references each triangle's
    corners are (``_fan_corners``; None: the faces are all triangles, three by three)."""
    face = ply.elements.get("face", {})
    references = next((face[name] for name in INDEX_NAMES if name in face), None)
    if not isinstance(references, PlyList):
        if ply.count("face"):
            raise ValueError("its `face` element has no list `vertex_indices` (nor `vertex_index`)")
        return np.zeros((0, 3), np.int64), np.zeros(0, np.int64), None
    sizes = references.counts
    vertices = _references(ply, "face", references, vertex_count, "a face")
    polygon = sizes >= 3
    if len(sizes) and not polygon.any() and "tristrips" not in ply.elements:
        each = "its face has" if len(sizes) == 1 else f"each of its {len(sizes)} faces has"
        raise ValueError(f"has no triangles: {each} fewer than 3 vertices")
    if not polygon.all():  # (faces of 0 to 2 vertices have no area: left out)
        vertices = vertices[np.repeat(polygon, sizes)]
    kept = sizes[polygon]
    corners = None if (kept == 3).all() else _fan_corners(kept)
    return _by_triangle(vertices, corners), sizes, corners


def _corner_uv(
    ply: PlyData, sizes: np.ndarray, corners: np.ndarray | None, unused: list[str]
) -> np.ndarray | None:
    """(T, 3, 2) the texture coordinates of each triangle's corners, from the faces'
    ``texcoord`` lists (u, v of each of a face's vertices), or None: the faces have none, or
    a list that does not give each vertex two numbers (``unused`` says so)."""
    texcoord = ply.elements.get("face", {}).get("texcoord")
    if not isinstance(texcoord, PlyList):
        return None
    wrong = np.flatnonzero(texcoord.counts != 2 * sizes)
    if len(wrong):
        row = int(wrong[0])
        unused.append(
            f"texture coordinates per face corner (`texcoord`; {ply.where('face', row)}: "
            f"{texcoord.counts[row]} numbers for {sizes[row]} vertices)"
        )
        return None
    uv = np.asarray(texcoord.values, dtype=np.float64).reshape(-1, 2)
    polygon = sizes >= 3
    if not polygon.all():
        uv = uv[np.repeat(polygon, sizes)]
    return uv[corners] if corners is not None else uv.reshape(-1, 3, 2)


def _references(ply: PlyData, element: str, references: PlyList, vertex_count: int, what: str) -> np.ndarray:
    """(R,) int64 the vertex indices of a list of every ``element``, or ``ValueError`` naming
    the first that is not a vertex's (0 to vertex_count - 1; -1 separates a strip's runs)."""
    values = references.values
    lowest = -1 if element == "tristrips" else 0
    # (Compared as stored: an unsigned 64-bit index beyond int64 stays itself.)
    bad = ~((values >= lowest) & (values < vertex_count))
    if values.dtype.kind == "f":
        bad |= values != np.floor(values)
    if bad.any():
        k = int(np.argmax(bad))
        row = references.row_of(k)
        there = f"{vertex_count} vertices (0 to {vertex_count - 1})" if vertex_count else "no vertices"
        raise ValueError(
            f"{ply.where(element, row)}: {what} refers to vertex {ply.written(references, k)}, "
            f"but there are {there}"
        )
    return values.astype(np.int64)


def strip_triangles(strips: list[np.ndarray]) -> np.ndarray:
    """(T, 3) the triangles of triangle strips: each (n,) array of vertex indices, in which -1
    starts a new strip, gives triangle k = (s[k], s[k+1], s[k+2]), every other one turned
    (s[k+1], s[k], s[k+2]) so that all face the way the first does; triangles that repeat a
    vertex (which strips use to join) are left out."""
    triangles = []
    for strip in strips:
        for run in np.split(strip, np.flatnonzero(strip < 0)):
            run = run[run >= 0]
            if len(run) < 3:
                continue
            k = np.arange(len(run) - 2)
            odd = k % 2 == 1
            triangle = np.stack(
                [np.where(odd, run[k + 1], run[k]), np.where(odd, run[k], run[k + 1]), run[k + 2]], 1
            )
            distinct = (
                (triangle[:, 0] != triangle[:, 1])
                & (triangle[:, 1] != triangle[:, 2])
                & (triangle[:, 0] != triangle[:, 2])
            )
            triangles.append(triangle[distinct])
    return np.concatenate(triangles) if triangles else np.zeros((0, 3), dtype=np.int64)
