"""What the student's process may send back to the grader: plain data, and names for the rest.

The grader never unpickles anything the student's process sends: unpickling runs code of
the sender's choosing. Replies are JSON, with arrays as ``.npy`` parts beside it, and the
grader decodes only this fixed schema (``Decoder``):

    null, true, false, numbers, strings                 themselves
    {"list": [...]}, {"tuple": [...]}, {"set": [...]}   containers
    {"dict": [[key, value], ...]}
    {"array": k}                                        the k-th .npy part: numbers only
    {"scalar": [dtype, value]}                          a NumPy scalar (numbers only)
    {"record": "Paths", "fields": {...}}                one of ``RECORDS``, rebuilt field by field
    {"function": h, "name", "kind", "origin", "parameters"}   a function or class (a dataclass
    {"object": h, "type": name}                         too) left in the child, or any other
                                                        object (one of a dataclass too): handle h

The ``.npy`` header is read with NumPy's own parser and the data viewed in place; an array
of Python objects, strings or records is refused. Anything else, or anything deeper than
``MAX_DEPTH``, is a ``MalformedError`` reply. ``Encoder`` is the child's side of the same schema.
"""

from __future__ import annotations

import functools
import io
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import fields, is_dataclass
from itertools import islice

import numpy as np

from ptlab.accel.base import Hits
from ptlab.integrators.path import PathSettings
from ptlab.integrators.wavefront import Paths, SurfaceHit
from ptlab.lights import ShapeSample
from ptlab.rendering.jobs import Job, JobResult, Tile

#: The library's own dataclasses that cross as records (rebuilt by name, field by field).
RECORDS = {
    cls.__name__: cls for cls in (Hits, Paths, PathSettings, SurfaceHit, ShapeSample, Tile, Job, JobResult)
}
#: The array element kinds that cross: bool, signed and unsigned integers, floats, complex.
ARRAY_KINDS = "biufc"
MAX_DEPTH = 40
#: Items taken from an iterator (a generator a function returned), at most.
MAX_ITEMS = 1_000_000
CALLABLE_KINDS = ("function", "method", "class")


def frozen(record: object) -> bool:
    """Whether the object ``record`` of a dataclass is frozen (its fields keep their values)."""
    # (Every dataclass has __dataclass_params__; typeshed's DataclassInstance leaves it out.)
    return type(record).__dataclass_params__.frozen  # type: ignore[attr-defined]


class MalformedError(Exception):
    """A reply that is not in the schema."""


class UnsendableError(Exception):
    """A value the student's code returned that the schema cannot carry (in the child)."""


# -- the child's side -------------------------------------------------------------------


class Encoder:
    """Turns values into the schema; arrays become ``.npy`` parts in ``self.parts``.

    Args:
        keep: stores an object in the child's table and returns its handle.
        describe: the ``name``, ``kind``, ``origin`` and ``parameters`` of a callable.
    """

    def __init__(self, keep: Callable[[object], int], describe: Callable[[object], dict]):
        self.keep, self.describe = keep, describe
        self.parts: list[tuple[bytes, memoryview]] = []

    def encode(self, value, depth: int = 0):
        if depth > MAX_DEPTH:
            raise UnsendableError(f"data nested more than {MAX_DEPTH} levels deep")
        kind = type(value)
        if value is None or kind in (bool, str):
            return value
        if isinstance(value, np.generic):
            return self._scalar(value)
        if kind in (int, float):
            return value
        if isinstance(value, np.ndarray):
            return {"array": self._array(value)}
        if kind.__name__ in RECORDS and kind is RECORDS[kind.__name__]:
            return {
                "record": kind.__name__,
                "fields": {
                    f.name: self.encode(getattr(value, f.name), depth + 1) for f in fields(value) if f.init
                },
            }
        if isinstance(value, dict):
            return {
                "dict": [[self.encode(k, depth + 1), self.encode(v, depth + 1)] for k, v in value.items()]
            }
        for container, tag in ((tuple, "tuple"), (list, "list"), (set | frozenset, "set")):
            if isinstance(value, container):
                return {tag: [self.encode(item, depth + 1) for item in value]}
        if isinstance(value, Iterator):
            return {"list": [self.encode(item, depth + 1) for item in _items_of(value)]}
        if callable(value) and (isinstance(value, type) or not is_dataclass(value)):
            # (a class, dataclass or not, is called to make objects; an object of a dataclass
            # with a __call__ stays an object, whose fields the grader reads)
            return dict(function=self.keep(value), **self.describe(value))
        return {"object": self.keep(value), "type": kind.__name__}

    def _scalar(self, value: np.generic) -> dict:
        dtype = value.dtype
        if dtype.kind not in ARRAY_KINDS:
            raise UnsendableError(f"a NumPy scalar of type {dtype}")
        item = value.item()
        return {"scalar": [dtype.str, [item.real, item.imag] if dtype.kind == "c" else item]}

    def _array(self, value: np.ndarray) -> int:
        array = np.asarray(value)
        if array.dtype.kind not in ARRAY_KINDS or array.dtype.fields is not None:
            raise UnsendableError(f"an array of {array.dtype} (the grader reads arrays of numbers)")
        self.parts.append(npy_part(array))
        return len(self.parts) - 1


