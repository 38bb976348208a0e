"""Mesh files: the triangles of an OBJ, STL, PLY, OFF or glTF file, read and checked.

trimesh reads each format and triangulates polygons; ptlab then checks what came out (three
coordinates per vertex, faces that refer to existing vertices, nothing NaN or infinite) and
drops triangles of zero area, which no ray can hit. OBJ text that ``check_obj_text`` accepts
and that has no texture coordinates is plain enough to read directly (``read_obj``), with
the same triangles as trimesh's: that spares a render of OBJ meshes importing trimesh, and
through it SciPy, a second of its start-up (measured: 1.2 s of 1.3 s CPU for a 16 x 16
Cornell box).

trimesh's OBJ reader is fast because it is lenient, and some of its leniency goes wrong
silently: it takes the number of values per vertex from the first ``v`` line, skips ``v``
and ``f`` lines that do not begin with the keyword and a space, drops faces of fewer than
three vertices, counts negative indices from the end of the file rather than from their
line, and reads a face whose references mix forms (``1/2`` beside ``3``) as other
vertices. ``check_obj_text`` looks for each of these first and names the line, so that a
malformed OBJ file is an error instead of a wrong picture.
"""

from __future__ import annotations

import math
import re
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


def read_mesh_triangles(path: Path, where: str | None = None,
                        limit: float = math.inf) -> np.ndarray:
    """(T, 3, 3) float64 triangles of a mesh file (``read_mesh``)."""
    return read_mesh(path, where, limit)[0]


