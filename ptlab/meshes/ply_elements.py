"""The elements of a PLY file, read with NumPy and held to the file's header.

A PLY file is a header, which announces each element (vertices, faces, ...), how many of it
and its properties, each a number or a list (a count, then as many numbers), then the
elements' data: text, one element a line, or binary, little- or big-endian (Turk, "The PLY
Polygon File Format", 1994, at paulbourke.net/dataformats/ply). ``read_ply_elements`` reads
any such file and holds it to its header: a text file has exactly the lines its header
announces (blank lines aside), each with exactly the numbers its properties take, and a
binary file exactly the bytes. A file cut short, one with more data than its header
announces, a word that is not a number, is an error that names the line (or the element)
and what is wrong.

Binary lists of varying lengths (a mesh of triangles and quads) are read too: where every
list has the first element's length, the data is one NumPy view of the bytes; else a loop
first finds where each list starts (each list's length moves the next).
"""

from __future__ import annotations

import re
import struct
import warnings
from dataclasses import dataclass, field

import numpy as np

#: NumPy's type of each PLY property type: the specification's (char ... double), the sized
#: names later writers use (int8 ... float64), and the 64-bit and half types a few write.
PLY_TYPES = {
    **dict.fromkeys(("char", "int8"), "i1"),
    **dict.fromkeys(("uchar", "uint8"), "u1"),
    **dict.fromkeys(("short", "int16"), "i2"),
    **dict.fromkeys(("ushort", "uint16"), "u2"),
    **dict.fromkeys(("int", "int32"), "i4"),
    **dict.fromkeys(("uint", "uint32"), "u4"),
    "int64": "i8",
    "uint64": "u8",
    "float16": "f2",
    **dict.fromkeys(("float", "float32"), "f4"),
    **dict.fromkeys(("double", "float64"), "f8"),
}
#: The formats a header may give, and the byte order of each ("" for text).
FORMATS = {"ascii": "", "binary_little_endian": "<", "binary_big_endian": ">"}

#: The ``struct`` code of each integer type (a list's count).
_STRUCT_CODES = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "i8": "q", "u8": "Q"}
#: Control characters, shown as "?" where a message quotes a header.
_UNPRINTABLE = dict.fromkeys([*range(9), *range(11, 13), *range(14, 32), 127], "?")
#: The header's last line (with its line end, the header's last bytes).
_END_HEADER = re.compile(rb"^end_header[ \t]*\r?(?:\n|\Z)", re.MULTILINE)
#: The bytes that separate words in a text file's data: those ``bytes.split`` splits at.
_BLANKS = np.zeros(256, bool)
_BLANKS[list(b" \t\n\r\x0b\x0c")] = True


@dataclass(frozen=True)
class PlyProperty:
    """A property of an element: its name, its numbers' type (a key of ``PLY_TYPES``), and
    for a list, the type of its count ("" for a single number)."""

    name: str
    kind: str
    count_kind: str = ""

    def __str__(self) -> str:
        return f"list {self.name}" if self.count_kind else self.name


@dataclass
class PlyElement:
    """An element the header announces: its name, how many, and its properties."""

    name: str
    count: int
    properties: list[PlyProperty] = field(default_factory=list)

    def least_bytes(self) -> int:
        """The fewest bytes this element's binary data can take (each list empty)."""
        sizes = [np.dtype(PLY_TYPES[p.count_kind or p.kind]).itemsize for p in self.properties]
        return self.count * sum(sizes)


@dataclass
class PlyHeader:
    """A PLY file's header: its byte order ("" for text), its elements, the texture images
    its comments name (``comment TextureFile``), where its data starts, and its lines."""

    byte_order: str
    elements: list[PlyElement]
    texture_files: list[str]
    data_start: int
    lines: int

    def announces(self) -> str:
        """The elements it announces, in words: "8 `vertex` and 12 `face` elements"."""
        counts = [f"{element.count} `{element.name}`" for element in self.elements]
        return " and ".join([", ".join(counts[:-1]), counts[-1]] if len(counts) > 1 else counts) + " elements"


