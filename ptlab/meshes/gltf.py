"""glTF 2.0 files (``.gltf``, ``.glb``): triangles placed by their nodes, vertex normals,
texture coordinates and base colours, read here from the file's own JSON and buffers.

A glTF file is JSON that describes a scene (Khronos, "glTF 2.0 Specification", 2021): nodes,
each with a transform and maybe a mesh; meshes of primitives, each a set of vertex attributes
(``POSITION``, ``NORMAL``, ``TEXCOORD_0``, ...) with its indices and material; the numbers
themselves in binary buffers, reached through accessors and buffer views. A ``.glb`` file
holds the JSON and one buffer in one binary container.

ptlab reads it itself rather than through trimesh, whose reader rounds each material's
colour factor to 8 bits, needs Pillow (not one of ptlab's dependencies) for any material at
all, skips triangle fans, drops a missing image silently and makes up normals where the file
has none. Read here:

* every primitive of mode triangles, triangle strip or fan (section 3.7.2.1), placed by its
  node's world transform (the product of the transforms from the scene's root, section
  3.5.3); normals by the inverse transpose of it (by its cofactors where a scale of 0 leaves
  it no inverse), and a transform that mirrors turns the triangles' order so that their front
  stays where the normals say (section 3.7.4); only the vertices a primitive's indices use;
* ``NORMAL`` where a primitive has it (never made up: such a primitive is flat-shaded);
* the texture coordinates its base colour texture uses (``TEXCOORD_n``), turned to OBJ's
  convention: glTF's origin is the image's top-left corner with v down (section 3.7.2.1),
  ptlab's (and OBJ's) the bottom-left with v up, so v becomes 1 - v;
* each material's ``baseColorFactor`` and ``baseColorTexture`` (section 3.9.2): the base
  colour is their product; the image is a file beside the glTF file or the bytes of one it
  holds.

What else it brings (metallic-roughness, normal and occlusion maps, emission, transparency,
vertex colours, points and lines, animations, cameras, extensions it may use) is named in
``unused``. A file that requires an extension ptlab does not implement (``extensionsRequired``,
section 3.12) is refused, as is any property of the wrong JSON type: every message names the
property by its path in the JSON (``nodes[2].children``).
"""

from __future__ import annotations

import base64
import contextlib
import json
import math
import struct
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from ptlab.errors import PtlabError, is_integer
from ptlab.meshes.base import FileMaterial, IndexedMesh
from ptlab.meshes.ply import strip_triangles

#: Accessor component types (section 3.6.2.2) and their NumPy types (little-endian).
COMPONENT_TYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
#: The component types that indices may have: unsigned integers (the schemas of a primitive's
#: ``indices`` and of a sparse accessor's, ``accessor.sparse.indices``).
INDEX_TYPES = (5121, 5123, 5125)
#: Values per element of each accessor type.
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
#: Primitive modes (section 3.7.2.1).
POINTS_AND_LINES, TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = (0, 1, 2, 3), 4, 5, 6
#: The extensions a file may require that ptlab implements: quantized attributes are accessors
#: of integer types, which every accessor here may be.
IMPLEMENTED = {"KHR_mesh_quantization"}
#: Extensions used that need no word: implemented, or their only effect is noted elsewhere
#: (emission, of which ptlab reads none, is named by the material).
SILENT = IMPLEMENTED | {"KHR_materials_emissive_strength"}
#: A GLB container's magic number and chunk types (section 4.4).
GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = b"glTF", 0x4E4F534A, 0x004E4942
#: The file extension of an embedded image, by its MIME type.
IMAGE_SUFFIXES = {"image/png": ".png", "image/jpeg": ".jpg", "image/webp": ".webp", "image/ktx2": ".ktx2"}
#: The texture sampler's wrap mode that ``ptlab.textures.ImageTexture`` uses: REPEAT.
REPEAT = 10497
#: How messages name each JSON type that ``_checked`` knows.
KIND_NAMES = {
    "object": "an object",
    "list": "a list",
    "string": "a string",
    "number": "a finite number",
    "integer": "an integer",
    "boolean": "true or false",
}
#: ``_field``'s default for a property the file must have.
REQUIRED: Any = object()


def read_gltf(data: bytes, folder: Path, binary: bool) -> IndexedMesh:
    """The mesh of a ``.gltf`` (``binary`` False) or ``.glb`` file's bytes, its external
    buffers and images looked for in ``folder``; ``ValueError`` for what cannot be read."""
    document, chunk = _glb(data) if binary else (_json(data), None)
    return GltfReader(document, folder, chunk, len(data)).mesh()


# -- the JSON, its types checked as it is read --------------------------------------------------


