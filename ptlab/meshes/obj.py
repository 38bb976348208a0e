"""OBJ files: ptlab's own reader, the whole text parsed at once.

``read_obj`` is one reader for every OBJ file, with texture coordinates or without. It
parses the whole text at once (``parse_obj``: lines found and classified by whole-array
operations on the bytes, each kind of record's numbers read by one ``np.fromstring``), so
that no Python loop runs per line: a 1.3 million-triangle file reads faster than trimesh
reads it (docs/performance.md). Its triangles are trimesh's, in the file's order, so images
are the same; and a render of OBJ meshes imports neither trimesh nor, through it, SciPy,
which spares it a second of start-up.

trimesh's OBJ reader is fast because it is lenient, and some of its leniency goes wrong
silently: it takes the number of values per vertex from the first ``v`` line, skips ``v``
and ``f`` lines that do not begin with the keyword and a space (a tab, which the format
allows there too, ``read_obj`` reads), drops faces of fewer than three vertices, counts
negative indices from the end of the file rather than from their line, and reads a face
whose references mix forms (``1/2`` beside ``3``) as other vertices. ``read_obj`` refuses
each of these and names the line, so that a malformed OBJ file, which other programs may
misread, is an error instead of a wrong picture: the parse itself confirms that a file is
written the common way (``ObjRecords.plain``), and only where it cannot does
``check_obj_lines`` look line by line.

Beyond the triangles, ``read_obj_mesh`` reads what else a file says of its surface: vertex
normals (``vn`` records, ``f v/vt/vn`` or ``f v//vn``), and materials: ``mtllib`` names
material files (``ptlab.meshes.mtl``), ``usemtl`` gives the faces after it a material.
"""

from __future__ import annotations

import functools
import itertools
import re
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.meshes.base import UV_LIMIT, FileMaterial, IndexedMesh
from ptlab.meshes.mtl import read_mtl

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