@dataclass
class PlyList:
    """A list property of every element: (n,) int64 ``counts``, and their numbers one list
    after another, (counts.sum(),) as stored (from a text file int64, or float64 where some
    are not integers); ``words``, for a text file, which of its words each number is (for
    messages)."""

    counts: np.ndarray
    values: np.ndarray
    words: np.ndarray | None = None

    def row_of(self, k: int) -> int:
        """Which element's list holds number ``k``."""
        return int(np.searchsorted(np.cumsum(self.counts), k, side="right"))


#: What an element holds: each property's (n,) numbers, or its lists, by name.
Properties = dict[str, "np.ndarray | PlyList"]


@dataclass
class PlyData:
    """A PLY file read: its header and each element's properties, by the element's name. A
    text file's data is kept too, and the line of each element (for messages)."""

    header: PlyHeader
    elements: dict[str, Properties]
    text: _Text | None = None
    lines: dict[str, np.ndarray] = field(default_factory=dict)

    def count(self, element: str) -> int:
        """How many of ``element`` the file holds (0 for an element it does not announce)."""
        return next((e.count for e in self.header.elements if e.name == element), 0)

    def where(self, element: str, row: int) -> str:
        """Where element ``row`` of ``element`` is written: "line 14" or "`face` 3 of 12"."""
        if element in self.lines:
            return f"line {self.lines[element][row]}"
        return f"`{element}` {row + 1} of {self.count(element)}"

    def written(self, values: PlyList, k: int) -> str:
        """Number ``k`` of a list, as the file writes it."""
        if self.text is None or values.words is None:
            return str(values.values[k].item())
        return self.text.word(int(values.words[k]))


def read_ply_elements(data: bytes) -> PlyData:
    """Every element of a PLY file's bytes, or ``ValueError`` for a file that is not PLY or
    whose data is not exactly what its header announces (module docstring)."""
    header = ply_header(data)
    if header.byte_order:
        return PlyData(header, _binary_elements(data, header))
    return _text_elements(data, header)


def ply_header(data: bytes) -> PlyHeader:
    """The header of a PLY file's bytes, or ``ValueError`` naming its line that is wrong."""
    if not re.match(rb"ply[ \t]*\r?\n", data):
        raise ValueError("not a PLY file (its first line is not `ply`)")
    end = _END_HEADER.search(data)
    if end is None:
        raise ValueError("truncated or malformed: its header has no `end_header` line")
    byte_order = None
    elements: list[PlyElement] = []
    texture_files = []
    text = data[: end.start()].decode("ascii", errors="replace").translate(_UNPRINTABLE)
    lines = text.splitlines()
    for number, line in enumerate(lines[1:], start=2):
        words = line.split()
        if words[:1] in (["comment"], ["obj_info"]) and words[1:2] == ["TextureFile"]:
            texture_files.append(line.split("TextureFile", 1)[1].strip())
        try:
            found = _header_line(words, elements)
            if found is not None and byte_order is not None:
                raise ValueError("a second `format` line")
        except ValueError as error:
            raise ValueError(f"line {number} of its header (`{line.strip()[:60]}`): {error}") from None
        byte_order = byte_order if found is None else found
    if byte_order is None:
        raise ValueError("its header has no `format` line")
    return PlyHeader(byte_order, elements, texture_files, end.end(), data.count(b"\n", 0, end.end()))


def _header_line(words: list[str], elements: list[PlyElement]) -> str | None:
    """Read a header line's ``words``: an element or a property is added to ``elements``; a
    format line gives its byte order; a comment, nothing (None). ``ValueError`` for a line
    that is none of these."""
    if not words or words[0] in ("comment", "obj_info"):
        return None
    if words[0] == "format":
        if len(words) != 3 or words[1] not in FORMATS:
            raise ValueError(f"the format is one of {', '.join(FORMATS)}, then a version")
        return FORMATS[words[1]]
    if words[0] == "element":
        if len(words) != 3 or not (words[2].isascii() and words[2].isdigit()):
            raise ValueError("an element is `element NAME COUNT`, its count 0 or more")
        if any(element.name == words[1] for element in elements):
            raise ValueError(f"a second element `{words[1]}`")
        elements.append(PlyElement(words[1], int(words[2])))
    elif words[0] == "property" and elements:
        found = _property(words)
        if any(prop.name == found.name for prop in elements[-1].properties):
            raise ValueError(f"a second property `{found.name}` of element `{elements[-1].name}`")
        elements[-1].properties.append(found)
    else:
        keywords = "format, element, property (after an element), comment, obj_info, end_header"
        raise ValueError(f"`{words[0]}` is not a header keyword here ({keywords})")
    return None