def _path(where: str, key: str | int) -> str:
    """The JSON path of ``key`` in the value at ``where`` (``nodes[2]`` + ``children``)."""
    if isinstance(key, int):
        return f"{where}[{key}]"
    return f"{where}.{key}" if where else key


def _shown(value: object) -> str:
    """``value`` as JSON, cut short."""
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _checked(value: Any, where: str, kind: str, minimum: int | None = None) -> Any:
    """``value`` (at JSON path ``where``) if it is of JSON type ``kind`` (``KIND_NAMES``) and at
    least ``minimum``, or ``ValueError``. An integer may be written 4.0 (section 2.7, item 5), so
    a whole float is taken as its int; ``true`` is no integer (a bool is an int to Python)."""
    if kind == "integer" and isinstance(value, float) and value.is_integer():
        value = int(value)
    fits = {
        "object": isinstance(value, dict),
        "list": isinstance(value, list),
        "string": isinstance(value, str),
        "boolean": isinstance(value, bool),
        "integer": is_integer(value),
        "number": _is_finite_number(value),
    }[kind]
    if fits and minimum is not None and value < minimum:
        fits = False
    if not fits:
        wanted = KIND_NAMES[kind] + ("" if minimum is None else f" of at least {minimum}")
        raise ValueError(f"{where} is {_shown(value)}, not {wanted}")
    return value


def _is_finite_number(value: object) -> bool:
    """True for an int or float that is finite as a float (JSON's 1e400 is not; a bool is no
    number)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # (an int too large for a float)
        return False


def _field(
    holder: dict, key: str, where: str, kind: str, default: Any = REQUIRED, minimum: int | None = None
) -> Any:
    """Property ``key`` of the JSON object ``holder`` (at path ``where``), ``_checked``;
    ``default`` where it is absent (``ValueError`` if that is ``REQUIRED``)."""
    if key not in holder:
        if default is REQUIRED:
            raise ValueError(f"{where or 'the file'} has no {key}")
        return default
    return _checked(holder[key], _path(where, key), kind, minimum)


def _numbers(holder: dict, key: str, where: str, length: int, default: list[float] | None) -> np.ndarray:
    """(length,) float64: property ``key`` of ``holder``, a list of ``length`` finite numbers."""
    values = _field(holder, key, where, "list", default)
    if len(values) != length:
        raise ValueError(f"{_path(where, key)} has {len(values)} numbers, not {length}")
    return np.array(
        [_checked(v, _path(_path(where, key), k), "number") for k, v in enumerate(values)], dtype=np.float64
    )


def _index_list(holder: dict, key: str, where: str) -> list[int]:
    """Property ``key`` of ``holder``: a list of indices (integers 0 or more), empty if absent."""
    entries = _field(holder, key, where, "list", [])
    return [_checked(k, _path(_path(where, key), i), "integer", minimum=0) for i, k in enumerate(entries)]


def _json(data: bytes) -> dict:
    """The JSON object of a glTF file, or ``ValueError``."""
    try:
        document = json.loads(data.decode("utf-8-sig"))
    except (ValueError, RecursionError) as error:  # (a JSONDecodeError is a ValueError)
        raise ValueError(f"not glTF JSON ({error})") from None
    if not isinstance(document, dict):
        raise ValueError("not glTF JSON (not an object)")
    version = _field(_field(document, "asset", "", "object", {}), "version", "asset", "string", "")
    if not version.startswith("2."):
        raise ValueError(f"glTF version {version or 'unknown'}; ptlab reads glTF 2.0")
    return document


def _glb(data: bytes) -> tuple[dict, bytes | None]:
    """The JSON object and binary chunk of a GLB container, or ``ValueError``."""
    if len(data) < 20 or data[:4] != GLB_MAGIC:
        raise ValueError("not a binary glTF file (it does not start with `glTF`)")
    version, length = struct.unpack_from("<II", data, 4)
    if version != 2:
        raise ValueError(f"binary glTF version {version}; ptlab reads glTF 2.0")
    if length > len(data):
        raise ValueError(f"truncated: its header says {length} bytes, the file has {len(data)}")
    document, chunk, offset = None, None, 12
    while offset + 8 <= length:
        size, kind = struct.unpack_from("<II", data, offset)
        body = data[offset + 8 : offset + 8 + size]
        if len(body) < size:
            raise ValueError("truncated: a chunk runs past the end of the file")
        if kind == JSON_CHUNK and document is None:
            document = _json(body)
        elif kind == BIN_CHUNK and chunk is None:
            chunk = body
        offset += 8 + size
    if document is None:
        raise ValueError("no JSON chunk")
    return document, chunk


# -- accessors, described before their values are read ------------------------------------------


@dataclass(frozen=True)
class Sparse:
    """The ``sparse`` part of an accessor (section 3.6.2.3): ``count`` values that replace
    those at ``count`` strictly increasing indices."""

    where: str
    count: int
    index_view: int
    index_offset: int
    index_dtype: np.dtype
    value_view: int
    value_offset: int


@dataclass(frozen=True)
class Accessor:
    """An accessor's description (section 3.6.2), checked; its values not yet read."""

    where: str  # (its JSON path, ``accessors[3]``)
    dtype: np.dtype
    width: int
    count: int
    view: int | None  # (None: the values are zeros, sparse ones put in place)
    offset: int
    normalized: bool
    sparse: Sparse | None

    @property
    def zeros_nbytes(self) -> int:
        """The bytes of its values where it has no buffer view: zeros, stored nowhere."""
        return 0 if self.view is not None else self.count * self.width * self.dtype.itemsize


