"""What a mesh file brings, as every reader returns it: ``MeshData`` and its ``FileMaterial``s.

A mesh file gives triangles and may say more of the surface: texture coordinates, vertex
normals (for smooth shading, ``ptlab.scene.Scene.normals``), materials per face. Every reader
(``ptlab.meshes.obj``, ``ply``, ``gltf``, trimesh for the rest) returns one ``MeshData``, with
one row per triangle in every array, and names in ``unused`` what the file brought that ptlab
does not use, so that a scene can warn instead of dropping it without a word.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: The largest texture coordinate a mesh may have: half of float32's largest number. Renderers
#: (Mitsuba's meshes) and file formats (glTF) keep uv in float32, and ptlab keeps a triangle's
#: as a corner and two differences (``Scene.triangle_uv``), which must stay finite too.
UV_LIMIT = float(np.finfo(np.float32).max) / 2


@dataclass
class FileMaterial:
    """One material a mesh file names (an OBJ material file's ``newmtl``, a glTF material).

    Attributes:
        name: its name in the file.
        albedo: (3,) its linear diffuse colour (OBJ ``Kd``, glTF ``baseColorFactor``'s RGB),
            or None where the file gives none.
        texture: its diffuse image (OBJ ``map_Kd``, glTF ``baseColorTexture``): a file (not
            yet read: ``ptlab.textures.ImageTexture`` reads it), or the pixels of an image the
            file holds (a GLB's), (H, W, C) as stored, row 0 the top (``ImageTexture.
            from_array``); None where it has none. Where both are given the diffuse colour is
            their product, as both formats define it.
        defined_in: where the material is written, for messages (``"spot.mtl, line 2"``).
    """

    name: str
    albedo: np.ndarray | None
    texture: Path | np.ndarray | None
    defined_in: str = ""


@dataclass
class MeshData:
    """What ptlab reads of a mesh file: one row per triangle in every array.

    Attributes:
        triangles: (T, 3, 3) float64, vertex k of triangle i at ``triangles[i, k]``.
        uv: (T, 3, 2) float64 texture coordinates of those vertices (v up, OBJ's convention),
            or None.
        normals: (T, 3, 3) float64 unit vertex normals at each corner, or None: the file has
            none (ptlab never makes them up: such a mesh is flat-shaded).
        material_ids: (T,) intp index into ``materials`` (-1: a face without one), or None
            where the file names no material.
        materials: the materials the triangles use.
        unused: what the file brought that ptlab does not use, in short phrases
            ("specular colour (Ks)", "glTF metallic-roughness").
    """

    triangles: np.ndarray
    uv: np.ndarray | None
    normals: np.ndarray | None
    material_ids: np.ndarray | None
    materials: list[FileMaterial]
    unused: list[str]

    def taken(self, rows: np.ndarray) -> MeshData:
        """The triangles ``rows`` (an index or mask), with their uv, normals and materials."""
        return MeshData(
            self.triangles[rows],
            None if self.uv is None else self.uv[rows],
            None if self.normals is None else self.normals[rows],
            None if self.material_ids is None else self.material_ids[rows],
            self.materials,
            self.unused,
        )


@dataclass
class IndexedMesh:
    """A mesh as a reader found it, before ptlab checks it (``ptlab.meshes.read_mesh_data``):
    vertices, and faces that index them.

    Attributes:
        vertices: (V, 3) float64.
        faces: (T, 3) integer indices into ``vertices``, unchecked.
        uv, normals: texture coordinates and vertex normals per vertex, (V, 2) and (V, 3), or
            per face corner, (T, 3, 2) and (T, 3, 3) (an OBJ file's, which index their own
            records), or None.
        material_ids, materials, unused: as ``MeshData``'s.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray | None = None
    normals: np.ndarray | None = None
    material_ids: np.ndarray | None = None
    materials: list[FileMaterial] = field(default_factory=list)
    unused: list[str] = field(default_factory=list)


def has_area(triangles: np.ndarray) -> np.ndarray:
    """(T,) bool: which of the (T, 3, 3) ``triangles`` have an area that is not zero."""
    return np.linalg.norm(face_normals_unnormalised(triangles), axis=1) > 0


def face_normals_unnormalised(triangles: np.ndarray) -> np.ndarray:
    """(T, 3) (v1 - v0) x (v2 - v0) of (T, 3, 3) ``triangles``: the front face's normal, as
    long as twice the triangle's area."""
    return np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])


def unit_corner_normals(normals: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(T, 3, 3) the corner ``normals`` (finite) of ``triangles`` made unit length; a normal
    of length 0, which gives no direction, becomes its triangle's face normal (a triangle of
    zero area keeps 0)."""
    with np.errstate(over="ignore"):
        length = np.linalg.norm(normals, axis=2, keepdims=True)
    if not ((length > 1e-150) & (length < 1e150)).all():
        # The squares of a huge normal (1e200) overflowed, or those of a tiny one (1e-170)
        # underflowed to 0: each is scaled by its largest component first (3x slower).
        largest = np.abs(normals).max(axis=2, keepdims=True)
        normals = np.divide(normals, largest, out=np.zeros(normals.shape), where=largest > 0)
        length = np.linalg.norm(normals, axis=2, keepdims=True)
    if (length > 0).all():
        return normals / length
    face = face_normals_unnormalised(triangles)
    face_length = np.linalg.norm(face, axis=1, keepdims=True)
    face = np.divide(face, face_length, out=np.zeros_like(face), where=face_length > 0)
    return np.where(length > 0, normals / np.where(length > 0, length, 1), face[:, None, :])