def _property(words: list[str]) -> PlyProperty:
    """The property a header line's ``words`` declare, or ``ValueError``."""
    if words[1:2] == ["list"]:
        if len(words) != 5:
            raise ValueError("a list is `property list COUNT_TYPE TYPE NAME`")
        found = PlyProperty(words[4], words[3], words[2])
    elif len(words) != 3:
        raise ValueError("a property is `property TYPE NAME`")
    else:
        found = PlyProperty(words[2], words[1])
    for kind in (found.count_kind, found.kind):
        if kind and kind not in PLY_TYPES:
            raise ValueError(
                f"unknown type `{kind}` (PLY's are char, uchar, short, ushort, int, uint, float, "
                f"double, and their sized names, int8 to float64)"
            )
    if found.count_kind and PLY_TYPES[found.count_kind][0] == "f":
        raise ValueError(f"a list's count is a whole number, not `{found.count_kind}`")
    return found


def _truncated(header: PlyHeader, element: PlyElement, held: int) -> ValueError:
    """The error of a file whose data ends after ``held`` of ``element``."""
    return ValueError(
        f"truncated: its header announces {header.announces()}, but the file holds {held} `{element.name}`"
    )


# -- binary data -------------------------------------------------------------------------------


def _binary_elements(data: bytes, header: PlyHeader) -> dict[str, Properties]:
    """Each element's properties, read from a binary file's bytes (``read_ply_elements``)."""
    least = sum(element.least_bytes() for element in header.elements)
    held = len(data) - header.data_start
    if held < least:  # (before anything is made, however many the header announces)
        raise ValueError(
            f"truncated: its header announces {header.announces()}, which take at least "
            f"{least} bytes, but the file holds {held} bytes of data"
        )
    elements = {}
    offset = header.data_start
    for element in header.elements:
        elements[element.name], offset = _binary_element(data, offset, element, header)
    if offset < len(data):
        raise ValueError(
            f"its header announces {header.announces()}, but the file holds "
            f"{len(data) - offset} bytes more than they take"
        )
    return elements