class GltfReader:
    """Reads one glTF document: its buffers, accessors, nodes and materials."""

    def __init__(self, document: dict, folder: Path, chunk: bytes | None, size: int):
        self.document, self.folder, self.chunk, self.size = document, folder, chunk, size
        self.buffers: dict[int, bytes] = {}
        self.zeros_read = 0  # (bytes of accessors without a buffer view, ``check_zeros``)
        self.unused: list[str] = []
        required = [
            _checked(name, f"extensionsRequired[{k}]", "string")
            for k, name in enumerate(self.listed("extensionsRequired"))
        ]
        for name in required:
            if name not in IMPLEMENTED:
                # (Section 3.12: an extension is required where the file cannot be loaded
                # right without it; ptlab does not make up what it would have meant.)
                raise ValueError(
                    f"requires the glTF extension {name} (extensionsRequired), which ptlab does not implement"
                )

    def listed(self, key: str) -> list:
        """The document's top-level list ``key`` ("accessors", ...), empty where it has none."""
        return _field(self.document, key, "", "list", [])

    def entry(self, kind: str, index: int, where: str) -> dict:
        """Entry ``index`` of the document's list ``kind``, which the property at ``where``
        refers to; ``ValueError`` if there is none or it is no object."""
        entries = self.listed(kind)
        if index >= len(entries):
            raise ValueError(f"{where} refers to {kind}[{index}], which the file does not have")
        return _checked(entries[index], f"{kind}[{index}]", "object")

    def target(self, holder: dict, key: str, where: str, kind: str) -> tuple[dict, str, int]:
        """The entry of list ``kind`` that property ``key`` of ``holder`` (at ``where``) refers
        to, its JSON path and its index."""
        index = _field(holder, key, where, "integer", minimum=0)
        return self.entry(kind, index, _path(where, key)), f"{kind}[{index}]", index

    def note(self, phrase: str) -> None:
        """Add ``phrase`` to what ptlab does not use, once."""
        if phrase not in self.unused:
            self.unused.append(phrase)

    def mesh(self) -> IndexedMesh:
        """Every triangle of the default scene, placed, with its normals, uv and material."""
        parts = []
        materials_used: dict[int, int] = {}  # (the file's index -> the mesh's)
        for node, where, matrix in self.placed_nodes():
            if "camera" in node:
                self.note("cameras")
            if "mesh" not in node:
                continue
            mesh, mesh_where, _ = self.target(node, "mesh", where, "meshes")
            for k, primitive in enumerate(_field(mesh, "primitives", mesh_where, "list", [])):
                primitive_where = f"{mesh_where}.primitives[{k}]"
                primitive = _checked(primitive, primitive_where, "object")
                part = self.primitive(primitive, primitive_where, matrix)
                if part is not None:
                    material = _field(primitive, "material", primitive_where, "integer", None, minimum=0)
                    index = (
                        -1 if material is None else materials_used.setdefault(material, len(materials_used))
                    )
                    parts.append((*part, index))
        for key, phrase in (("animations", "animations"), ("skins", "skins")):
            if self.document.get(key):
                self.note(phrase)
        for k, extension in enumerate(self.listed("extensionsUsed")):
            if _checked(extension, f"extensionsUsed[{k}]", "string") not in SILENT:
                self.note(f"the glTF extension {extension}")
        materials = [self.material(index) for index in materials_used]
        if not parts:
            return IndexedMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), unused=self.unused)
        return self.joined(parts, materials)

    def joined(self, parts: list, materials: list[FileMaterial]) -> IndexedMesh:
        """One mesh of the primitives' (vertices, faces, normals, uv, material) parts."""
        offsets = np.cumsum([0] + [len(vertices) for vertices, *_ in parts])
        faces = np.concatenate(
            [faces + offset for (_, faces, *_), offset in zip(parts, offsets, strict=False)]
        )
        vertices = np.concatenate([vertices for vertices, *_ in parts])

        def joined_attribute(k: int, width: int) -> np.ndarray | None:
            """Attribute k of every part, zeros where a part lacks it; None if all lack it."""
            if all(part[k] is None for part in parts):
                return None
            return np.concatenate([np.zeros((len(p[0]), width)) if p[k] is None else p[k] for p in parts])

        # (A primitive without normals, beside some with, gets 0s, which become its faces'
        # normals: it stays flat, ``ptlab.meshes.base.unit_corner_normals``.)
        normals = joined_attribute(2, 3)
        material_ids = np.concatenate([np.full(len(faces), index) for (_, faces, *_, index) in parts])
        return IndexedMesh(
            vertices=vertices,
            faces=faces,
            uv=joined_attribute(3, 2),
            normals=normals,
            material_ids=material_ids.astype(np.intp) if materials else None,
            materials=materials,
            unused=self.unused,
        )

    def placed_nodes(self) -> Iterator[tuple[dict, str, np.ndarray]]:
        """(node, its JSON path, (4, 4) world transform) of every node of the default scene,
        depth first."""
        nodes = self.listed("nodes")
        if self.listed("scenes"):
            scene = _field(self.document, "scene", "", "integer", 0, minimum=0)
            roots = _index_list(self.entry("scenes", scene, "scene"), "nodes", f"scenes[{scene}]")
            where_roots = f"scenes[{scene}].nodes"
        else:  # (no scene: every node that is nobody's child)
            has_parent = {
                child
                for k in range(len(nodes))
                for child in _index_list(self.entry("nodes", k, "nodes"), "children", f"nodes[{k}]")
            }
            roots = [k for k in range(len(nodes)) if k not in has_parent]
            where_roots = "nodes"
        stack = [(root, f"{where_roots}[{k}]", np.eye(4)) for k, root in reversed(list(enumerate(roots)))]
        visited = 0
        while stack:
            index, reference, parent = stack.pop()
            node, where = self.entry("nodes", index, reference), f"nodes[{index}]"
            visited += 1
            if visited > len(nodes):
                raise ValueError("its nodes form a cycle")
            with np.errstate(over="ignore", invalid="ignore"):  # (refused below, in the file's terms)
                matrix = parent @ _local_transform(node, where)
            if not np.isfinite(matrix).all():
                raise ValueError(f"{where} is placed by a transform too large for 64-bit floats")
            yield node, where, matrix
            children = _index_list(node, "children", where)
            stack.extend(
                (child, f"{where}.children[{k}]", matrix) for k, child in reversed(list(enumerate(children)))
            )

    def primitive(self, primitive: dict, where: str, matrix: np.ndarray):
        """(vertices, faces, normals or None, uv or None) of one primitive (at ``where``),
        placed by ``matrix``; None for one that is not made of triangles."""
        mode = _field(primitive, "mode", where, "integer", TRIANGLES)
        if mode in POINTS_AND_LINES:
            self.note("points and lines")
            return None
        if mode not in (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN):
            raise ValueError(f"{where}.mode is {mode}, which glTF does not define")
        attributes = _field(primitive, "attributes", where, "object", {})
        if "POSITION" not in attributes:
            return None  # (section 3.7.2.1: without positions a primitive is skipped)
        uv_name = f"TEXCOORD_{self.texture_coordinate_set(primitive, where)}"
        read, index_list = self.accessors_of(primitive, where, attributes, uv_name)
        count = read["POSITION"].count
        # (Only the vertices that the indices use are read: primitives that share one large
        # vertex accessor, or nodes that place one mesh many times, would each copy all of it.)
        order, used = _compacted(self.vertex_indices(index_list, count, where), count)
        faces = _faces(order, mode)
        if "targets" in primitive:
            self.note("morph targets")
        if any(name.startswith("COLOR_") for name in attributes):
            self.note("vertex colours (COLOR_0)")
        linear = matrix[:3, :3]
        with np.errstate(over="ignore", invalid="ignore"):  # (``read_mesh_data`` names what overflows)
            vertices = self.values(read["POSITION"], used) @ linear.T + matrix[:3, 3]
        normals = None
        if "NORMAL" in read:
            normals = self.values(read["NORMAL"], used) @ _normal_transform(linear).T
        if _determinant_sign(linear) < 0:
            faces = faces[:, [0, 2, 1]]  # (a mirror: keep the front where the normals are)
        uv = None
        if uv_name in read:
            uv = self.values(read[uv_name], used)
            uv[:, 1] = 1.0 - uv[:, 1]  # (glTF's v runs down the image, OBJ's and ptlab's up)
        return vertices, faces, normals, uv

    def accessors_of(
        self, primitive: dict, where: str, attributes: dict, uv_name: str
    ) -> tuple[dict[str, Accessor], Accessor | None]:
        """The accessors a primitive's triangles are read from: its attributes that ptlab uses
        (by name) and its indices (or None). Every one is described, and its count checked,
        before any values are read: a count the rest of the file does not bear out is refused
        before it is allocated."""
        in_attributes = f"{where}.attributes"
        read = {
            name: self.described(attributes, name, in_attributes, kind)
            for name, kind in (("POSITION", "VEC3"), ("NORMAL", "VEC3"), (uv_name, "VEC2"))
            if name in attributes
        }
        count = read["POSITION"].count
        for name, accessor in read.items():
            if accessor.count != count:
                raise ValueError(
                    f"{in_attributes}: {name} has {accessor.count} values, POSITION {count} "
                    f"(a primitive's attributes have one count, section 3.7.2.1)"
                )
        index_list = None
        if "indices" in primitive:
            index_list = self.described(primitive, "indices", where, "SCALAR", INDEX_TYPES)
        self.check_zeros([*read.values(), *([index_list] if index_list else [])])
        return read, index_list

    def vertex_indices(self, index_list: Accessor | None, count: int, where: str) -> np.ndarray:
        """(n,) int64 the vertices of a primitive (at ``where``) of ``count`` vertices in the
        order its mode takes them: its indices, or every vertex in turn without them."""
        if index_list is None:
            return np.arange(count)
        vertex_indices = self.values(index_list).astype(np.int64)[:, 0]
        if len(vertex_indices) and vertex_indices.max() >= count:
            raise ValueError(
                f"{where}.indices ({index_list.where}) holds vertex {vertex_indices.max()}, "
                f"but the primitive has {count} vertices"
            )
        return vertex_indices

    def texture_coordinate_set(self, primitive: dict, where: str) -> int:
        """The ``TEXCOORD_n`` set that a primitive's base colour texture uses (0 without one)."""
        if "material" not in primitive:
            return 0
        material, material_where, _ = self.target(primitive, "material", where, "materials")
        pbr_where = _path(material_where, "pbrMetallicRoughness")
        pbr = _field(material, "pbrMetallicRoughness", material_where, "object", {})
        texture = _field(pbr, "baseColorTexture", pbr_where, "object", {})
        return _field(texture, "texCoord", _path(pbr_where, "baseColorTexture"), "integer", 0, minimum=0)

    def material(self, index: int) -> FileMaterial:
        """Material ``index`` as a ``FileMaterial``, what ptlab does not use of it noted."""
        where = f"materials[{index}]"
        material = self.entry("materials", index, where)
        name = _field(material, "name", where, "string", f"material {index}")
        pbr_where = _path(where, "pbrMetallicRoughness")
        pbr = _field(material, "pbrMetallicRoughness", where, "object", {})
        factor = _numbers(pbr, "baseColorFactor", pbr_where, 4, [1.0, 1.0, 1.0, 1.0])
        metallic = _field(pbr, "metallicFactor", pbr_where, "number", 1.0)
        roughness = _field(pbr, "roughnessFactor", pbr_where, "number", 1.0)
        if metallic != 0 or roughness != 1 or "metallicRoughnessTexture" in pbr:
            self.note("glTF metallic-roughness")
        for key, phrase in (
            ("normalTexture", "normal map (normalTexture)"),
            ("occlusionTexture", "occlusion map (occlusionTexture)"),
            ("emissiveTexture", "emission (emissiveTexture)"),
        ):
            if key in material:
                self.note(phrase)
        if _numbers(material, "emissiveFactor", where, 3, [0.0, 0.0, 0.0]).any():
            self.note("emission (emissiveFactor)")
        alpha_mode = _field(material, "alphaMode", where, "string", "OPAQUE")
        if alpha_mode != "OPAQUE":
            self.note(f"transparency (alphaMode {alpha_mode})")
        for extension in _field(material, "extensions", where, "object", {}):
            self.note(f"the glTF extension {extension}")
        texture = None
        if "baseColorTexture" in pbr:
            info = _field(pbr, "baseColorTexture", pbr_where, "object")
            texture = self.image_of(info, _path(pbr_where, "baseColorTexture"), name)
        return FileMaterial(name, factor[:3], texture, f"glTF material {index}")

    def image_of(self, info: dict, where: str, material: str) -> Path | np.ndarray | None:
        """The image of a texture reference (at ``where``): a file, or the pixels of one the
        file holds."""
        texture, texture_where, _ = self.target(info, "index", where, "textures")
        extensions = _field(info, "extensions", where, "object", {})
        if extensions:
            self.note(f"texture transforms of material {material!r} ({', '.join(extensions)})")
        if "sampler" in texture:
            sampler, sampler_where, _ = self.target(texture, "sampler", texture_where, "samplers")
            wraps = [_field(sampler, key, sampler_where, "integer", REPEAT) for key in ("wrapS", "wrapT")]
            if wraps != [REPEAT, REPEAT]:
                self.note("texture wrap modes other than repeat (sampler)")
        if "source" not in texture:
            self.note(f"the base colour image of material {material!r} (in a format of an extension)")
            return None
        image, image_where, _ = self.target(texture, "source", texture_where, "images")
        uri = _field(image, "uri", image_where, "string", None)
        if uri is not None and not uri.startswith("data:"):
            return self.folder / unquote(uri)
        if uri is not None:
            data = self.uri_bytes(uri, _path(image_where, "uri"))
        elif "bufferView" in image:
            data = self.view_bytes(
                _field(image, "bufferView", image_where, "integer", minimum=0),
                _path(image_where, "bufferView"),
            )
        else:
            raise ValueError(f"{image_where} has neither a uri nor a bufferView")
        mime_type = _field(image, "mimeType", image_where, "string", "")
        try:
            return _decoded(data, IMAGE_SUFFIXES.get(mime_type, ".png"))
        except PtlabError:
            raise ValueError(
                f"holds a base colour image ({image_where}, material {material!r}) that cannot be read"
            ) from None

    def described(
        self, holder: dict, key: str, where: str, kind: str, components: tuple[int, ...] | None = None
    ) -> Accessor:
        """The accessor that property ``key`` of ``holder`` (at ``where``) refers to, which must
        be of type ``kind`` and, if given, of one of the ``components`` types."""
        accessor, at, _ = self.target(holder, key, where, "accessors")
        component = _field(accessor, "componentType", at, "integer")
        if component not in COMPONENT_TYPES:
            raise ValueError(f"{at}.componentType is {component}, which glTF does not define")
        if components is not None and component not in components:
            raise ValueError(
                f"{_path(where, key)} is {at}, of componentType {component}: it must be unsigned "
                f"integers ({', '.join(map(str, components))})"
            )
        type_name = _field(accessor, "type", at, "string")
        if type_name not in TYPE_SIZES:
            raise ValueError(f"{at}.type is {_shown(type_name)}, which glTF does not define")
        if type_name != kind:
            raise ValueError(f"{_path(where, key)} is {at}, of type {type_name}: it must be {kind}")
        count = _field(accessor, "count", at, "integer", minimum=0)
        sparse = None
        if "sparse" in accessor:
            sparse = self.described_sparse(
                _field(accessor, "sparse", at, "object"), _path(at, "sparse"), count
            )
        return Accessor(
            where=at,
            dtype=np.dtype(COMPONENT_TYPES[component]),
            width=TYPE_SIZES[type_name],
            count=count,
            view=_field(accessor, "bufferView", at, "integer", None, minimum=0),
            offset=_field(accessor, "byteOffset", at, "integer", 0, minimum=0),
            normalized=_field(accessor, "normalized", at, "boolean", False),
            sparse=sparse,
        )

    @staticmethod
    def described_sparse(sparse: dict, where: str, count: int) -> Sparse:
        """The ``sparse`` object (at ``where``) of an accessor of ``count`` values."""
        sparse_count = _field(sparse, "count", where, "integer", minimum=1)
        if sparse_count > count:
            raise ValueError(f"{where}.count is {sparse_count}, more than the accessor's {count} values")
        index_where, value_where = _path(where, "indices"), _path(where, "values")
        index_part = _field(sparse, "indices", where, "object")
        value_part = _field(sparse, "values", where, "object")
        component = _field(index_part, "componentType", index_where, "integer")
        if component not in INDEX_TYPES:
            raise ValueError(
                f"{index_where}.componentType is {component}: sparse indices are unsigned "
                f"integers (5121, 5123 or 5125)"
            )
        return Sparse(
            where=where,
            count=sparse_count,
            index_view=_field(index_part, "bufferView", index_where, "integer", minimum=0),
            index_offset=_field(index_part, "byteOffset", index_where, "integer", 0, minimum=0),
            index_dtype=np.dtype(COMPONENT_TYPES[component]),
            value_view=_field(value_part, "bufferView", value_where, "integer", minimum=0),
            value_offset=_field(value_part, "byteOffset", value_where, "integer", 0, minimum=0),
        )

    def check_zeros(self, accessors: list[Accessor]) -> None:
        """Refuse accessors without a buffer view (zeros, section 3.6.2.3) that would take more
        bytes than the file and its buffer files hold: nothing in the file bears such a count
        out, and reading it would fill the memory with zeros."""
        zeros = sum(accessor.zeros_nbytes for accessor in accessors)
        if not zeros:
            return
        held = self.size
        for buffer in self.listed("buffers"):
            uri = buffer.get("uri") if isinstance(buffer, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:"):
                with contextlib.suppress(OSError):  # (a buffer that cannot be read holds nothing)
                    held += (self.folder / unquote(uri)).stat().st_size
        self.zeros_read += zeros  # (counted over the whole file: instances read theirs again)
        if self.zeros_read > held:
            first = next(accessor for accessor in accessors if accessor.zeros_nbytes)
            raise ValueError(
                f"{first.where} has no bufferView and a count of {first.count}: its zeros "
                f"({self.zeros_read} bytes) are more than the {held} bytes of the file and its buffers"
            )

    def values(self, accessor: Accessor, rows: np.ndarray | None = None) -> np.ndarray:
        """(count, n) float64 values of an accessor (section 3.6.2), normalised integers made
        fractions, sparse values put in place; only those of ``rows`` where given."""
        if accessor.view is None:
            result = np.zeros((accessor.count, accessor.width))
        else:
            stored = self.strided(
                accessor.view, accessor.offset, accessor.dtype, accessor.count, accessor.width, accessor.where
            )
            if rows is not None and accessor.sparse is None:
                stored, rows = stored[rows], None  # (only those rows copied)
            result = stored.astype(np.float64)
        sparse = accessor.sparse
        if sparse is not None:
            replaced = self.strided(
                sparse.index_view,
                sparse.index_offset,
                sparse.index_dtype,
                sparse.count,
                1,
                _path(sparse.where, "indices"),
            )[:, 0]
            if replaced.max() >= accessor.count:
                raise ValueError(
                    f"{sparse.where}.indices holds index {replaced.max()}, but the accessor has "
                    f"{accessor.count} values"
                )
            result[replaced] = self.strided(
                sparse.value_view,
                sparse.value_offset,
                accessor.dtype,
                sparse.count,
                accessor.width,
                _path(sparse.where, "values"),
            )
        if accessor.normalized and accessor.dtype.kind in "iu":
            # (Section 3.11: unsigned c / (2^n - 1); signed max(c / (2^(n-1) - 1), -1).)
            result = np.maximum(result / np.iinfo(accessor.dtype).max, -1.0)
        return result if rows is None else result[rows]

    def strided(
        self, view_index: int, offset: int, dtype: np.dtype, count: int, width: int, where: str
    ) -> np.ndarray:
        """(count, width) values of type ``dtype`` from buffer view ``view_index`` (which the
        property at ``where`` names), from byte ``offset`` on, at the view's stride (or packed);
        a view of the buffer, no copy."""
        view_where = f"bufferViews[{view_index}]"
        view = self.entry("bufferViews", view_index, _path(where, "bufferView"))
        _, _, buffer_index = self.target(view, "buffer", view_where, "buffers")
        data = self.buffer(buffer_index)
        view_offset = _field(view, "byteOffset", view_where, "integer", 0, minimum=0)
        size = dtype.itemsize * width
        stride = _field(view, "byteStride", view_where, "integer", size, minimum=size)
        end = view_offset + _field(view, "byteLength", view_where, "integer", minimum=0)
        start = view_offset + offset
        if count == 0:
            return np.zeros((0, width), dtype=dtype)
        if start + stride * (count - 1) + size > min(end, len(data)):
            raise ValueError(
                f"truncated or malformed: {view_where} does not hold the {count} values {where} asks of it"
            )
        return np.ndarray(
            (count, width), dtype=dtype, buffer=data, offset=start, strides=(stride, dtype.itemsize)
        )

    def buffer(self, index: int) -> bytes:
        """The bytes of buffer ``index``: the GLB's binary chunk, a data URI's, or a file's."""
        if index in self.buffers:
            return self.buffers[index]
        where = f"buffers[{index}]"
        buffer = self.entry("buffers", index, where)
        uri = _field(buffer, "uri", where, "string", None)
        if uri is None:
            if self.chunk is None:
                raise ValueError(f"{where} has no uri, and the file no binary chunk")
            data = self.chunk
        elif uri.startswith("data:"):
            data = self.uri_bytes(uri, _path(where, "uri"))
        else:
            path = self.folder / unquote(uri)
            try:
                data = path.read_bytes()
            except OSError as error:
                raise ValueError(f"cannot read its buffer file {uri}: {error.strerror}") from None
        self.buffers[index] = data
        return data

    def view_bytes(self, index: int, where: str) -> bytes:
        """The bytes of buffer view ``index``, which the property at ``where`` names."""
        view_where = f"bufferViews[{index}]"
        view = self.entry("bufferViews", index, where)
        _, _, buffer_index = self.target(view, "buffer", view_where, "buffers")
        start = _field(view, "byteOffset", view_where, "integer", 0, minimum=0)
        length = _field(view, "byteLength", view_where, "integer", minimum=0)
        return self.buffer(buffer_index)[start : start + length]

    @staticmethod
    def uri_bytes(uri: str, where: str) -> bytes:
        """The bytes of a base64 data URI (``data:...;base64,...``, RFC 2397) at ``where``."""
        head, comma, body = uri.partition(",")
        if not comma or not head.endswith(";base64"):
            raise ValueError(f"{where} is a data URI that is not base64")
        try:  # (white space is allowed, and dropped; any other character outside base64 is not)
            return base64.b64decode("".join(body.split()), validate=True)
        except ValueError:  # (binascii.Error is one)
            raise ValueError(f"{where} is a data URI that is not valid base64") from None


def _faces(indices: np.ndarray, mode: int) -> np.ndarray:
    """(T, 3) the triangles of a primitive's (n,) vertex ``indices`` in ``mode`` (section
    3.7.2.1): a list, a strip, or a fan (0, k, k + 1)."""
    if mode == TRIANGLES:
        if len(indices) % 3:
            raise ValueError(f"a triangle list of {len(indices)} indices, not a multiple of 3")
        return indices.reshape(-1, 3)
    if mode == TRIANGLE_STRIP:
        return strip_triangles([indices])
    k = np.arange(1, max(len(indices) - 1, 1))
    return np.stack([np.full(len(k), indices[0] if len(k) else 0), indices[k], indices[k + 1]], axis=1)


def _compacted(order: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray | None]:
    """A primitive's vertex ``order`` (indices into its ``count`` vertices) renumbered over the
    vertices it uses, and those vertices' indices (None where it uses all of them)."""
    if len(order) < count:  # (fewer indices than vertices: sorting them costs less than a pass over all)
        used, renumbered = np.unique(order, return_inverse=True)
        return renumbered, used
    is_used = np.zeros(count, dtype=bool)
    is_used[order] = True
    used = np.flatnonzero(is_used)
    if len(used) == count:
        return order, None
    return (np.cumsum(is_used) - 1)[order], used


def _local_transform(node: dict, where: str) -> np.ndarray:
    """(4, 4) the transform of a node (at ``where``): its ``matrix`` (column-major), or
    translation x rotation (a unit quaternion x, y, z, w) x scale (section 3.5.3)."""
    if "matrix" in node:
        return _numbers(node, "matrix", where, 16, None).reshape(4, 4).T
    rotation = _numbers(node, "rotation", where, 4, [0.0, 0.0, 0.0, 1.0])
    largest = np.abs(rotation).max()
    if largest == 0:
        raise ValueError(f"{where}.rotation is {rotation.tolist()}, which is no rotation (a unit quaternion)")
    # The specification has the quaternion unit; one that is not (written with few digits, or
    # scaled) is normalised, not refused: its direction is the rotation the file means, and the
    # scale in it would otherwise scale the mesh by its squared length without a word.
    x, y, z, w = (
        rotation / largest / np.linalg.norm(rotation / largest)
    )  # (scaled first: 1e300 or 1e-300 squared)
    rotation_matrix = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    matrix = np.eye(4)
    matrix[:3, :3] = rotation_matrix * _numbers(node, "scale", where, 3, [1.0, 1.0, 1.0])
    matrix[:3, 3] = _numbers(node, "translation", where, 3, [0.0, 0.0, 0.0])
    return matrix


def _normal_transform(linear: np.ndarray) -> np.ndarray:
    """(3, 3) the map of normals under a (3, 3) ``linear`` map M, up to a positive factor (the
    normals are made unit later): the inverse transpose M^-T (pbrt-v4 section 3.10.3) as
    sign(det M) times the cofactor matrix det(M) M^-T, whose columns are the cross products of
    M's columns. Unlike the inverse it exists where M is singular (a scale of 0, which glTF
    allows): all normals of a mesh flattened onto a plane become the plane's, or 0 (then
    ``ptlab.meshes.base.unit_corner_normals`` gives the face's) where it is flattened further."""
    largest = np.abs(linear).max()
    if not largest > 0:
        return np.zeros((3, 3))
    a, b, c = (linear / largest).T  # (scaled so that the products neither overflow nor vanish)
    cofactor = np.stack([np.cross(b, c), np.cross(c, a), np.cross(a, b)], axis=1)
    return -cofactor if _determinant_sign(linear) < 0 else cofactor


def _determinant_sign(linear: np.ndarray) -> float:
    """The sign of a (3, 3) matrix's determinant (1, -1 or 0), which overflows for none."""
    return float(np.linalg.slogdet(linear)[0])


def _decoded(data: bytes, suffix: str) -> np.ndarray:
    """(H, W, C) the pixels of an image file's bytes (read by OpenImageIO from a temporary
    file of that ``suffix``)."""
    from ptlab.textures import read_texels

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"image{suffix}"
        path.write_bytes(data)
        return read_texels(path)
