"""Mesh files: the triangles of an OBJ, STL, PLY, OFF or glTF file, read and checked.

OBJ files are read here (``read_obj``), the other formats by trimesh, which triangulates
polygons; ptlab then checks what came out (three coordinates per vertex, faces that refer to
existing vertices, nothing NaN or infinite) and drops triangles of zero area, which no ray
can hit.

``read_obj`` is one reader for every OBJ file, with texture coordinates or without. It
parses the whole text at once (``parse_obj``: lines found and classified by whole-array
operations on the bytes, each kind of record's numbers read by one ``np.fromstring``), so
that no Python loop runs per line: a 1.3 million-triangle file reads faster than trimesh
reads it (docs/performance.md). Its triangles are trimesh's, in the file's order, so images
are the same; and a render of OBJ meshes imports neither trimesh nor, through it, SciPy,
which spares it a second of start-up.

trimesh's OBJ reader is fast because it is lenient, and some of its leniency goes wrong
silently: it takes the number of values per vertex from the first ``v`` line, skips ``v``
and ``f`` lines that do not begin with the keyword and a space, drops faces of fewer than
three vertices, counts negative indices from the end of the file rather than from their
line, and reads a face whose references mix forms (``1/2`` beside ``3``) as other
vertices. ``read_obj`` refuses each of these and names the line, so that a malformed OBJ
file, which other programs may misread, is an error instead of a wrong picture: the parse
itself confirms that a file is written the common way (``ObjRecords.plain``), and only where
it cannot does ``check_obj_lines`` look line by line.
"""

from __future__ import annotations

import functools
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.errors import SceneError

#: The mesh formats trimesh reads without optional packages (by file extension).
MESH_FORMATS = ("obj", "stl", "ply", "off", "glb", "gltf")

#: A number as trimesh's OBJ reader (NumPy's ``fromstring``) parses it: decimal, optional
#: exponent, or nan/inf (which ``read_mesh_triangles`` then reports).
_NUMBER = r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|(?i:nan|inf(?:inity)?))"
#: A face's reference to a vertex: ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn`` (1-based, or
#: negative: counted back from the last vertex so far).
_REFERENCE = r"-?[0-9]+(?:/-?[0-9]+|//-?[0-9]+|/-?[0-9]+/-?[0-9]+)?"
#: Whole records, matched at once (one match per line, not one per number).
_NUMBERS_RECORD = re.compile(rf"v[tn]?(?:[ \t]+{_NUMBER})*[ \t]*")
_FACE_RECORD = re.compile(rf"f(?:[ \t]+{_REFERENCE})*[ \t]*")
#: How many numbers each OBJ record takes: (fewest, most); ``v`` may carry w or an RGB colour.
_RECORD_SIZES = {"v": (3, 7), "vt": (1, 3), "vn": (3, 3)}


def read_mesh_triangles(path: Path, where: str | None = None, limit: float = math.inf) -> np.ndarray:
    """(T, 3, 3) float64 triangles of a mesh file (``read_mesh``)."""
    return read_mesh(path, where, limit)[0]