def _binary_element(
    data: bytes, offset: int, element: PlyElement, header: PlyHeader
) -> tuple[Properties, int]:
    """An element's properties, read from ``data`` at ``offset``, and where it ends."""
    if element.count == 0 or not element.properties:
        return {p.name: _none(p) for p in element.properties}, offset
    order = header.byte_order
    first = _list_offsets(data, offset, element, header, rows=1)
    lengths = {p: int(_at(data, at, _type(order, p.count_kind))[0]) for p, at in first.items()}
    fields: list[tuple] = []
    for k, prop in enumerate(element.properties):
        if not prop.count_kind:
            fields.append((f"p{k}", _type(order, prop.kind)))
        else:
            fields += [
                (f"n{k}", _type(order, prop.count_kind)),
                (f"p{k}", _type(order, prop.kind), (lengths[prop],)),
            ]
    layout = np.dtype(fields)
    end = offset + element.count * layout.itemsize
    if end <= len(data):
        columns = _uniform_columns(element, np.frombuffer(data, layout, element.count, offset))
        if columns is not None:
            return columns, end
    if not lengths:  # (single numbers only, which the data does not hold)
        raise _truncated(header, element, (len(data) - offset) // layout.itemsize)
    return _varying_columns(data, element, order, _list_offsets(data, offset, element, header, element.count))


def _uniform_columns(element: PlyElement, rows: np.ndarray) -> Properties | None:
    """An element's properties, from a view of its bytes whose lists have the first
    element's lengths, or None unless every list has them."""
    columns: Properties = {}
    for k, prop in enumerate(element.properties):
        if not prop.count_kind:
            columns[prop.name] = rows[f"p{k}"]
            continue
        values = rows[f"p{k}"]
        if (rows[f"n{k}"] != values.shape[1]).any():
            return None
        columns[prop.name] = PlyList(np.full(len(rows), values.shape[1], np.int64), values.reshape(-1))
    return columns


def _list_offsets(
    data: bytes, offset: int, element: PlyElement, header: PlyHeader, rows: int
) -> dict[PlyProperty, np.ndarray]:
    """(rows,) int64 where the count of each list of the first ``rows`` elements is, found
    one element after the other, or ``ValueError`` for a file that ends before them or a
    list of fewer than 0 numbers."""
    # Each list: the bytes of single numbers before it (since the element's start or the
    # end of the list before), its count's type, and its numbers' size; then the bytes after.
    steps = []
    before = 0
    for prop in element.properties:
        size = np.dtype(PLY_TYPES[prop.kind]).itemsize
        if not prop.count_kind:
            before += size
        else:
            count = struct.Struct(header.byte_order + _STRUCT_CODES[PLY_TYPES[prop.count_kind]])
            steps.append((before, count, size))
            before = 0
    if not steps:
        return {}
    found: list[list[int]] = [[] for _ in steps]
    at = offset
    try:
        if len(steps) == 1:  # (one list, as a face has: a loop 4x faster than the other)
            ((lead, count, size),) = steps
            unpack, where, tail = count.unpack_from, found[0], count.size + before
            for row in range(rows):
                where.append(at + lead)
                (length,) = unpack(data, at + lead)
                if length < 0:
                    raise _negative(element, row, length)
                at += lead + length * size + tail
        else:
            for row in range(rows):
                for (lead, count, size), where in zip(steps, found, strict=True):
                    at += lead
                    where.append(at)
                    (length,) = count.unpack_from(data, at)
                    if length < 0:
                        raise _negative(element, row, length)
                    at += count.size + length * size
                at += before
    except struct.error:  # (a count beyond the data)
        at = len(data) + 1
    if at > len(data):
        # (Element r is whole where element r + 1 starts within the data.)
        starts = np.array(found[0], dtype=np.int64) - steps[0][0]
        raise _truncated(header, element, int((starts[1:] <= len(data)).sum()))
    lists = [prop for prop in element.properties if prop.count_kind]
    return {prop: np.array(where, dtype=np.int64) for prop, where in zip(lists, found, strict=True)}


def _negative(element: PlyElement, row: int, length: int) -> ValueError:
    """The error of a list of fewer than 0 numbers in element ``row``."""
    return ValueError(f"`{element.name}` {row + 1} of {element.count} has a list of {length} numbers")


def _varying_columns(
    data: bytes, element: PlyElement, order: str, list_offsets: dict[PlyProperty, np.ndarray]
) -> tuple[Properties, int]:
    """An element's properties, gathered from where its lists are (``_list_offsets``), and
    where it ends."""
    # Single numbers are found from where their run starts: the element's start (the first
    # list's offset less the numbers before it), or the end of the list before them.
    leading = element.properties[: next(k for k, p in enumerate(element.properties) if p.count_kind)]
    start = next(iter(list_offsets.values())) - sum(np.dtype(PLY_TYPES[p.kind]).itemsize for p in leading)
    run = 0
    columns: Properties = {}
    for prop in element.properties:
        kind = _type(order, prop.kind)
        if not prop.count_kind:
            columns[prop.name] = _at(data, start + run, kind)
            run += kind.itemsize
            continue
        count_kind = _type(order, prop.count_kind)
        first = list_offsets[prop] + count_kind.itemsize
        counts = _at(data, list_offsets[prop], count_kind).astype(np.int64)
        values = _at(data, np.repeat(first, counts) + _within(counts) * kind.itemsize, kind)
        columns[prop.name] = PlyList(counts, values)
        start, run = first + counts * kind.itemsize, 0
    return columns, int(start[-1]) + run


def _type(order: str, kind: str) -> np.dtype:
    """NumPy's type of PLY type ``kind`` in byte order ``order``."""
    return np.dtype(order + PLY_TYPES[kind])


def _at(data: bytes, at: np.ndarray, kind: np.dtype) -> np.ndarray:
    """(n,) the numbers of type ``kind`` at the (n,) byte offsets ``at`` of ``data``."""
    found = np.empty(len(at), kind)
    # (Through views of the bytes as ``kind`` from each offset modulo its size: no (n, size)
    # array of byte indices.)
    residue = at % kind.itemsize
    for r in range(kind.itemsize):
        where = residue == r
        if where.any():
            view = np.frombuffer(data, kind, (len(data) - r) // kind.itemsize, r)
            found[where] = view[at[where] // kind.itemsize]
    return found


def _none(prop: PlyProperty) -> np.ndarray | PlyList:
    """A property of no element."""
    return PlyList(np.zeros(0, np.int64), np.zeros(0)) if prop.count_kind else np.zeros(0)


def _within(counts: np.ndarray) -> np.ndarray:
    """(counts.sum(),) each number's place in its list: 0 to counts[i] - 1, for each i."""
    return np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)


# -- text data ---------------------------------------------------------------------------------


@dataclass
class _Text:
    """A text file's data: its bytes, where each word starts and each line ends, and the
    line number of its first line."""

    body: bytes
    word_starts: np.ndarray
    line_ends: np.ndarray
    first_line: int

    def line(self, word: int) -> int:
        """The line of the file that word ``word`` is on."""
        return self.first_line + int(np.searchsorted(self.line_ends, self.word_starts[word]))

    def word(self, word: int) -> str:
        """Word ``word``, as the file writes it (``_shown``)."""
        start = int(self.word_starts[word])
        found = re.match(rb"\S*", self.body[start : start + 40])
        return _shown(found.group() if found else b"")

    def cut(self, word: int) -> bool:
        """Whether the file ends in the middle of a line, the line of ``word`` (cut short)."""
        return not self.body.endswith(b"\n") and self.line(word) == self.line(len(self.word_starts) - 1)

    def numbers(self, words: range, integers: bool) -> np.ndarray:
        """The numbers that ``words`` (consecutive) write, int64 where ``integers`` and they
        are all integers, else float64; or ``ValueError`` naming the first that is not one."""
        if not len(words):
            return np.zeros(0)
        start = int(self.word_starts[words.start])
        end = int(self.word_starts[words.stop]) if words.stop < len(self.word_starts) else len(self.body)
        block = self.body[start:end]
        # (NumPy reads integers 8x faster than floats. A word that is not wholly a number stops
        # the reading with an error, so as many numbers as words are one number a word; an
        # integer beyond int64 is read as its largest, which is no vertex's index either.)
        for kind in (np.int64, np.float64) if integers else (np.float64,):
            with warnings.catch_warnings():
                warnings.simplefilter("error", DeprecationWarning)
                try:
                    values = np.fromstring(block, dtype=kind, sep=" ")
                except (ValueError, DeprecationWarning):
                    continue
            if len(values) == len(words):
                return values
        split = block.split()
        chunk = 4096  # (the word that is not a number is looked for chunk by chunk, then alone)
        for first in range(0, len(split), chunk):
            if not _are_numbers(split[first : first + chunk]):
                k = next(k for k in range(first, first + chunk) if not _are_numbers(split[k : k + 1]))
                word = words.start + k
                cut = "truncated: " if word == len(self.word_starts) - 1 and self.cut(word) else ""
                raise ValueError(f"{cut}line {self.line(word)}: `{self.word(word)}` is not a number")
        # (Where the two readings disagree, as on a word of NUL bytes, the stricter decides.)
        return np.array(split, dtype=np.float64)


def _text_elements(data: bytes, header: PlyHeader) -> PlyData:
    """Every element of a text file (``read_ply_elements``)."""
    body = data[header.data_start :]
    raw = np.frombuffer(body, np.uint8)
    blank = _BLANKS[raw]
    text = _Text(
        body,
        word_starts=np.flatnonzero(~blank & np.concatenate(([True], blank[:-1]))),
        line_ends=np.flatnonzero(raw == ord("\n")),
        first_line=header.lines + 1,
    )
    # Each line's first word and how many it has; blank lines left out.
    ends = np.append(np.searchsorted(text.word_starts, text.line_ends), len(text.word_starts))
    starts = np.concatenate(([0], ends[:-1]))
    held = np.flatnonzero(ends > starts)
    first, per_line, lines = starts[held], (ends - starts)[held], text.first_line + held
    # (An element without properties would be a blank line, which is not told from none.)
    announced = np.cumsum([0] + [element.count if element.properties else 0 for element in header.elements])
    if len(lines) < announced[-1]:
        short = int(np.searchsorted(announced, len(lines), side="right")) - 1
        raise _truncated(header, header.elements[short], len(lines) - int(announced[short]))
    if len(lines) > announced[-1]:
        raise ValueError(
            f"line {lines[announced[-1]]}: more data than its header announces ({header.announces()})"
        )
    ply = PlyData(header, {}, text)
    for element, start in zip(header.elements, announced[:-1], strict=True):
        rows = slice(start, start + (element.count if element.properties else 0))
        ply.elements[element.name] = _text_element(text, element, first[rows], per_line[rows])
        ply.lines[element.name] = lines[rows]
    return ply


def _text_element(text: _Text, element: PlyElement, first: np.ndarray, per_line: np.ndarray) -> Properties:
    """An element's properties, from its lines' words: (n,) the first of each, and how many."""
    words = range(int(first[0]), int(first[-1] + per_line[-1])) if len(first) else range(0)
    integers = all(
        PLY_TYPES[kind][0] != "f" for p in element.properties for kind in (p.kind, p.count_kind) if kind
    )
    values = text.numbers(words, integers)
    at = first - words.start  # (each line's next word, among the element's)
    end = at + per_line
    columns: Properties = {}

    def whole(label: str, kind: str, where: np.ndarray) -> np.ndarray:
        """The numbers of the element's words ``where``, or ``ValueError`` for one that is not
        a whole number where ``kind`` is an integer type (``label``: what the numbers are)."""
        found = values[where]
        if (
            found.dtype.kind == "f"
            and PLY_TYPES[kind][0] != "f"
            and (wrong := found != np.floor(found)).any()
        ):
            word = words.start + int(where[np.argmax(wrong)])
            raise ValueError(
                f"line {text.line(word)}: `{text.word(word)}` is not a whole number "
                f"({label} holds {kind} numbers)"
            )
        return found

    for prop in element.properties:
        if (at >= end).any():
            row = int(np.argmax(at >= end))
            raise _wrong_line(text, element, row, first, per_line, f"none for `{prop.name}`")
        if not prop.count_kind:
            columns[prop.name] = whole(f"`{prop.name}`", prop.kind, at)
            at = at + 1
            continue
        counts = whole(f"the count of `{prop.name}`", prop.count_kind, at)
        wrong = (counts < 0) | (counts > end - at - 1)
        if wrong.any():
            row = int(np.argmax(wrong))
            follow = f" and {end[row] - at[row] - 1} follow" if counts[row] >= 0 else ""
            why = f"its `{prop.name}` list announces {text.word(words.start + int(at[row]))} numbers{follow}"
            raise _wrong_line(text, element, row, first, per_line, why)
        counts = counts.astype(np.int64)
        listed = np.repeat(at + 1, counts) + _within(counts)
        columns[prop.name] = PlyList(counts, whole(f"`{prop.name}`", prop.kind, listed), listed + words.start)
        at = at + 1 + counts
    if (at < end).any():
        row = int(np.argmax(at < end))
        raise _wrong_line(
            text, element, row, first, per_line, f"its properties take {at[row] - first[row] + words.start}"
        )
    return columns


def _wrong_line(
    text: _Text, element: PlyElement, row: int, first: np.ndarray, per_line: np.ndarray, why: str
) -> ValueError:
    """The error of element ``row``'s line, which does not hold the numbers its properties
    take (``why``)."""
    word = int(first[row])
    properties = ", ".join(map(str, element.properties))
    return ValueError(
        f"{'truncated: ' if text.cut(word) else ''}line {text.line(word)}: `{element.name}` {row + 1} "
        f"of {element.count} has {per_line[row]} numbers, but {why} (properties: {properties})"
    )


def _are_numbers(words: list[bytes]) -> bool:
    """Whether every one of ``words`` is a number (NumPy's strict reading, without Python's
    1_000, which a PLY file does not write)."""
    try:
        np.array(words, dtype=np.float64)
    except ValueError:
        return False
    return not any(b"_" in word for word in words)


def _shown(word: bytes) -> str:
    """A word of a file, to quote in a message (printable, at most 30 characters)."""
    text = word.decode("ascii", errors="replace")
    return "".join(c if c.isprintable() else "?" for c in text[:30]) + ("..." if len(text) > 30 else "")