def _items_of(iterator: Iterator) -> list:
    """The items of an iterator (sent as a list), at most ``MAX_ITEMS`` of them."""
    items = list(islice(iterator, MAX_ITEMS + 1))
    if len(items) > MAX_ITEMS:
        raise UnsendableError(f"an iterator of more than {MAX_ITEMS:,} items")
    return items


def npy_part(array: np.ndarray) -> tuple[bytes, memoryview]:
    """An array as an ``.npy`` file (format 1.0, as ``numpy.save`` writes it): its header,
    and its data viewed in place (no copy unless the array is neither C- nor F-ordered)."""
    fortran = bool(array.flags.f_contiguous and not array.flags.c_contiguous)
    if not (array.flags.c_contiguous or fortran):
        array = np.ascontiguousarray(array)
    # (``.data`` is the array's memoryview: NumPy's stubs type memoryview(array) on Python 3.12 on.)
    data = array.reshape(-1, order="F" if fortran else "C").data.cast("B")
    return _npy_header(array.dtype, array.shape, fortran), data


@functools.lru_cache(maxsize=256)
def _npy_header(dtype: np.dtype, shape: tuple, fortran: bool) -> bytes:
    header = (
        f"{{'descr': {np.lib.format.dtype_to_descr(dtype)!r}, "
        f"'fortran_order': {fortran}, 'shape': {shape!r}, }}"
    ).encode("latin1")
    padding = -(len(NPY_MAGIC) + 2 + len(header) + 1) % 64  # numpy aligns data to 64 bytes
    header += b" " * padding + b"\n"
    return NPY_MAGIC + len(header).to_bytes(2, "little") + header


# -- the grader's side -------------------------------------------------------------------


def read_array(part: bytearray) -> np.ndarray:
    """The array in one ``.npy`` part, viewed in place; ``MalformedError`` unless it is a plain
    array of numbers whose data is exactly as long as its header says."""
    shape, fortran_order, dtype, offset = _read_header(part)
    if dtype.kind not in ARRAY_KINDS or dtype.fields is not None or dtype.subdtype is not None:
        raise MalformedError(f"an array of {dtype}")
    count = math.prod(shape)
    if count * dtype.itemsize != len(part) - offset:
        raise MalformedError(f"an array of shape {shape} with {len(part) - offset} bytes of data")
    if count == 0:
        return np.empty(shape, dtype)
    flat = np.frombuffer(part, dtype=dtype, count=count, offset=offset)
    return flat.reshape(shape, order="F" if fortran_order else "C")


NPY_MAGIC = b"\x93NUMPY\x01\x00"
#: The header ``numpy.save`` writes for an array of a simple type (format 1.0): parsed
#: directly, 100x faster than numpy's general parser, which takes every other header.
_SIMPLE_HEADER = re.compile(
    rb"\{'descr': '([<>|=][a-z]\d+)', 'fortran_order': (True|False), "
    rb"'shape': \(((?:\d+, )*\d+,?)?\), \} *\n"
)


def _read_header(part: bytearray) -> tuple[tuple, bool, np.dtype, int]:
    """(shape, fortran_order, dtype, data offset) from an ``.npy`` part's header."""
    if bytes(part[: len(NPY_MAGIC)]) == NPY_MAGIC and len(part) >= 10:
        end = 10 + int.from_bytes(bytes(part[8:10]), "little")
        simple = _simple_header(bytes(part[10:end]))
        if simple is not None:
            return *simple, end
    stream = io.BytesIO(bytes(part[:65536]))
    try:
        version = np.lib.format.read_magic(stream)
        read_header = {
            (1, 0): np.lib.format.read_array_header_1_0,
            (2, 0): np.lib.format.read_array_header_2_0,
        }.get(version)
        if read_header is None:
            raise MalformedError(f"an .npy part of version {version}")
        shape, fortran_order, dtype = read_header(stream)
    except MalformedError:
        raise
    except Exception as error:  # numpy's parser refusing the header, in whatever way
        raise MalformedError(f"an .npy part with a bad header ({error})") from None
    return shape, fortran_order, dtype, stream.tell()


@functools.lru_cache(maxsize=256)
def _simple_header(header: bytes) -> tuple[tuple, bool, np.dtype] | None:
    """(shape, fortran_order, dtype) of a header as ``numpy.save`` writes it, else None."""
    match = _SIMPLE_HEADER.fullmatch(header)
    if not match:
        return None
    descr, fortran, shape = match.groups()
    try:
        dtype = np.dtype(descr.decode("ascii"))
    except TypeError:
        raise MalformedError(f"an array of type {descr!r}") from None
    return tuple(int(n) for n in (shape or b"").split(b",") if n.strip()), fortran == b"True", dtype


def clean_text(text: str) -> str:
    """``text`` with lone surrogates (which cannot be printed) replaced."""
    return text.encode("utf-8", "replace").decode("utf-8")


