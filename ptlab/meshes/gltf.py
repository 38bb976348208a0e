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
  3.5.3); normals by the inverse transpose of it, and a transform that mirrors turns the
  triangles' order so that their front stays where the normals say (section 3.7.4);
* ``NORMAL`` where a primitive has it (never made up: such a primitive is flat-shaded);
* the texture coordinates its base colour texture uses (``TEXCOORD_n``), turned to OBJ's
  convention: glTF's origin is the image's top-left corner with v down (section 3.7.2.1),
  ptlab's (and OBJ's) the bottom-left with v up, so v becomes 1 - v;
* each material's ``baseColorFactor`` and ``baseColorTexture`` (section 3.9.2): the base
  colour is their product; the image is a file beside the glTF file or the bytes of one it
  holds.

What else it brings (metallic-roughness, normal and occlusion maps, emission, transparency,
vertex colours, points and lines, animations, cameras, extensions) is named in ``unused``.
"""

from __future__ import annotations

import base64
import json
import struct
import tempfile
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ptlab.errors import PtlabError
from ptlab.meshes.base import FileMaterial, IndexedMesh
from ptlab.meshes.ply import strip_triangles

#: Accessor component types (section 3.6.2.2) and their NumPy types (little-endian).
COMPONENT_TYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
#: Values per element of each accessor type.
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
#: Primitive modes (section 3.7.2.1).
POINTS_AND_LINES, TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = (0, 1, 2, 3), 4, 5, 6
#: Extensions without which the geometry cannot be read (compressed buffers).
UNREADABLE = {"KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"}
#: A GLB container's magic number and chunk types (section 4.4).
GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = b"glTF", 0x4E4F534A, 0x004E4942
#: The file extension of an embedded image, by its MIME type.
IMAGE_SUFFIXES = {"image/png": ".png", "image/jpeg": ".jpg", "image/webp": ".webp", "image/ktx2": ".ktx2"}
#: The texture sampler's wrap mode that ``ptlab.textures.ImageTexture`` uses: REPEAT.
REPEAT = 10497


def read_gltf(data: bytes, folder: Path, binary: bool) -> IndexedMesh:
    """The mesh of a ``.gltf`` (``binary`` False) or ``.glb`` file's bytes, its external
    buffers and images looked for in ``folder``; ``ValueError`` for what cannot be read."""
    document, chunk = _glb(data) if binary else (_json(data), None)
    return GltfReader(document, folder, chunk).mesh()


def _json(data: bytes) -> dict:
    """The JSON object of a glTF file, or ``ValueError``."""
    try:
        document = json.loads(data.decode("utf-8-sig"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"not glTF JSON ({error})") from None
    if not isinstance(document, dict):
        raise ValueError("not glTF JSON (not an object)")
    version = str(document.get("asset", {}).get("version", ""))
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


class GltfReader:
    """Reads one glTF document: its buffers, accessors, nodes and materials."""

    def __init__(self, document: dict, folder: Path, chunk: bytes | None):
        self.document, self.folder, self.chunk = document, folder, chunk
        self.buffers: dict[object, bytes] = {}
        self.unused: list[str] = []
        required = UNREADABLE & set(document.get("extensionsRequired", ()))
        if required:
            raise ValueError(f"uses the glTF extension {sorted(required)[0]}, which ptlab cannot read")

    def part(self, kind: str, index: object) -> dict:
        """Entry ``index`` of the document's list ``kind`` ("accessors", ...), or ``ValueError``."""
        entries = self.document.get(kind, [])
        if (
            not isinstance(index, int)
            or not 0 <= index < len(entries)
            or not isinstance(entries[index], dict)
        ):
            raise ValueError(f"refers to {kind[:-1]} {index!r}, which it does not have")
        return entries[index]

    def note(self, phrase: str) -> None:
        """Add ``phrase`` to what ptlab does not use, once."""
        if phrase not in self.unused:
            self.unused.append(phrase)

    def mesh(self) -> IndexedMesh:
        """Every triangle of the default scene, placed, with its normals, uv and material."""
        parts = []
        materials_used: dict[int, int] = {}  # (the file's index -> the mesh's)
        for node, matrix in self.placed_nodes():
            if "camera" in node:
                self.note("cameras")
            if "mesh" not in node:
                continue
            for primitive in self.part("meshes", node["mesh"]).get("primitives", []):
                part = self.primitive(primitive, matrix)
                if part is not None:
                    material = primitive.get("material")
                    index = (
                        -1 if material is None else materials_used.setdefault(material, len(materials_used))
                    )
                    parts.append((*part, index))
        for key, phrase in (("animations", "animations"), ("skins", "skins")):
            if self.document.get(key):
                self.note(phrase)
        for extension in self.document.get("extensionsUsed", []):
            if extension not in ("KHR_mesh_quantization", "KHR_materials_emissive_strength"):
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

    def placed_nodes(self):
        """(node, (4, 4) world transform) of every node of the default scene, depth first."""
        nodes = self.document.get("nodes", [])
        scenes = self.document.get("scenes", [])
        if scenes:
            roots = self.part("scenes", self.document.get("scene", 0)).get("nodes", [])
        else:  # (no scene: every node that is nobody's child)
            children = {child for node in nodes for child in node.get("children", [])}
            roots = [k for k in range(len(nodes)) if k not in children]
        stack = [(root, np.eye(4)) for root in reversed(roots)]
        visited = 0
        while stack:
            index, parent = stack.pop()
            node = self.part("nodes", index)
            visited += 1
            if visited > len(nodes):
                raise ValueError("its nodes form a cycle")
            matrix = parent @ _local_transform(node)
            yield node, matrix
            stack.extend((child, matrix) for child in reversed(node.get("children", [])))

    def primitive(self, primitive: dict, matrix: np.ndarray):
        """(vertices, faces, normals or None, uv or None) of one primitive, placed by ``matrix``;
        None for one that is not made of triangles."""
        mode = primitive.get("mode", TRIANGLES)
        if mode in POINTS_AND_LINES:
            self.note("points and lines")
            return None
        attributes = primitive.get("attributes", {})
        if "POSITION" not in attributes:
            return None
        positions = self.accessor(attributes["POSITION"])
        count = len(positions)
        indices = self.accessor(primitive["indices"])[:, 0] if "indices" in primitive else np.arange(count)
        faces = _faces(indices.astype(np.int64), mode)
        if "targets" in primitive:
            self.note("morph targets")
        if any(name.startswith("COLOR_") for name in attributes):
            self.note("vertex colours (COLOR_0)")
        vertices = positions[:, :3] @ matrix[:3, :3].T + matrix[:3, 3]
        normals = None
        if "NORMAL" in attributes:
            # Normals go by the inverse transpose (pbrt-v4 section 3.10.3), made unit later.
            normals = self.accessor(attributes["NORMAL"])[:, :3] @ np.linalg.inv(matrix[:3, :3])
        if np.linalg.det(matrix[:3, :3]) < 0:
            faces = faces[:, [0, 2, 1]]  # (a mirror: keep the front where the normals are)
        uv = None
        name = f"TEXCOORD_{self.texture_coordinate_set(primitive)}"
        if name in attributes:
            uv = self.accessor(attributes[name])[:, :2].copy()
            uv[:, 1] = 1.0 - uv[:, 1]  # (glTF's v runs down the image, OBJ's and ptlab's up)
        for array in (normals, uv):
            if array is not None and len(array) != count:
                raise ValueError(f"has a primitive whose attributes hold {len(array)} and {count} vertices")
        return vertices, faces, normals, uv

    def texture_coordinate_set(self, primitive: dict) -> int:
        """The ``TEXCOORD_n`` set that a primitive's base colour texture uses (0 without one)."""
        if "material" not in primitive:
            return 0
        material = self.part("materials", primitive["material"])
        texture = material.get("pbrMetallicRoughness", {}).get("baseColorTexture", {})
        return int(texture.get("texCoord", 0))

    def material(self, index: int) -> FileMaterial:
        """Material ``index`` as a ``FileMaterial``, what ptlab does not use of it noted."""
        material = self.part("materials", index)
        name = str(material.get("name", f"material {index}"))
        pbr = material.get("pbrMetallicRoughness", {})
        factor = np.asarray(pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0]), dtype=np.float64)
        if factor.shape != (4,) or not np.isfinite(factor).all():
            raise ValueError(f"material {name!r} has a baseColorFactor that is not 4 numbers")
        metallic, roughness = pbr.get("metallicFactor", 1.0), pbr.get("roughnessFactor", 1.0)
        if metallic != 0 or roughness != 1 or "metallicRoughnessTexture" in pbr:
            self.note("glTF metallic-roughness")
        for key, phrase in (
            ("normalTexture", "normal map (normalTexture)"),
            ("occlusionTexture", "occlusion map (occlusionTexture)"),
            ("emissiveTexture", "emission (emissiveTexture)"),
        ):
            if key in material:
                self.note(phrase)
        if any(material.get("emissiveFactor", [0, 0, 0])):
            self.note("emission (emissiveFactor)")
        if material.get("alphaMode", "OPAQUE") != "OPAQUE":
            self.note(f"transparency (alphaMode {material['alphaMode']})")
        for extension in material.get("extensions", {}):
            self.note(f"the glTF extension {extension}")
        texture = None
        if "baseColorTexture" in pbr:
            texture = self.image_of(pbr["baseColorTexture"], name)
        return FileMaterial(name, factor[:3], texture, f"glTF material {index}")

    def image_of(self, info: dict, material: str) -> Path | np.ndarray | None:
        """The image of a texture reference: a file, or the pixels of one the file holds."""
        texture = self.part("textures", info.get("index"))
        if "extensions" in info:
            self.note(f"texture transforms of material {material!r} ({', '.join(info['extensions'])})")
        sampler = self.part("samplers", texture["sampler"]) if "sampler" in texture else {}
        if sampler.get("wrapS", REPEAT) != REPEAT or sampler.get("wrapT", REPEAT) != REPEAT:
            self.note("texture wrap modes other than repeat (sampler)")
        if "source" not in texture:
            self.note(f"the base colour image of material {material!r} (in a format of an extension)")
            return None
        image = self.part("images", texture["source"])
        uri = image.get("uri")
        if uri is not None and not uri.startswith("data:"):
            return self.folder / unquote(uri)
        data = self.uri_bytes(uri) if uri is not None else self.view_bytes(image.get("bufferView"))
        try:
            return _decoded(data, IMAGE_SUFFIXES.get(image.get("mimeType", ""), ".png"))
        except PtlabError:
            raise ValueError(
                f"holds a base colour image (material {material!r}) that cannot be read"
            ) from None

    def accessor(self, index: object) -> np.ndarray:
        """(count, n) float64 values of accessor ``index`` (section 3.6.2), normalised integers
        made fractions, sparse values put in place."""
        accessor = self.part("accessors", index)
        try:
            dtype = np.dtype(COMPONENT_TYPES[accessor["componentType"]])
            width = TYPE_SIZES[accessor["type"]]
            count = int(accessor["count"])
        except (KeyError, TypeError, ValueError):
            raise ValueError(
                f"has an accessor ({index}) without a valid componentType, type or count"
            ) from None
        if "bufferView" in accessor:
            values = self.strided(
                accessor["bufferView"], int(accessor.get("byteOffset", 0)), dtype, count, width
            )
        else:
            values = np.zeros((count, width), dtype=dtype)
        if "sparse" in accessor:
            sparse = accessor["sparse"]
            where = self.strided(
                sparse["indices"]["bufferView"],
                int(sparse["indices"].get("byteOffset", 0)),
                np.dtype(COMPONENT_TYPES[sparse["indices"]["componentType"]]),
                int(sparse["count"]),
                1,
            )[:, 0]
            values = values.copy()
            values[where] = self.strided(
                sparse["values"]["bufferView"],
                int(sparse["values"].get("byteOffset", 0)),
                dtype,
                int(sparse["count"]),
                width,
            )
        result = values.astype(np.float64)
        if accessor.get("normalized") and dtype.kind in "iu":
            # (Section 3.11: unsigned c / (2^n - 1); signed max(c / (2^(n-1) - 1), -1).)
            result = np.maximum(result / np.iinfo(dtype).max, -1.0)
        return result

    def strided(self, view_index: object, offset: int, dtype: np.dtype, count: int, width: int) -> np.ndarray:
        """(count, width) values of type ``dtype`` from buffer view ``view_index``, from byte
        ``offset`` on, at the view's stride (or packed)."""
        view = self.part("bufferViews", view_index)
        data = self.buffer(view.get("buffer"))
        start = int(view.get("byteOffset", 0)) + offset
        size = dtype.itemsize * width
        stride = int(view.get("byteStride", size))
        end = int(view.get("byteOffset", 0)) + int(view.get("byteLength", 0))
        if count and (start + stride * (count - 1) + size > min(end, len(data)) or stride < size):
            raise ValueError(
                f"truncated or malformed: buffer view {view_index} does not hold the {count} values "
                f"asked of it"
            )
        if count == 0:
            return np.zeros((0, width), dtype=dtype)
        return np.ndarray(
            (count, width), dtype=dtype, buffer=data, offset=start, strides=(stride, dtype.itemsize)
        )

    def buffer(self, index: object) -> bytes:
        """The bytes of buffer ``index``: the GLB's binary chunk, a data URI's, or a file's."""
        if index in self.buffers:
            return self.buffers[index]
        buffer = self.part("buffers", index)
        uri = buffer.get("uri")
        if uri is None:
            if self.chunk is None:
                raise ValueError(f"has a buffer ({index}) without data")
            data = self.chunk
        elif uri.startswith("data:"):
            data = self.uri_bytes(uri)
        else:
            path = self.folder / unquote(uri)
            try:
                data = path.read_bytes()
            except OSError as error:
                raise ValueError(f"cannot read its buffer file {uri}: {error.strerror}") from None
        self.buffers[index] = data
        return data

    def view_bytes(self, index: object) -> bytes:
        """The bytes of buffer view ``index``."""
        view = self.part("bufferViews", index)
        start = int(view.get("byteOffset", 0))
        return self.buffer(view.get("buffer"))[start : start + int(view.get("byteLength", 0))]

    @staticmethod
    def uri_bytes(uri: str) -> bytes:
        """The bytes of a base64 data URI (``data:...;base64,...``)."""
        head, _, body = uri.partition(",")
        if not head.endswith(";base64"):
            raise ValueError("has a data URI that is not base64")
        return base64.b64decode(body)