def read_mesh(path: Path, where: str | None = None,
              limit: float = math.inf) -> tuple[np.ndarray, np.ndarray | None]:
    """The triangles of a mesh file and their texture coordinates: an OBJ file without
    texture coordinates read here (``read_obj``), any other file by trimesh.

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
        raise SceneError(where, f"mesh {path.name}: unknown mesh format {path.suffix!r} "
                                f"(use .{', .'.join(MESH_FORMATS)})")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SceneError(where, f"cannot read mesh {path.name}: {error.strerror}") from None
    if not data.strip():
        raise SceneError(where, f"mesh {path.name} is empty")
    if fmt == "obj":
        try:
            check_obj_text(data)
        except ValueError as error:
            raise SceneError(where, f"mesh {path.name}: {error}") from None
    if fmt == "obj" and b"\nvt " not in b"\n" + data:
        vertices, faces = read_obj(data.decode("utf-8").replace("\r\n", "\n"))
        mesh = None
    else:
        mesh = _read_with_trimesh(path, where, fmt)
        vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
        faces = np.asarray(getattr(mesh, "faces", ()))
    if len(faces) == 0:
        raise SceneError(where, f"mesh {path.name} has no triangles")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise SceneError(where, f"mesh {path.name}: vertices must have 3 coordinates, "
                                f"got {vertices.shape[-1] if vertices.ndim == 2 else 0}")
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        raise SceneError(where, f"mesh {path.name}: trimesh returned faces of shape {faces.shape}")
    outside = faces[(faces < 0) | (faces >= len(vertices))]
    if len(outside):
        raise SceneError(where, f"mesh {path.name}: a face refers to vertex {int(outside[0])}, "
                                f"but there are {len(vertices)} vertices (0 to "
                                f"{len(vertices) - 1})")
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        raise SceneError(where, f"mesh {path.name} has {int(bad.sum())} vertices that are NaN "
                                f"or infinite (first: vertex {int(np.flatnonzero(bad)[0])})")
    triangles = vertices[faces]
    beyond = np.abs(triangles).max(axis=2) > limit
    if beyond.any():
        vertex = triangles[beyond][0]
        raise SceneError(where, f"mesh {path.name} has a vertex at {vertex.tolist()}: every "
                                f"coordinate must lie within +-{limit:g}")
    uv = None if mesh is None else _texture_coordinates(mesh, len(vertices), where, path.name)
    uv = None if uv is None else uv[faces]
    # (Only now: a vertex far out can make its triangles degenerate in float64.)
    kept = has_area(triangles)
    if not kept.any():
        raise SceneError(where, f"mesh {path.name} has only zero-area triangles")
    return triangles[kept], None if uv is None else uv[kept]


def _texture_coordinates(mesh, vertex_count: int, where: str, name: str) -> np.ndarray | None:
    """(V, 2) uv per vertex of a trimesh mesh (v = 0 where the file gives u only), or None."""
    uv = getattr(getattr(mesh, "visual", None), "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.ndim != 2 or len(uv) != vertex_count or uv.shape[1] == 0:
        raise SceneError(where, f"mesh {name}: texture coordinates of shape {uv.shape} for "
                                f"{vertex_count} vertices")
    uv = np.pad(uv[:, :2], ((0, 0), (0, max(0, 2 - uv.shape[1]))))
    if not np.isfinite(uv).all():
        raise SceneError(where, f"mesh {name} has texture coordinates that are NaN or infinite")
    return uv


def has_area(triangles: np.ndarray) -> np.ndarray:
    """(T,) bool: which of the (T, 3, 3) ``triangles`` have an area that is not zero."""
    area2 = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                    triangles[:, 2] - triangles[:, 0]), axis=1)
    return area2 > 0


def _read_with_trimesh(path: Path, where: str, fmt: str):
    """The trimesh mesh of a file of any format trimesh reads."""
    import trimesh

    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except ModuleNotFoundError:
        # trimesh imports a character-set detector (an optional package) only for a file
        # that is neither valid binary data of its format nor UTF-8 text.
        raise SceneError(where, f"cannot read mesh {path.name}: neither a binary .{fmt} file "
                                f"nor UTF-8 text") from None
    except Exception as error:  # trimesh raises many kinds for unreadable files
        raise SceneError(where, f"cannot read mesh {path.name}: {error}") from None
    return mesh


def read_obj(text: str) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) float64 vertices and (F, 3) int64 triangles (0-based) of OBJ text that
    ``check_obj_text`` accepted: every record at the start of its line, ``v`` lines alike,
    faces of at least three references whose vertices exist.

    Faces are cut into triangles as trimesh cuts them, in the file's order: a quad (a, b, c, d)
    into (a, b, c) and (c, d, a), a larger polygon into the fan (0, k, k + 1). A negative index
    counts back from the last vertex before its line (the check allows it only where that is
    also the end of the file, so the two readings agree).
    """
    lines = text.replace("\\\n", "").split("\n")     # (lines continued with a backslash)
    vertex_lines = [line[2:] for line in lines if line.startswith("v ")]
    size = len(vertex_lines[0].split()) if vertex_lines else 3
    vertices = np.fromstring(" ".join(vertex_lines), sep=" ").reshape(-1, size)[:, :3]
    # Faces grouped by their number of vertices, each group read at once: the vertex index is
    # what comes before a reference's first "/" (the texture and normal indices are dropped).
    by_size: dict[int, tuple[list[int], list[str]]] = {}   # size -> (face numbers, faces)
    faces = (line[2:].split() for line in lines if line.startswith("f "))
    for number, references in enumerate(faces):
        order, group = by_size.setdefault(len(references), ([], []))
        order.append(number)
        group.append(" ".join(references))
    triangles, face_of = [], []
    for count, (order, group) in by_size.items():
        index = np.fromstring(_TEXTURE_AND_NORMAL.sub("", " ".join(group)), dtype=np.int64,
                              sep=" ").reshape(-1, count)
        index = np.where(index > 0, index - 1, len(vertices) + index)
        corners = _CUTS.get(count) or [(0, k, k + 1) for k in range(1, count - 1)]
        triangles.append(index[:, np.array(corners)].reshape(-1, 3))
        face_of.append(np.repeat(order, len(corners)))
    if not triangles:
        return vertices, np.zeros((0, 3), np.int64)
    in_file_order = np.argsort(np.concatenate(face_of), kind="stable")
    return vertices, np.concatenate(triangles)[in_file_order]


#: How trimesh cuts a triangle and a quad (larger polygons: fans from the first corner).
_CUTS = {3: [(0, 1, 2)], 4: [(0, 1, 2), (2, 3, 0)]}


#: The texture and normal parts of face references (``/vt``, ``//vn``, ``/vt/vn``).
_TEXTURE_AND_NORMAL = re.compile(r"/\S*")


def drop_zero_area(triangles: np.ndarray) -> np.ndarray:
    """(T', 3, 3) the triangles of (T, 3, 3) ``triangles`` whose area is not zero."""
    return triangles[has_area(triangles)]