class Decoder:
    """Rebuilds values from the schema; proxies for handles come from ``remote(tag)``."""

    def __init__(self, arrays: list[bytearray], remote: Callable[[dict], object]):
        self.arrays, self.remote = arrays, remote

    def decode(self, tree, depth: int = 0):
        if depth > MAX_DEPTH:
            raise MalformedError(f"data nested more than {MAX_DEPTH} levels deep")
        if tree is None or type(tree) in (bool, int, float):
            return tree
        if type(tree) is str:
            return clean_text(tree)
        if type(tree) is not dict or len(tree) == 0:
            raise MalformedError(f"a value of JSON type {type(tree).__name__}")
        tag = next(iter(tree))
        body = tree[tag]
        if tag in ("list", "tuple", "set", "dict") and len(tree) == 1:
            return self._collection(tag, body, depth)
        if tag == "array" and len(tree) == 1:
            if type(body) is not int or not 0 <= body < len(self.arrays):
                raise MalformedError(f"a reference to array part {body!r}")
            return read_array(self.arrays[body])
        if tag == "scalar" and len(tree) == 1:
            return self._scalar(body)
        if tag == "record" and set(tree) == {"record", "fields"}:
            return self._record(body, tree["fields"], depth)
        if tag == "function" and set(tree) == {"function", "name", "kind", "origin", "parameters"}:
            return self.remote(self._callable_tag(tree))
        if tag == "object" and set(tree) == {"object", "type"}:
            return self.remote(self._object_tag(body, tree["type"]))
        raise MalformedError(f"an unknown tag {tag!r}")

    @staticmethod
    def _object_tag(handle, type_name) -> dict:
        """An object's tag (its handle in the other process and its type's name), checked."""
        if type(handle) is not int or type(type_name) is not str:
            raise MalformedError("an object tag without a handle and a type name")
        return {"object": handle, "type": clean_text(type_name)}

    def _collection(self, tag: str, body, depth: int):
        """A list, tuple, set or dict (a list of [key, value] pairs) of decoded items."""
        if tag == "dict":
            pairs = [self._list(pair) for pair in self._list(body)]
            if any(len(pair) != 2 for pair in pairs):
                raise MalformedError("a dict entry that is not a [key, value] pair")
            try:
                return {self.decode(k, depth + 1): self.decode(v, depth + 1) for k, v in pairs}
            except TypeError:
                raise MalformedError("a dict with an unhashable key") from None
        items = [self.decode(item, depth + 1) for item in self._list(body)]
        try:
            return {"list": list, "tuple": tuple, "set": set}[tag](items)
        except TypeError:
            raise MalformedError("a set of unhashable items") from None

    @staticmethod
    def _list(value) -> list:
        if type(value) is not list:
            raise MalformedError(f"a {type(value).__name__} where a list belongs")
        return value

    @staticmethod
    def _scalar(body) -> np.generic:
        if type(body) is not list or len(body) != 2 or type(body[0]) is not str:
            raise MalformedError("a scalar that is not [dtype, value]")
        try:
            dtype = np.dtype(body[0])
        except Exception:  # numpy refusing the type string
            raise MalformedError(f"a scalar of type {body[0]!r}") from None
        if dtype.kind not in ARRAY_KINDS or dtype.fields is not None or dtype.subdtype is not None:
            raise MalformedError(f"a scalar of type {dtype}")
        value = body[1]
        if dtype.kind == "c":
            if type(value) is not list or len(value) != 2 or not all(type(v) in (int, float) for v in value):
                raise MalformedError("a complex scalar that is not [real, imag]")
            value = complex(*value)
        elif type(value) not in ((bool,) if dtype.kind == "b" else (bool, int, float)):
            raise MalformedError(f"a {dtype} scalar holding {type(value).__name__}")
        try:
            return dtype.type(value)
        except (OverflowError, ValueError, TypeError):
            raise MalformedError(f"the value {value!r} for a {dtype} scalar") from None

    def _record(self, name, body, depth: int):
        cls = RECORDS.get(name) if type(name) is str else None
        if cls is None:
            raise MalformedError(f"a record of type {name!r}")
        expected = {f.name for f in fields(cls) if f.init}
        if type(body) is not dict or set(body) != expected:
            raise MalformedError(f"a {name} record without exactly its fields")
        return cls(**{key: self.decode(value, depth + 1) for key, value in body.items()})

    @staticmethod
    def _callable_tag(tree: dict) -> dict:
        name, kind, origin, parameters = (tree[k] for k in ("name", "kind", "origin", "parameters"))
        if (
            type(tree["function"]) is not int
            or type(name) is not str
            or kind not in CALLABLE_KINDS
            or not (origin is None or type(origin) is str)
        ):
            raise MalformedError("a function tag with a bad field")
        if parameters is not None:
            if type(parameters) is not list or not all(
                type(p) is list and len(p) == 2 and type(p[0]) is str and type(p[1]) is int
                for p in parameters
            ):
                raise MalformedError("a function tag with bad parameters")
            parameters = [(clean_text(p[0]), p[1]) for p in parameters]
        return {
            "function": tree["function"],
            "name": clean_text(name),
            "kind": kind,
            "origin": None if origin is None else clean_text(origin),
            "parameters": parameters,
        }