def _faces(indices: np.ndarray, mode: object) -> np.ndarray:
    """(T, 3) the triangles of a primitive's (n,) vertex ``indices`` in ``mode`` (section
    3.7.2.1): a list, a strip, or a fan (0, k, k + 1)."""
    if mode == TRIANGLES:
        if len(indices) % 3:
            raise ValueError(f"a triangle list of {len(indices)} indices, not a multiple of 3")
        return indices.reshape(-1, 3)
    if mode == TRIANGLE_STRIP:
        return strip_triangles([indices])
    if mode == TRIANGLE_FAN:
        k = np.arange(1, max(len(indices) - 1, 1))
        return np.stack([np.full(len(k), indices[0] if len(k) else 0), indices[k], indices[k + 1]], axis=1)
    raise ValueError(f"a primitive of mode {mode!r}, which glTF does not define")


def _local_transform(node: dict) -> np.ndarray:
    """(4, 4) a node's transform: its ``matrix`` (column-major), or translation x rotation
    (a unit quaternion x, y, z, w) x scale (section 3.5.2)."""
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T
    x, y, z, w = node.get("rotation", (0.0, 0.0, 0.0, 1.0))
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    matrix = np.eye(4)
    matrix[:3, :3] = rotation * np.asarray(node.get("scale", (1.0, 1.0, 1.0)), dtype=np.float64)
    matrix[:3, 3] = node.get("translation", (0.0, 0.0, 0.0))
    return matrix


def _decoded(data: bytes, suffix: str) -> np.ndarray:
    """(H, W, C) the pixels of an image file's bytes (read by OpenImageIO from a temporary
    file of that ``suffix``)."""
    from ptlab.textures import read_texels

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"image{suffix}"
        path.write_bytes(data)
        return read_texels(path)