def check_obj_text(data: bytes) -> None:
    """Raise ``ValueError("line N: ...")`` where trimesh would misread this OBJ file.

    Checks the text (UTF-8, no byte-order mark, LF or CRLF line ends) and every ``v``,
    ``vt``, ``vn`` and ``f`` record: where it starts, its numbers, and each face's vertex
    references. Other records (``o``, ``g``, ``usemtl``, ``l``, ...) are left to trimesh.
    """
    if b"\0" in data:
        raise ValueError("contains NUL bytes: a binary file, not OBJ text")
    if data.startswith(b"\xef\xbb\xbf"):
        raise ValueError("starts with a byte-order mark, which hides its first line from "
                         "trimesh: save it as UTF-8 without BOM")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise ValueError(f"is not UTF-8 text (byte {data[error.start]:#04x} at offset "
                         f"{error.start}): a binary file, or another encoding") from None
    text = text.replace("\r\n", "\n")
    if "\r" in text:
        raise ValueError("ends its lines with CR alone, which trimesh does not split: save it "
                         "with LF or CRLF line ends")
    if not is_plain_obj(text):
        check_obj_lines(text)


#: A record that does not start its line with the keyword and a space (in text that
#: starts with a line break; beginning with one makes the search fast).
_MISPLACED = re.compile(r"\n(?:[^\S\n]+(?:v|vt|vn|f)(?:[^\S\n]|\n|$)|(?:v|vt|vn|f)(?:[^\S\n ]|\n|$))")
#: A face's references in each form, with positive indices.
_FORMS = {"i": "[0-9]+", "i/i": "[0-9]+/[0-9]+", "i//i": "[0-9]+//[0-9]+",
          "i/i/i": "[0-9]+/[0-9]+/[0-9]+"}


def is_plain_obj(text: str) -> bool:
    """True if the OBJ text is written the common way, which a few scans of the whole text
    can confirm (measured on a 330 000-face file: 5x faster than ``check_obj_lines``, and
    faster than trimesh's own reading): no continued lines,
    records at the start of their lines and without comments, every ``v`` (``vt``, ``vn``)
    with as many numbers, and every face in one form, with positive indices of vertices
    that exist. False means only that ``check_obj_lines`` must look line by line.
    """
    text = "\n" + text
    if "\\\n" in text or _MISPLACED.search(text) or _commented_record(text):
        return False
    for keyword, (fewest, most) in _RECORD_SIZES.items():
        first = re.search(rf"\n{keyword} (.*)", text)
        if first is None:
            continue
        size = len(first.group(1).split())
        unlike = rf"\n{keyword} (?![ \t]*{_NUMBER}(?:[ \t]+{_NUMBER}){{{size - 1}}}[ \t]*(?:\n|$))"
        if not fewest <= size <= most or re.search(unlike, text):
            return False
    faces = re.findall(r"\nf (.*)", text)
    if not faces or not faces[0].split():
        return False
    form = _form(faces[0].split()[0])
    if form not in _FORMS:
        return False
    reference = _FORMS[form]
    if re.search(rf"\nf (?![ \t]*{reference}(?:[ \t]+{reference}){{2,}}[ \t]*(?:\n|$))", text):
        return False
    numbers = " ".join(faces).replace("/", " ")
    if re.search("[0-9]{19}", numbers):      # an index beyond int64: surely no such vertex
        return False
    indices = np.fromstring(numbers, dtype=np.int64, sep=" ")[::form.count("i")]
    return 1 <= indices.min() and indices.max() <= text.count("\nv ")


def _commented_record(text: str) -> bool:
    """Whether a ``v``, ``vt``, ``vn`` or ``f`` line of ``text`` holds a comment (a ``#``)."""
    for hash_sign in re.finditer("#", text):      # (few: comments are rare in big files)
        start = text.rfind("\n", 0, hash_sign.start()) + 1
        if text.startswith(("v ", "vt ", "vn ", "f "), start):
            return True
    return False