def read_mesh(
    path: Path, where: str | None = None, limit: float = math.inf
) -> tuple[np.ndarray, np.ndarray | None]:
    """The triangles of a mesh file and their texture coordinates: an OBJ file read here
    (``read_obj``), any other file by trimesh.

    Returns:
        triangles: (T, 3, 3) float64, vertex k of triangle i at ``triangles[i, k]``;
        uv: (T, 3, 2) float64 texture coordinates of those vertices (an OBJ file's ``vt``;
        a missing v is 0), or None if the file has none.

    Raises ``SceneError`` (naming ``where``, e.g. the scene file and key) for a file trimesh
    cannot read or would misread, an empty mesh, NaN or infinite vertices or texture
    coordinates, and coordinates beyond +-``limit``. Triangles of zero area are then dropped.
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
    if fmt == "obj":
        try:
            vertices, faces, uv = read_obj(data)
        except ValueError as error:
            raise SceneError(where, f"mesh {path.name}: {error}") from None
    else:
        mesh = _read_with_trimesh(path, where, fmt)
        vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
        faces = np.asarray(getattr(mesh, "faces", ()))
    _check_faces(vertices, faces, where, path.name)
    triangles = vertices[faces]
    # (A closed mesh has a sixth as many vertices as corners: they are looked at first, the
    # corners only to name the vertex, or where the one beyond belongs to no face.)
    if (np.abs(vertices) > limit).any() and (beyond := np.abs(triangles).max(axis=2) > limit).any():
        vertex = triangles[beyond][0]
        raise SceneError(
            where,
            f"mesh {path.name} has a vertex at {vertex.tolist()}: every "
            f"coordinate must lie within +-{limit:g}",
        )
    if fmt != "obj":
        uv = _texture_coordinates(mesh, len(vertices), where, path.name)
        uv = None if uv is None else uv[faces]
    if uv is not None and not np.isfinite(uv).all():
        raise SceneError(where, f"mesh {path.name} has texture coordinates that are NaN or infinite")
    # (Only now: a vertex far out can make its triangles degenerate in float64.)
    kept = has_area(triangles)
    if not kept.any():
        raise SceneError(where, f"mesh {path.name} has only zero-area triangles")
    if kept.all():  # (spares a copy)
        return triangles, uv
    return triangles[kept], None if uv is None else uv[kept]


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


def _texture_coordinates(mesh, vertex_count: int, where: str, name: str) -> np.ndarray | None:
    """(V, 2) uv per vertex of a trimesh mesh (v = 0 where the file gives u only), or None."""
    uv = getattr(getattr(mesh, "visual", None), "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim != 2 or len(uv) != vertex_count or uv.shape[1] == 0:
        raise SceneError(
            where, f"mesh {name}: texture coordinates of shape {uv.shape} for {vertex_count} vertices"
        )
    return np.pad(uv[:, :2], ((0, 0), (0, max(0, 2 - uv.shape[1]))))


def has_area(triangles: np.ndarray) -> np.ndarray:
    """(T,) bool: which of the (T, 3, 3) ``triangles`` have an area that is not zero."""
    area2 = np.linalg.norm(
        np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
    )
    return area2 > 0


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


def read_obj(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The triangles of an OBJ file, read the way trimesh reads them, or ``ValueError("line
    N: ...")`` where trimesh would misread the file (module docstring).

    Faces are cut into triangles as trimesh cuts them, in the file's order: a quad (a, b, c, d)
    into (a, b, c) and (c, d, a), a larger polygon into the fan (0, k, k + 1).

    Returns:
        vertices: (V, 3) float64, each ``v`` record's first three numbers;
        faces: (F, 3) int64 0-based vertex indices of each triangle;
        uv: (F, 3, 2) float64 texture coordinates of each triangle's vertices (a ``vt``
        record's u and v; v = 0 where it gives u only), or None where some face gives none
        or one that does not exist.
    """
    text = _obj_text(data)
    records = parse_obj(text)
    if records is None or not records.plain:
        check_obj_lines(text.decode("utf-8"))
        # (check_obj_lines accepts only text that parse_obj reads.)
        assert records is not None
    # (Where every face is a triangle, nothing is cut: each is its three references.)
    corners = None if (records.face_sizes == 3).all() else _fan_corners(records.face_sizes)
    faces = _by_triangle(records.vertex_references, corners)
    if records.texture_references is None:
        return records.vertices, faces, None
    return records.vertices, faces, records.texture[_by_triangle(records.texture_references, corners)]


