"""PLY files: read by trimesh, checked against their header, triangle strips read here.

A PLY file is a header, which announces each element (vertices, faces, ...), how many of it
and its properties, then the elements' data, as text or binary (Turk, "The PLY Polygon File
Format", 1994). trimesh reads the data (``trimesh.exchange.ply.load_ply``, which also keeps
it raw, element by element) but forgives too much: a text file cut short loses its last
faces without a word, and a binary one fails with "list index out of range". Here the
header is read too, and what trimesh found is held against it, so that such a file is an
error that says what is missing.

What the file says of its surface: vertex normals (``nx``, ``ny``, ``nz``; trimesh gives
them only when the file has them), texture coordinates per vertex (``u``/``v``, ``s``/``t``)
or per face corner (a face's ``texcoord`` list), a texture image (``comment TextureFile``),
and faces given as triangle strips (an element ``tristrips``, strips of vertex indices
separated by -1, as some scanners write), which trimesh does not read.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.meshes.base import FileMaterial, IndexedMesh

#: Bytes per value of each PLY property type.
TYPE_SIZES = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "int32", "uint32", "float", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}
#: Vertex properties that colour a mesh, which ptlab does not use.
COLOUR_PROPERTIES = {"red", "green", "blue", "r", "g", "b", "diffuse_red", "diffuse_green", "diffuse_blue"}


@dataclass
class PlyElement:
    """An element the header announces: its name, how many, and its properties (name, and
    for a list the size of its count's type, else None)."""

    name: str
    count: int
    properties: list[tuple[str, str, int | None]]

    def least_bytes(self) -> int:
        """The fewest bytes this element's binary data can take (each list empty)."""
        per = sum(
            TYPE_SIZES.get(kind, 0) if counted is None else counted for _, kind, counted in self.properties
        )
        return self.count * per


@dataclass
class PlyHeader:
    """A PLY file's header: its format, its elements, its texture images, where data starts."""

    ascii: bool
    elements: list[PlyElement]
    texture_files: list[str]
    data_start: int

    def announces(self) -> str:
        """The elements it announces, in words: "8 `vertex` and 12 `face` elements"."""
        counts = [f"{element.count} `{element.name}`" for element in self.elements]
        return " and ".join([", ".join(counts[:-1]), counts[-1]] if len(counts) > 1 else counts) + " elements"


def read_ply(data: bytes, folder: Path) -> IndexedMesh:
    """The mesh of a PLY file's bytes (a texture image looked for in ``folder``), or
    ``ValueError`` for a file that is not PLY, is cut short or does not match its header."""
    header = ply_header(data)
    import trimesh

    try:
        # (No resolver: the texture image is ptlab's to read. fix_texture=False keeps the
        # vertices as they are: per-corner texture coordinates are taken from the raw data.)
        found = trimesh.exchange.ply.load_ply(io.BytesIO(data), resolver=None, fix_texture=False)
    except Exception as error:  # trimesh raises many kinds for data that does not fit
        raise ValueError(_misfit(header, len(data) - header.data_start, error)) from None
    raw = found.get("metadata", {}).get("_ply_raw", {})
    for element in header.elements:
        read = _rows(raw.get(element.name, {}).get("data"))
        if read < element.count:
            raise ValueError(
                f"truncated: its header announces {header.announces()}, but the file holds "
                f"{read} `{element.name}`"
            )
    vertices = np.asarray(found.get("vertices", np.zeros((0, 3))), dtype=np.float64)
    faces = found.get("faces")
    unused = []
    if "tristrips" in raw:
        strips = strip_triangles(_lists(raw["tristrips"]["data"]))
        faces = strips if faces is None or len(faces) == 0 else np.concatenate([faces, strips])
    faces = np.zeros((0, 3), dtype=np.int64) if faces is None else np.asarray(faces)
    normals = found.get("vertex_normals")
    uv = _texture_coordinates(raw, found, faces)
    vertex_properties = next((e.properties for e in header.elements if e.name == "vertex"), [])
    if COLOUR_PROPERTIES & {name for name, _, _ in vertex_properties}:
        unused.append("vertex colours")
    materials, material_ids = [], None
    if header.texture_files:
        texture = folder / header.texture_files[0]
        if uv is None:
            unused.append(f"texture {header.texture_files[0]} (the file has no texture coordinates)")
        else:
            materials = [FileMaterial(Path(texture).stem, None, texture, "its header (TextureFile)")]
            material_ids = np.zeros(len(faces), dtype=np.intp)
    return IndexedMesh(
        vertices=vertices,
        faces=faces,
        uv=uv,
        normals=None if normals is None else np.asarray(normals, dtype=np.float64),
        material_ids=material_ids,
        materials=materials,
        unused=unused,
    )


def ply_header(data: bytes) -> PlyHeader:
    """The header of a PLY file's bytes, or ``ValueError`` if it has none."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply"):
        raise ValueError("not a PLY file (it does not start with `ply`)")
    if end < 0:
        raise ValueError("truncated or malformed: its header has no `end_header` line")
    data_start = data.index(b"\n", end) + 1 if b"\n" in data[end:] else len(data)
    lines = data[:end].decode("ascii", errors="replace").splitlines()
    elements: list[PlyElement] = []
    texture_files = []
    is_ascii = False
    for line in lines:
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            is_ascii = words[1:2] == ["ascii"]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append(PlyElement(words[1], int(words[2]), []))
        elif words[0] == "property" and elements:
            if words[1:2] == ["list"] and len(words) == 5:
                elements[-1].properties.append((words[4], words[3], TYPE_SIZES.get(words[2], 0)))
            elif len(words) == 3:
                elements[-1].properties.append((words[2], words[1], None))
        elif words[0] in ("comment", "obj_info") and words[1:2] == ["TextureFile"]:
            texture_files.append(line.split("TextureFile", 1)[1].strip())
    return PlyHeader(is_ascii, elements, texture_files, data_start)


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


def _rows(data) -> int:
    """How many rows trimesh read of an element (a structured array, or a dict of arrays)."""
    if data is None:
        return 0
    if isinstance(data, dict):
        return min((len(values) for values in data.values()), default=0)
    return len(data)


def _lists(data) -> list[np.ndarray]:
    """The rows of an element's one list property, as trimesh keeps them raw: a dict of one
    array (text files) or a structured array whose field holds (count, values) (binary)."""
    values = next(iter(data.values())) if isinstance(data, dict) else data[data.dtype.names[0]]["f1"]
    if isinstance(values, np.ndarray) and values.dtype != object:
        return list(np.atleast_2d(values).astype(np.int64))
    return [np.asarray(row, dtype=np.int64).ravel() for row in values]


def _texture_coordinates(raw: dict, found: dict, faces: np.ndarray) -> np.ndarray | None:
    """(T, 3, 2) per-corner texture coordinates from the faces' ``texcoord`` lists, or (V, 2)
    per-vertex ones (``u``/``v``, ``s``/``t``) as trimesh found them, or None."""
    face = raw.get("face", {}).get("data")
    names = face.dtype.names if isinstance(face, np.ndarray) else tuple(face or ())
    if face is not None and "texcoord" in names:
        texcoord = face["texcoord"]["f1"] if isinstance(face, np.ndarray) else face["texcoord"]
        texcoord = np.asarray(texcoord, dtype=np.float64)
        if texcoord.ndim == 2 and texcoord.shape == (len(faces), 6):
            return texcoord.reshape(-1, 3, 2)
        return None
    visual = found.get("visual")
    uv = getattr(visual, "uv", None)
    return None if uv is None else np.asarray(uv, dtype=np.float64)[:, :2]


def _misfit(header: PlyHeader, data_bytes: int, error: Exception) -> str:
    """Why trimesh could not read a PLY file's data, in words: cut short, or not as its header
    says."""
    if not header.ascii:
        least = sum(element.least_bytes() for element in header.elements)
        if data_bytes < least:
            return (
                f"truncated: its header announces {header.announces()}, which take at least "
                f"{least} bytes, but the file holds {data_bytes} bytes of data"
            )
    return (
        f"truncated or malformed: its data does not match its header, which announces "
        f"{header.announces()} (trimesh: {error})"
    )