def read_obj(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The triangles of an OBJ file, read the way trimesh reads them, or ``ValueError("line
    N: ...")`` where trimesh would misread the file (module docstring).

    Faces are cut into triangles as trimesh cuts them, in the file's order: a quad (a, b, c, d)
    into (a, b, c) and (c, d, a), a larger polygon into the fan (0, k, k + 1).

    Returns:
        vertices: (V, 3) float64, each ``v`` record's first three numbers;
        faces: (F, 3) int64 0-based vertex indices of each triangle;
        uv: (F, 3, 2) float64 texture coordinates of each triangle's vertices (a ``vt``
        record's u and v; v = 0 where it gives u only), or None where some face gives none.
        A face that refers to a ``vt`` record that does not exist, or one that is not a
        finite float32 number, is an error.
    """
    text = _obj_text(data)
    records = _checked_records(text, statements=False)
    # (Where every face is a triangle, nothing is cut: each is its three references.)
    corners = None if (records.face_sizes == 3).all() else _fan_corners(records.face_sizes)
    faces = _by_triangle(records.vertex_references, corners)
    return records.vertices, faces, _triangle_uv(records, corners, text)


def read_obj_mesh(data: bytes, folder: Path) -> IndexedMesh:
    """Everything ptlab reads of an OBJ file's bytes (``read_obj``'s triangles, their normals
    and materials), its material files looked for in ``folder``; ``ValueError`` naming the
    line (of the OBJ file, or of a material file) that is wrong.

    Vertex normals are read where every face gives them (``v//vn``, ``v/vt/vn``) and all of
    them exist; else they are left out, and ``unused`` says why.
    """
    text = _obj_text(data)
    records = _checked_records(text)
    corners = None if (records.face_sizes == 3).all() else _fan_corners(records.face_sizes)
    mesh = IndexedMesh(records.vertices, _by_triangle(records.vertex_references, corners))
    mesh.uv = _triangle_uv(records, corners, text)
    if records.normal_references is not None:
        mesh.normals = records.normals[_by_triangle(records.normal_references, corners)]
    elif records.normal_problem:
        mesh.unused.append(f"vertex normals ({records.normal_problem})")
    if records.smoothing and len(records.normals) == 0:
        mesh.unused.append("smoothing groups (`s`): without `vn` normals the faces stay flat")
    for keyword, what in ((b"l", "lines (`l`)"), (b"p", "points (`p`)")):
        # (Byte searches, as fast as the text is long: no surface, nothing a ray can hit.)
        if any(
            text.startswith(keyword + blank) or b"\n" + keyword + blank in text for blank in (b" ", b"\t")
        ):
            mesh.unused.append(f"{what}: ptlab renders surfaces only")
    if records.libraries or records.face_materials is not None:
        mesh.materials, material_ids, unused = _obj_materials(records, folder)
        mesh.unused += unused
        if material_ids is not None:
            # (A face's triangles are consecutive, in the faces' order: ``_fan_corners``.)
            mesh.material_ids = np.repeat(material_ids, records.face_sizes - 2)
    return mesh


def _checked_records(text: bytes, statements: bool = True) -> ObjRecords:
    """``parse_obj``'s records of OBJ text, or ``ValueError`` for the first line trimesh
    would misread (``check_obj_lines``)."""
    records = parse_obj(text, statements)
    if records is None or not records.plain:
        check_obj_lines(text.decode("utf-8"))
        # (check_obj_lines accepts only text that parse_obj reads.)
        assert records is not None
    return records


def _triangle_uv(records: ObjRecords, corners: np.ndarray | None, text: bytes) -> np.ndarray | None:
    """(T, 3, 2) the texture coordinates of each triangle's corners (``read_obj``), or None;
    ``ValueError`` naming the line of a ``vt`` record a face uses whose numbers are not
    finite or lie beyond ``UV_LIMIT``."""
    references = records.texture_references
    if references is None:
        return None
    within = (np.abs(records.texture) <= UV_LIMIT).all(axis=1)
    if not within.all():  # (the records are looked at first: there are fewer than references)
        used = np.zeros(len(within), bool)
        used[references] = True
        wrong = np.flatnonzero(used & ~within)
        if len(wrong):
            number, line = _record_line(text, "vt", int(wrong[0]))
            raise ValueError(
                f"line {number}: `{line.strip()}`: texture coordinates must be finite numbers "
                f"within +-{UV_LIMIT:.4g} (half of float32's largest)"
            )
    return records.texture[_by_triangle(references, corners)]


def _record_line(text: bytes, keyword: str, index: int) -> tuple[int, str]:
    """(line number, line) of record ``index`` (from 0) of kind ``keyword`` in OBJ text."""
    lines = (record for record in _obj_records(text.decode("utf-8")) if record[1] == keyword)
    number, _, line = next(itertools.islice(lines, index, None))
    return number, line


def _obj_materials(
    records: ObjRecords, folder: Path
) -> tuple[list[FileMaterial], np.ndarray | None, list[str]]:
    """The materials the faces use, found in the file's material libraries (``mtllib``):
    ([FileMaterial] in order of first use, (F,) each face's index among them (-1: none),
    what ptlab does not use of them)."""
    library: dict[str, FileMaterial] = {}
    unused_of: dict[str, list[str]] = {}
    unused: list[str] = []
    for line in records.libraries:
        # (One name, which may hold spaces, or several: the specification allows a list. A
        # line that is neither one file nor files that all exist is one name, not found.)
        names = line.split()
        if (folder / line).is_file() or not all((folder / name).is_file() for name in names):
            names = [line]
        for name in names:
            _read_library(folder, name, library, unused_of, unused)
    if records.face_materials is None:
        return [], None, unused
    used: list[FileMaterial] = []
    ids = np.full(len(records.material_names) + 1, -1, dtype=np.intp)
    for k, name in enumerate(records.material_names):
        if name in library:
            ids[k] = len(used)
            used.append(library[name])
            unused += [u for u in unused_of[name] if u not in unused]
        else:
            unused.append(f"material {name} (in no material library)")
    # (-1, a face before any ``usemtl``, takes the last entry: -1.)
    return used, ids[records.face_materials], unused


def _read_library(
    folder: Path,
    name: str,
    library: dict[str, FileMaterial],
    unused_of: dict[str, list[str]],
    unused: list[str],
) -> None:
    """Add the materials of material file ``name`` (in ``folder``) to ``library`` (the first
    of a name wins), what ptlab does not use of each to ``unused_of``; a file not found, to
    ``unused``."""
    path = folder / name
    if not path.is_file() and "\\" in name:  # (written on Windows)
        path = folder / name.replace("\\", "/")
    if not path.is_file():
        unused.append(f"material library '{name}' (not found in {folder})")
        return
    for material, ignored in read_mtl(path):
        library.setdefault(material.name, material)
        unused_of.setdefault(material.name, ignored)


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
    """The ``v``, ``vt``, ``vn`` and ``f`` records of OBJ text, parsed at once (``parse_obj``),
    and the faces' materials (``usemtl``, ``mtllib``).

    Attributes:
        vertices: (V, 3) float64, each ``v`` record's first three numbers.
        texture: (VT, 2) float64 ``vt`` records' u and v (0 where a record gives u only).
        vertex_references: (R,) int64 0-based vertex of every face's every reference, in
            the file's order.
        texture_references: (R,) int64 0-based ``vt`` record of every reference, or None
            where some face gives none (one that does not exist is an error).
        normals: (VN, 3) float64 ``vn`` records.
        normal_references: (R,) int64 0-based ``vn`` record of every reference, or None
            where some face gives none or one that does not exist (``normal_problem``).
        normal_problem: why faces that give normals have none here ("" if none do, or all do).
        face_sizes: (F,) the number of references of each face.
        face_materials: (F,) intp each face's material, an index into ``material_names``
            (-1 before any ``usemtl`` line), or None where the file has no ``usemtl``.
        material_names: the names ``usemtl`` lines give, each once, in order of first use.
        libraries: the argument of each ``mtllib`` line (one file name or several).
        smoothing: an ``s`` line turns smoothing groups on (not ``off`` or 0).
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
    normals: np.ndarray
    normal_references: np.ndarray | None
    normal_problem: str
    face_materials: np.ndarray | None
    material_names: list[str]
    libraries: list[str]
    smoothing: bool


def parse_obj(text: bytes, statements: bool = True) -> ObjRecords | None:
    """The records of OBJ text (LF line ends), read by a few whole-array operations on its
    bytes, or None where they cannot be read that way (then ``check_obj_lines`` finds a
    line that is wrong).

    Lines are found by their line feeds and classified by their first three bytes; the lines
    of each kind of record are gathered into one array of bytes (keyword blanked), whose
    fields one ``np.fromstring`` call reads. Bytes of a few classes (separators, slashes)
    give the fields of each line and their forms. No Python loop runs over lines, so reading
    takes a time proportional to the file's size (docs/performance.md). ``statements``: look
    for the ``usemtl``, ``mtllib`` and ``s`` lines too (three more searches of the whole text,
    left out where only the triangles are wanted).
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
    face_lines = kind == _KINDS["f"]

    @functools.cache
    def before(record: str) -> np.ndarray:
        """(F,) how many records of kind ``record`` come before each face's line (made only
        for negative indices, which count back from there)."""
        return np.cumsum(kind == _KINDS[record])[face_lines]

    counts = {record: len(values) for record, values in numbers.items()}
    faces = _face_records(lines_of("f"), before, counts)
    if faces is None:
        return None
    texture = numbers["vt"][:, :2]
    face_materials, material_names = _face_materials(joined, starts[face_lines]) if statements else (None, [])
    smoothing = statements and any(group not in ("off", "0") for _, group in _statements(joined, b"s"))
    return ObjRecords(
        vertices=numbers["v"][:, :3],
        texture=np.pad(texture, ((0, 0), (0, 2 - texture.shape[1]))),
        vertex_references=faces.vertex,
        texture_references=faces.texture,
        face_sizes=faces.sizes,
        plain=not continued and not misplaced.any() and not commented and plain_numbers and faces.plain,
        normals=numbers["vn"],
        normal_references=faces.normal,
        normal_problem=faces.normal_problem,
        face_materials=face_materials,
        material_names=material_names,
        libraries=[name for _, name in _statements(joined, b"mtllib")] if statements else [],
        smoothing=smoothing,
    )


def _statements(text: bytes, keyword: bytes) -> list[tuple[int, str]]:
    """(where its line starts, its argument) for each line of OBJ text (LF line ends) that
    is ``keyword``, blanks and an argument: a material's name, a file's, a group's."""
    if keyword not in text:  # (the common case, found at the speed of a byte search)
        return []
    # (A literal start lets the search skip ahead as fast; the first line is looked at alone.)
    found = [(match.start() + 1, match) for match in re.finditer(rb"\n" + keyword + rb"[ \t]+([^\n]*)", text)]
    if (first := re.match(keyword + rb"[ \t]+([^\n]*)", text)) is not None:
        found.insert(0, (0, first))
    return [(start, match.group(1).decode("utf-8").strip()) for start, match in found]


def _face_materials(text: bytes, face_starts: np.ndarray) -> tuple[np.ndarray | None, list[str]]:
    """(F,) each face's material, as an index into the names of the materials that ``usemtl``
    lines give (-1 before the first), and those names, each once; (None, []) without any."""
    statements = _statements(text, b"usemtl")
    if not statements:
        return None, []
    names: dict[str, int] = {}
    material_of_line = np.array([names.setdefault(name, len(names)) for _, name in statements] + [-1])
    # The last ``usemtl`` line before each face (-1: none, which picks the -1 at the end).
    line = np.searchsorted([start for start, _ in statements], face_starts) - 1
    return material_of_line[line], list(names)


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
#: character that may be whitespace): a keyword followed by one of these but a space or a
#: tab is a misplaced record, as is a record after any of them.
_BLANK = _byte_class(bytes(range(0x21)) + bytes(range(0x80, 0x100)))
#: What may follow a record's keyword: a space or a tab.
_AFTER_KEYWORD = _byte_class(b" \t")


def _line_kinds(data: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(L,) uint8 kind of each line (``_KINDS``, from its first three bytes), and (L,) bool:
    which lines may be misplaced records (indented, or a keyword followed by other
    whitespace than a space or a tab)."""

    def byte(k: int) -> np.ndarray:
        """Byte k of every line; a line feed beyond a line's end."""
        return np.where(ends - starts > k, data[np.minimum(starts + k, len(data) - 1)], _NEWLINE)

    b0, b1, b2 = byte(0), byte(1), byte(2)
    v, f = b0 == ord("v"), b0 == ord("f")
    vt_or_vn = v & ((b1 == ord("t")) | (b1 == ord("n")))
    kind = np.zeros(len(starts), np.uint8)
    after1, after2 = _AFTER_KEYWORD[b1], _AFTER_KEYWORD[b2]
    kind[v & after1] = _KINDS["v"]
    kind[vt_or_vn & (b1 == ord("t")) & after2] = _KINDS["vt"]
    kind[vt_or_vn & (b1 == ord("n")) & after2] = _KINDS["vn"]
    kind[f & after1] = _KINDS["f"]
    misplaced = (
        (_BLANK[b0] & (b0 != _NEWLINE)) | ((v | f) & _BLANK[b1] & ~after1) | (vt_or_vn & _BLANK[b2] & ~after2)
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


@dataclass
class _FaceRecords:
    """The references of F faces (``_face_records``).

    Attributes:
        vertex: (R,) 0-based vertices; texture, normal: (R,) 0-based ``vt``, ``vn`` records,
            or None (``ObjRecords``); normal_problem: why normal is None where faces give some.
        sizes: (F,) references per face. plain: the faces are written the common way.
    """

    vertex: np.ndarray
    texture: np.ndarray | None
    normal: np.ndarray | None
    normal_problem: str
    sizes: np.ndarray
    plain: bool


def _face_records(
    stream: np.ndarray, before: Callable[[str], np.ndarray], counts: dict[str, int]
) -> _FaceRecords | None:
    """The references of F faces, from their lines' bytes (keyword blanked), the number of
    records of each kind before each line (``before(record)``, (F,)) and in the file
    (``counts``); or None."""
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

    def last_numbers() -> np.ndarray:
        """(R,) the last number of each reference (its vn, where it gives one)."""
        return numbers_at(int(per[0])) if first is None else numbers[first + np.repeat(per, sizes)]

    written = numbers_at(0)
    vertex = _zero_based(written, lambda: before("v"), sizes, counts["v"])
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
        texture = _zero_based(numbers_at(1), lambda: before("vt"), sizes, counts["vt"])
        if texture is None:  # (a `vt` that does not exist: check_obj_lines names the line)
            return None
    normal, normal_problem = _normal_references(
        (per == 2) | (doubles > 0), last_numbers, lambda: before("vn"), sizes, counts["vn"]
    )
    return _FaceRecords(vertex, texture, normal, normal_problem, sizes, plain)


def _normal_references(
    with_normal: np.ndarray,
    written: Callable[[], np.ndarray],
    before: Callable[[], np.ndarray],
    sizes: np.ndarray,
    count: int,
) -> tuple[np.ndarray | None, str]:
    """(R,) 0-based ``vn`` records of every reference, from (F,) which faces give normals (in
    the form v/vt/vn or v//vn) and their indices as ``written``; or None, and why not (""
    where no face gives any)."""
    if not with_normal.all():
        return None, "some faces give none" if with_normal.any() else ""
    normal = _zero_based(written(), before, sizes, count)
    return normal, "" if normal is not None else "a face refers to a `vn` record that does not exist"


def _zero_based(
    index: np.ndarray, before: Callable[[], np.ndarray], sizes: np.ndarray, count: int
) -> np.ndarray | None:
    """(R,) 0-based records of the (R,) OBJ indices of faces of (F,) ``sizes`` references
    (from 1, or negative: counted back from the last of the (F,) ``before()`` records before
    the face's line), or None if one of them is not among the ``count`` records."""
    if index.min() > 0:  # (the common case: spare the negatives)
        return index - 1 if index.max() <= count else None
    zero_based = np.where(index > 0, index - 1, index + np.repeat(before(), sizes))
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
    count = Counter(keyword for _, keyword, _ in records)  # records of each kind in the file
    so_far: Counter[str] = Counter()  # ... before the line
    sizes: dict[str, tuple[int, int]] = {}  # record keyword -> (size, first line with it)
    forms: dict[int, tuple[str, int]] = {}  # numbers in a face -> (its form, first line)
    for number, keyword, line in records:
        fields = line.split()[1:]
        so_far[keyword] += 1
        if keyword == "f":
            _check_face(number, line, fields, so_far, count, forms)
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
    if count["f"] == 0:
        raise ValueError(
            "has no faces (`f` lines)"
            if count["v"]
            else "has no vertices or faces (`v` and `f` lines): is it an OBJ file?"
        )


def _obj_records(text: str):
    """(line number, keyword, line) of each ``v``, ``vt``, ``vn`` and ``f`` line.

    trimesh joins lines ending in a backslash to the next one, and finds a record only at the
    very start of a line, followed by a space (here, or a tab); comments must be lines of their
    own.
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
        if not line.startswith(keyword) or line[len(keyword) : len(keyword) + 1] not in (" ", "\t"):
            raise ValueError(
                f"line {start}: write `{keyword}` at the very start of the line, followed by a space or a tab"
            )
        if "#" in line:
            raise ValueError(
                f"line {start}: a comment after the data; trimesh reads comments only on lines of their own"
            )
        yield start, keyword, line


def _check_indices(number: int, indices: list[int], names: tuple[str, str], so_far: int, count: int) -> None:
    """Raise ``ValueError`` unless the OBJ ``indices`` a face on line ``number`` gives (from
    1, or negative: counted back from the last record before the line) refer to records that
    exist, ``so_far`` before the line and ``count`` in the file (``names``: what one and
    several records are called)."""
    one, several = names
    if 0 in indices:
        raise ValueError(f"line {number}: {one} index 0 (OBJ counts {several} from 1)")
    for index in (max(indices), min(indices)):
        if index > count or -index > so_far:
            raise ValueError(
                f"line {number}: {one} {index} does not exist (the file has "
                f"{count} {several}, {so_far} before this line)"
            )


def _form(reference: str) -> str:
    """The form of a vertex reference: ``i``, ``i/i``, ``i//i`` or ``i/i/i``."""
    return re.sub(r"-?[0-9]+", "i", reference)


def _check_face(
    number: int,
    line: str,
    references: list[str],
    so_far: Counter[str],
    count: Counter[str],
    forms: dict[int, tuple[str, int]],
) -> None:
    """Raise ``ValueError`` for a face that trimesh would drop or misread, or that refers to
    records (``v``, ``vt``) that do not exist; ``so_far`` and ``count``: how many records of
    each kind come before the line, and in the file."""
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
    numbers = [r.split("/") for r in references]
    indices = [int(n[0]) for n in numbers]
    _check_indices(number, indices, ("vertex", "vertices"), so_far["v"], count["v"])
    if slashes and not doubles:  # (v/vt or v/vt/vn)
        textures = [int(n[1]) for n in numbers]
        _check_indices(number, textures, ("`vt` record", "`vt` records"), so_far["vt"], count["vt"])
    low = min(indices)
    if low < 0 and so_far["v"] != count["v"]:
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