def _obj_text(data: bytes) -> bytes:
    """The text of an OBJ file with LF line ends, or ``ValueError`` for bytes that are not
    text a reader of OBJ lines would split as this one does."""
    if b"\0" in data:
        raise ValueError("contains NUL bytes: a binary file, not OBJ text")
    if data.startswith(b"\xef\xbb\xbf"):
        raise ValueError(
            "starts with a byte-order mark, which hides its first line from "
            "trimesh: save it as UTF-8 without BOM"
        )
    try:
        data.isascii() or data.decode("utf-8")  # (the first is 20x faster)
    except UnicodeDecodeError as error:
        raise ValueError(
            f"is not UTF-8 text (byte {data[error.start]:#04x} at offset "
            f"{error.start}): a binary file, or another encoding"
        ) from None
    # (`in` looks for one byte 20x faster than `replace` looks for two.)
    text = data.replace(b"\r\n", b"\n") if b"\r" in data else data
    if b"\r" in text:
        raise ValueError(
            "ends its lines with CR alone, which trimesh does not split: save it with LF or CRLF line ends"
        )
    return text


@dataclass
class ObjRecords:
    """The ``v``, ``vt`` and ``f`` records of OBJ text, parsed at once (``parse_obj``).

    Attributes:
        vertices: (V, 3) float64, each ``v`` record's first three numbers.
        texture: (VT, 2) float64 ``vt`` records' u and v (0 where a record gives u only).
        vertex_references: (R,) int64 0-based vertex of every face's every reference, in
            the file's order.
        texture_references: (R,) int64 0-based ``vt`` record of every reference, or None
            where some face gives none or one that does not exist.
        face_sizes: (F,) the number of references of each face.
        plain: the text is written the common way, which the parse itself confirms: records
            at the very start of their lines and without comments, numbers made of digits,
            signs, points and exponents, every face's references in one form, with indices
            of vertices that exist. False means only that ``check_obj_lines`` must look line
            by line.
    """

    vertices: np.ndarray
    texture: np.ndarray
    vertex_references: np.ndarray
    texture_references: np.ndarray | None
    face_sizes: np.ndarray
    plain: bool


def parse_obj(text: bytes) -> ObjRecords | None:
    """The records of OBJ text (LF line ends), read by a few whole-array operations on its
    bytes, or None where they cannot be read that way (then ``check_obj_lines`` finds a
    line that is wrong).

    Lines are found by their line feeds and classified by their first three bytes; the lines
    of each kind of record are gathered into one array of bytes (keyword blanked), whose
    fields one ``np.fromstring`` call reads. Bytes of a few classes (separators, slashes)
    give the fields of each line and their forms. No Python loop runs over lines, so reading
    takes a time proportional to the file's size (docs/performance.md).
    """
    continued = b"\\" in text and b"\\\n" in text  # (lines continued with a backslash)
    joined = text.replace(b"\\\n", b"") if continued else text
    if not joined.endswith(b"\n"):
        joined += b"\n"
    data = np.frombuffer(joined, np.uint8)
    ends = np.flatnonzero(data == _NEWLINE)
    starts = np.concatenate(([0], ends[:-1] + 1))
    kind, misplaced = _line_kinds(data, starts, ends)
    hashes = np.flatnonzero(data == ord("#"))
    commented = (kind[np.searchsorted(ends, hashes)] != 0).any()

    @functools.cache
    def byte_kind() -> np.ndarray:
        """(n,) uint8 the kind of each byte's line (made where a kind's lines are apart)."""
        return np.repeat(kind, ends - starts + 1)

    def lines_of(record: str) -> np.ndarray:
        """The bytes of every line of one kind of record, keyword blanked: (n,) uint8."""
        lines = np.flatnonzero(kind == _KINDS[record])
        if len(lines) == 0:
            return np.zeros(0, np.uint8)
        if lines[-1] - lines[0] == len(lines) - 1:  # (one block of lines, as most files are)
            stream = data[starts[lines[0]] : ends[lines[-1]] + 1].copy()
        else:
            stream = data[byte_kind() == _KINDS[record]]
        lengths = (ends - starts + 1)[lines]
        first = np.cumsum(lengths) - lengths
        for k in range(len(record)):
            stream[first + k] = _SPACE
        return stream

    numbers = {}
    plain_numbers = True
    for record, (fewest, most) in _RECORD_SIZES.items():
        values = _number_records(lines_of(record), fewest, most)
        if values is None:
            return None
        numbers[record], plain = values
        plain_numbers &= plain
    # Per face: how many `v` and `vt` records come before its line.
    before = {record: np.cumsum(kind == _KINDS[record])[kind == _KINDS["f"]] for record in ("v", "vt")}
    faces = _face_records(lines_of("f"), before, len(numbers["v"]), len(numbers["vt"]))
    if faces is None:
        return None
    vertex_references, texture_references, face_sizes, plain_faces = faces
    texture = numbers["vt"][:, :2]
    return ObjRecords(
        vertices=numbers["v"][:, :3],
        texture=np.pad(texture, ((0, 0), (0, 2 - texture.shape[1]))),
        vertex_references=vertex_references,
        texture_references=texture_references,
        face_sizes=face_sizes,
        plain=not continued and not misplaced.any() and not commented and plain_numbers and plain_faces,
    )