def check_obj_lines(text: str) -> None:
    """Raise ``ValueError("line N: ...")`` for the first record trimesh would misread."""
    records = list(_obj_records(text))
    vertex_count = sum(keyword == "v" for _, keyword, _ in records)
    sizes: dict[str, tuple[int, int]] = {}     # record keyword -> (size, first line with it)
    forms: dict[int, tuple[str, int]] = {}     # numbers in a face -> (its form, first line)
    vertices_so_far = faces = 0
    for number, keyword, line in records:
        fields = line.split()[1:]
        if keyword == "f":
            _check_face(number, line, fields, vertices_so_far, vertex_count, forms)
            faces += 1
            continue
        if not _NUMBERS_RECORD.fullmatch(line):
            bad = next((f for f in fields if not re.fullmatch(_NUMBER, f)), None)
            raise ValueError(f"line {number}: {bad!r} is not a number" if bad else
                             f"line {number}: separate the numbers with spaces or tabs")
        fewest, most = _RECORD_SIZES[keyword]
        if not fewest <= len(fields) <= most:
            expected = f"{fewest}" if fewest == most else f"{fewest} to {most}"
            raise ValueError(f"line {number}: `{keyword}` needs {expected} numbers, got "
                             f"{len(fields)}")
        size, first = sizes.setdefault(keyword, (len(fields), number))
        if len(fields) != size:
            raise ValueError(f"line {number}: `{keyword}` has {len(fields)} numbers but line "
                             f"{first}'s has {size}: write every `{keyword}` alike")
        vertices_so_far += keyword == "v"
    if faces == 0:
        raise ValueError("has no faces (`f` lines)" if vertex_count else
                         "has no vertices or faces (`v` and `f` lines): is it an OBJ file?")


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
        if not line or line[0] not in "vf" and not line[0].isspace():   # (a quick skip)
            continue
        words = line.split(None, 1)
        if not words or words[0] not in ("v", "vt", "vn", "f"):
            continue
        keyword = words[0]
        if not line.startswith(keyword + " "):
            raise ValueError(f"line {start}: write `{keyword}` at the very start of the line, "
                             f"with a space after it: trimesh skips the line otherwise")
        if "#" in line:
            raise ValueError(f"line {start}: a comment after the data; trimesh reads "
                             f"comments only on lines of their own")
        yield start, keyword, line


def _form(reference: str) -> str:
    """The form of a vertex reference: ``i``, ``i/i``, ``i//i`` or ``i/i/i``."""
    return re.sub(r"-?[0-9]+", "i", reference)


def _check_face(number: int, line: str, references: list[str], vertices_so_far: int,
                vertex_count: int, forms: dict[int, tuple[str, int]]) -> None:
    """Raise ``ValueError`` for a face that trimesh would drop or misread."""
    if len(references) < 3:
        raise ValueError(f"line {number}: a face needs at least 3 vertices, got "
                         f"{len(references)} (`{line.strip()}`)")
    if not _FACE_RECORD.fullmatch(line):
        bad = next((r for r in references if not re.fullmatch(_REFERENCE, r)), None)
        raise ValueError(f"line {number}: {bad!r} is not a vertex reference (v, v/vt, v//vn "
                         f"or v/vt/vn)" if bad else
                         f"line {number}: separate the references with spaces or tabs")
    # All references are in the first one's form if the line has as many slashes, and as
    # many double slashes, as that many copies of it.
    first = references[0]
    slashes, doubles = first.count("/"), first.count("//")
    if line.count("/") != slashes * len(references) or \
            line.count("//") != doubles * len(references):
        raise ValueError(f"line {number}: the face mixes reference forms "
                         f"({', '.join(sorted({_form(r) for r in references}))}): write its "
                         f"vertices alike")
    indices = [int(r.split("/", 1)[0]) for r in references] if slashes else \
        list(map(int, references))
    low, high = min(indices), max(indices)
    if low <= 0 <= high and 0 in indices:
        raise ValueError(f"line {number}: vertex index 0 (OBJ counts vertices from 1)")
    for index in (high, low):
        if index > vertex_count or -index > vertices_so_far:
            raise ValueError(f"line {number}: vertex {index} does not exist (the file has "
                             f"{vertex_count} vertices, {vertices_so_far} before this line)")
    if low < 0 and vertices_so_far != vertex_count:
        raise ValueError(f"line {number}: negative vertex index {low} with vertices after "
                         f"this line: trimesh would count it from the end of the file; use "
                         f"positive indices")
    # trimesh reads the faces that have as many numbers as the first such face in its form.
    form = _form(first)
    first_form, first_line = forms.setdefault(len(references) * (slashes - doubles + 1),
                                              (form, number))
    if form != first_form:
        raise ValueError(f"line {number}: this face ({form}) and line {first_line}'s "
                         f"({first_form}) have as many numbers, so trimesh reads them in one "
                         f"form: write the faces alike")