#: The records ``parse_obj`` reads, and the code of each in its per-line kinds (0: others).
_KINDS = {"v": 1, "vt": 2, "vn": 3, "f": 4}
_NEWLINE, _SPACE, _SLASH = b"\n /"


def _byte_class(chars: bytes) -> np.ndarray:
    """(256,) bool: which byte values are among ``chars``."""
    table = np.zeros(256, bool)
    table[list(chars)] = True
    return table


#: The bytes that a plain number or face reference is made of (and the fields' separators).
_NUMBER_BYTES = b"0123456789.+-eE \t\n"
_REFERENCE_BYTES = b"0123456789-/ \t\n"
#: Bytes that may be whitespace to Python's ``str.split`` (or end a line, or start a UTF-8
#: character that may be whitespace): a keyword followed by one of these but a space is a
#: misplaced record, as is a record after any of them.
_BLANK = _byte_class(bytes(range(0x21)) + bytes(range(0x80, 0x100)))


def _line_kinds(data: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L,) uint8 kind of each line (``_KINDS``, from its first three bytes), and (L,) bool:
    which lines may be misplaced records (indented, or a keyword not followed by a space)."""

    def byte(k: int) -> np.ndarray:
        """Byte k of every line; a line feed beyond a line's end."""
        return np.where(ends - starts > k, data[np.minimum(starts + k, len(data) - 1)], _NEWLINE)

    b0, b1, b2 = byte(0), byte(1), byte(2)
    v, f = b0 == ord("v"), b0 == ord("f")
    vt_or_vn = v & ((b1 == ord("t")) | (b1 == ord("n")))
    kind = np.zeros(len(starts), np.uint8)
    kind[v & (b1 == _SPACE)] = _KINDS["v"]
    kind[vt_or_vn & (b1 == ord("t")) & (b2 == _SPACE)] = _KINDS["vt"]
    kind[vt_or_vn & (b1 == ord("n")) & (b2 == _SPACE)] = _KINDS["vn"]
    kind[f & (b1 == _SPACE)] = _KINDS["f"]
    misplaced = (
        (_BLANK[b0] & (b0 != _NEWLINE))
        | ((v | f) & _BLANK[b1] & (b1 != _SPACE))
        | (vt_or_vn & _BLANK[b2] & (b2 != _SPACE))
    )
    return kind, misplaced


def _made_of(stream: np.ndarray, allowed: bytes) -> bool:
    """Whether the bytes of ``stream`` are all among ``allowed``."""
    # (bytes.translate deletes them 4x faster than NumPy looks each byte up in a table.)
    return not stream.tobytes().translate(None, allowed)


def _fields(stream: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the fields of ``stream`` (lines of bytes, each ending in a line feed) start,
    (n,); where its lines end, (L,); and (L,) how many fields each line has. Fields are
    separated by spaces, tabs and any other control byte (which ``_made_of`` finds)."""
    separator = stream <= _SPACE
    is_start = ~separator
    is_start[1:] &= separator[:-1]
    start = np.flatnonzero(is_start)
    ends = np.flatnonzero(stream == _NEWLINE)
    return start, ends, np.diff(np.searchsorted(start, ends), prepend=0)


def _read_numbers(stream: np.ndarray, count: int, dtype: type) -> np.ndarray | None:
    """The ``count`` numbers of ``stream`` (bytes of fields separated by whitespace), or None
    if it does not hold exactly that many, each a whole field."""
    if count == 0:
        return np.zeros(0, dtype)  # (np.fromstring reads blank text as [-1])
    with warnings.catch_warnings():
        # A field that is not (wholly) a number ends the reading with a warning.
        warnings.simplefilter("error", DeprecationWarning)
        try:
            values: np.ndarray = np.fromstring(stream.tobytes(), dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    return values if len(values) == count else None


def _number_records(stream: np.ndarray, fewest: int, most: int) -> tuple[np.ndarray, bool] | None:
    """(n, size) float64 numbers of n ``v`` (``vt``, ``vn``) lines that each have as many,
    between ``fewest`` and ``most``, and whether they are all plain numbers; or None."""
    _, _, counts = _fields(stream)
    if len(counts) == 0:
        return np.zeros((0, fewest)), True
    size = int(counts[0])
    if not fewest <= size <= most or (counts != size).any():
        return None
    values = _read_numbers(stream, len(counts) * size, np.float64)
    if values is None:
        return None
    # (Anything else that np.fromstring reads, nan and inf, is left to check_obj_lines.)
    return values.reshape(-1, size), _made_of(stream, _NUMBER_BYTES)


def _face_records(
    stream: np.ndarray, before: dict[str, np.ndarray], vertex_count: int, texture_count: int
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, bool] | None:
    """The references of F faces, from their lines' bytes (keyword blanked) and the number
    of ``v`` and ``vt`` records before each line, (F,) each: (R,) 0-based vertices, (R,)
    0-based ``vt`` records or None, (F,) references per face, and whether the faces are
    plain; or None."""
    if not _made_of(stream, _REFERENCE_BYTES):
        return None
    start, ends, sizes = _fields(stream)
    if len(sizes) == 0 or sizes.min() < 3:
        return None
    # Each line's references are in one form (i, i/i, i//i or i/i/i), of `per` numbers, as
    # its slashes tell.
    slash = np.flatnonzero(stream == _SLASH)
    slashes = np.diff(np.searchsorted(slash, ends), prepend=0)
    double = slash[1:][np.diff(slash) == 1]  # the second of two slashes in a row
    doubles = np.diff(np.searchsorted(double, ends), prepend=0)
    per, rest = np.divmod(slashes - doubles, sizes)
    if rest.any() or (per > 2).any():
        return None
    if slash.size:
        stream = stream.copy()
        stream[slash] = _SPACE
    numbers = _read_numbers(stream, int(((per + 1) * sizes).sum()), np.int64)
    if numbers is None:
        return None
    first = None  # (where each reference's numbers start, unless every face has one form)
    if (per != per[0]).any():
        per_reference = np.repeat(per + 1, sizes)
        first = np.cumsum(per_reference) - per_reference

    def numbers_at(k: int) -> np.ndarray:
        """(R,) number k of each reference (its vertex, its vt), as the file writes it: where
        every face has one form, a view of every (per + 1)th number."""
        return numbers[k :: int(per[0]) + 1] if first is None else numbers[first + k]

    written = numbers_at(0)
    vertex = _zero_based(written, before["v"], sizes, vertex_count)
    if vertex is None:
        return None
    # Plain: positive indices, and every reference in the first one's form: as many slashes
    # each, all between its start and the next reference's, and a double slash in all or none.
    form = int(slashes[0] // sizes[0])
    inside = slash.reshape(len(start), form) if len(slash) == form * len(start) else None
    plain = (
        inside is not None
        and bool((inside > start[:, None]).all())
        and bool((inside[:-1] < start[1:, None]).all())
        and doubles.sum() in (0, len(start))
        and bool((written > 0).all())
    )
    texture = None
    if ((per >= 1) & (doubles == 0)).all():
        texture = _zero_based(numbers_at(1), before["vt"], sizes, texture_count)
    return vertex, texture, sizes, plain


def _zero_based(index: np.ndarray, before: np.ndarray, sizes: np.ndarray, count: int) -> np.ndarray | None:
    """(R,) 0-based records of the (R,) OBJ indices of faces of (F,) ``sizes`` references
    (from 1, or negative: counted back from the last of the (F,) ``before`` records before
    the face's line), or None if one of them is not among the ``count`` records."""
    if index.min() > 0:  # (the common case: spare the negatives)
        return index - 1 if index.max() <= count else None
    zero_based = np.where(index > 0, index - 1, index + np.repeat(before, sizes))
    if (index == 0).any() or zero_based.min() < 0 or zero_based.max() >= count:
        return None
    return zero_based


def _by_triangle(references: np.ndarray, corners: np.ndarray | None) -> np.ndarray:
    """(T, 3) the (R,) ``references`` of each triangle: at its ``corners`` (``_fan_corners``),
    or, for None, three by three."""
    return references.reshape(-1, 3) if corners is None else references[corners]


def _fan_corners(sizes: np.ndarray) -> np.ndarray:
    """(T, 3) the references of each triangle of faces of (F,) ``sizes`` references, in the
    faces' order, as indices into all their references: a quad (a, b, c, d) cut into
    (a, b, c) and (c, d, a), a larger polygon into the fan (0, k, k + 1), as trimesh cuts."""
    count = sizes - 2
    face = np.repeat(np.arange(len(sizes)), count)
    k = np.arange(len(face)) - np.repeat(np.cumsum(count) - count, count)  # (in its face)
    first = (np.cumsum(sizes) - sizes)[face]
    corners = first[:, None] + np.stack([np.zeros_like(k), k + 1, k + 2], axis=1)
    quad = (sizes[face] == 4) & (k == 1)
    corners[quad] = first[quad, None] + [2, 3, 0]
    return corners


def check_obj_lines(text: str) -> None:
    """Raise ``ValueError("line N: ...")`` for the first record trimesh would misread."""
    records = list(_obj_records(text))
    vertex_count = sum(keyword == "v" for _, keyword, _ in records)
    sizes: dict[str, tuple[int, int]] = {}  # record keyword -> (size, first line with it)
    forms: dict[int, tuple[str, int]] = {}  # numbers in a face -> (its form, first line)
    vertices_so_far = faces = 0
    for number, keyword, line in records:
        fields = line.split()[1:]
        if keyword == "f":
            _check_face(number, line, fields, vertices_so_far, vertex_count, forms)
            faces += 1
            continue
        if not _NUMBERS_RECORD.fullmatch(line):
            bad = next((f for f in fields if not re.fullmatch(_NUMBER, f)), None)
            raise ValueError(
                f"line {number}: {bad!r} is not a number"
                if bad
                else f"line {number}: separate the numbers with spaces or tabs"
            )
        fewest, most = _RECORD_SIZES[keyword]
        if not fewest <= len(fields) <= most:
            expected = f"{fewest}" if fewest == most else f"{fewest} to {most}"
            raise ValueError(f"line {number}: `{keyword}` needs {expected} numbers, got {len(fields)}")
        size, first = sizes.setdefault(keyword, (len(fields), number))
        if len(fields) != size:
            raise ValueError(
                f"line {number}: `{keyword}` has {len(fields)} numbers but line "
                f"{first}'s has {size}: write every `{keyword}` alike"
            )
        vertices_so_far += keyword == "v"
    if faces == 0:
        raise ValueError(
            "has no faces (`f` lines)"
            if vertex_count
            else "has no vertices or faces (`v` and `f` lines): is it an OBJ file?"
        )


def _obj_records(text: str):
    """(line number, keyword, line) of each ``v``, ``vt``, ``vn`` and ``f`` line.

    trimesh joins lines ending in a backslash to the next one, and finds a record only at the
    very start of a line, followed by a space; comments must be lines of their own.
    """
    lines = text.split("\n")
    number = 0
    while number < len(lines):
        start = number + 1
        line = lines[number]
        while line.endswith("\\") and number + 1 < len(lines):
            number += 1
            line = line[:-1] + lines[number]
        number += 1
        if not line or (line[0] not in "vf" and not line[0].isspace()):  # (a quick skip)
            continue
        words = line.split(None, 1)
        if not words or words[0] not in ("v", "vt", "vn", "f"):
            continue
        keyword = words[0]
        if not line.startswith(keyword + " "):
            raise ValueError(
                f"line {start}: write `{keyword}` at the very start of the line, "
                f"with a space after it: trimesh skips the line otherwise"
            )
        if "#" in line:
            raise ValueError(
                f"line {start}: a comment after the data; trimesh reads comments only on lines of their own"
            )
        yield start, keyword, line


def _form(reference: str) -> str:
    """The form of a vertex reference: ``i``, ``i/i``, ``i//i`` or ``i/i/i``."""
    return re.sub(r"-?[0-9]+", "i", reference)


def _check_face(
    number: int,
    line: str,
    references: list[str],
    vertices_so_far: int,
    vertex_count: int,
    forms: dict[int, tuple[str, int]],
) -> None:
    """Raise ``ValueError`` for a face that trimesh would drop or misread."""
    if len(references) < 3:
        raise ValueError(
            f"line {number}: a face needs at least 3 vertices, got {len(references)} (`{line.strip()}`)"
        )
    if not _FACE_RECORD.fullmatch(line):
        bad = next((r for r in references if not re.fullmatch(_REFERENCE, r)), None)
        raise ValueError(
            f"line {number}: {bad!r} is not a vertex reference (v, v/vt, v//vn or v/vt/vn)"
            if bad
            else f"line {number}: separate the references with spaces or tabs"
        )
    first = references[0]
    slashes, doubles = first.count("/"), first.count("//")
    written = {_form(r) for r in references}
    if len(written) > 1:
        raise ValueError(
            f"line {number}: the face mixes reference forms "
            f"({', '.join(sorted(written))}): write its vertices alike"
        )
    indices = [int(r.split("/", 1)[0]) for r in references] if slashes else list(map(int, references))
    low, high = min(indices), max(indices)
    if low <= 0 <= high and 0 in indices:
        raise ValueError(f"line {number}: vertex index 0 (OBJ counts vertices from 1)")
    for index in (high, low):
        if index > vertex_count or -index > vertices_so_far:
            raise ValueError(
                f"line {number}: vertex {index} does not exist (the file has "
                f"{vertex_count} vertices, {vertices_so_far} before this line)"
            )
    if low < 0 and vertices_so_far != vertex_count:
        raise ValueError(
            f"line {number}: negative vertex index {low} with vertices after "
            f"this line: trimesh would count it from the end of the file; use "
            f"positive indices"
        )
    # trimesh reads the faces that have as many numbers as the first such face in its form.
    form = _form(first)
    first_form, first_line = forms.setdefault(len(references) * (slashes - doubles + 1), (form, number))
    if form != first_form:
        raise ValueError(
            f"line {number}: this face ({form}) and line {first_line}'s "
            f"({first_form}) have as many numbers, so trimesh reads them in one "
            f"form: write the faces alike"
        )
