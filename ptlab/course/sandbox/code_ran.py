"""What ran in the student's process, checked against the code the grader reads.

The second reading of ``ptlab.course.sandbox.readable``. While it serves the grader's requests,
the student's process records every code object that runs (``ptlab.course.sandbox.child.
CodeRecorder``) and the file of every module it loads from the student's folder, and each
reply carries the new ones: ``[file, first line, qualified name, code_digest, names]``
(``child.code_record``). ``CodeRan.check`` compares each with the grader's own
compilation of the file it names (compiling runs nothing):

* the submission's files (``child.SUBMISSION_FILE``), as handed in;
* ptlab's kit (``child.PTLAB_FILE``), the files of Python and of the allowed packages (at
  the same paths in the sandbox as here), and the modules frozen into Python;
* code the standard library writes from strings and compiles (``<string>``): a named
  tuple's ``__new__`` is written again from its field names and compared; a dataclass's
  methods (``__create_fn__.<locals>.__init__``) depend on the class, and are taken by
  their name: only code compiled from a string could forge that, and the reading of the
  text refuses every way to compile one.

A module loaded from the student's folder must be one of the files handed in (not one the
code wrote there while it ran, a shared library least of all).
"""

from __future__ import annotations

import _imp
import functools
import os
import stat
import types
from pathlib import Path

from ptlab.course.sandbox.child import PTLAB_FILE, SUBMISSION_FILE, code_digest
from ptlab.course.sandbox.intake import Taken
from ptlab.course.sandbox.readable import Unreadable
from ptlab.course.sandbox.sandbox import SYSTEM, package_folders, python_prefixes

#: The largest library file the grader reads to check what ran.
MAX_LIBRARY_FILE = 8 << 20
#: Code objects, and files they are from, that a check's process may report in all: a
#: chapter-7 render runs about 900 of them, from about 60 files (ptlab's kit, NumPy, Python's).
MAX_RECORDS = 20_000
MAX_FILES = 600
#: The first line and qualified name of the records of modules (not code objects).
MODULE_RECORD = (0, "<module file>")


class CodeRan:
    """The grader's side of the recording, for one process of the student's submission."""

    def __init__(self, taken: Taken, kit: Path, packages: tuple[str, ...]):
        self.places = _Places(taken, kit, packages)
        self.records = 0
        self.files: set[str] = set()

    def check(self, report) -> Unreadable | None:
        """Why the new records ``report`` (from a reply, as decoded: checked here) are not
        the grader's own code at the places they name, or None if they all are."""
        records = _records(report)
        self.records += len(records or ())
        self.files.update(record[0] for record in records or ())
        if records is None or self.records > MAX_RECORDS or len(self.files) > MAX_FILES:
            return Unreadable("unreadable.too_much", {})
        for file, line, qualname, digest, names in records:
            if not self.places.holds(file, line, qualname, digest, names):
                shown_place = f"{os.path.basename(file)[:80]}:{line}" if line else os.path.basename(file)[:80]
                return Unreadable("unreadable.not_the_text", {"code": qualname[:80], "where": shown_place})
        return None


def _records(report) -> list[tuple[str, int, str, str, list]] | None:
    """The report's records, or None if it is not the schema ``child.code_record`` sends."""
    if type(report) is not list:
        return None
    found = []
    for record in report:
        if not (
            type(record) is list
            and len(record) == 5
            and type(record[0]) is str
            and type(record[1]) is int
            and type(record[2]) is str
            and type(record[3]) is str
            and type(record[4]) is list
            and all(type(name) is str for name in record[4])
        ):
            return None
        found.append(tuple(record))
    return found


class _Places:
    """Where the grader reads the code the student's process names: the submission's files
    (``child.SUBMISSION_FILE``), the kit in ptlab's place (``child.PTLAB_FILE``), the files of
    Python and of the allowed packages, and the modules frozen into Python."""

    def __init__(self, taken: Taken, kit: Path, packages: tuple[str, ...]):
        self.taken, self.kit = taken, kit / "ptlab"
        roots = [*python_prefixes(), *SYSTEM, *package_folders(packages)]
        self.roots = tuple(os.path.realpath(root) + os.sep for root in roots)

    def holds(self, file: str, line: int, qualname: str, digest: str, names: list[str]) -> bool:
        """Whether the code recorded is the grader's own at that place (or, for a module's
        record, whether the module's file is a file of the submission or of the library)."""
        if (line, qualname) == MODULE_RECORD:
            return self._is_handed_in(file) or self._library_path(file) is not None
        if file == "<string>":
            return _written_by_python(qualname, digest, names)
        index = self.index(file)
        return index is not None and digest in index.get((line, qualname), ())

    def index(self, file: str) -> dict | None:
        if file.startswith("<frozen ") and file.endswith(">"):
            return _frozen_index(file[len("<frozen ") : -1])
        if file.startswith(SUBMISSION_FILE):
            source = self.taken.files.get(file[len(SUBMISSION_FILE) :])
            return _text_index(source) if source is not None else None
        library = self._library_path(file)
        return _library_index(library) if library is not None else None

    def _is_handed_in(self, file: str) -> bool:
        name = file[len(SUBMISSION_FILE) :] if file.startswith(SUBMISSION_FILE) else None
        return name is not None and name.endswith(".py") and name in self.taken.files

    def _library_path(self, file: str) -> str | None:
        """Where the grader reads a file of the kit or of the library, or None."""
        if file.startswith(PTLAB_FILE):
            inside = Path(file[len(PTLAB_FILE) :])
            return None if ".." in inside.parts or inside.is_absolute() else str(self.kit / inside)
        real = os.path.realpath(file) if os.path.isabs(file) else ""
        return real if real.startswith(self.roots) else None


def _written_by_python(qualname: str, digest: str, names: list[str]) -> bool:
    """Whether code compiled from a string is what the standard library writes: a
    dataclass's method, or a named tuple's ``__new__`` (written again from its fields)."""
    if qualname == "__create_fn__" or qualname.startswith("__create_fn__.<locals>."):
        return True
    if qualname not in ("<lambda>", "<module>") or not names or names[0] != "_cls":
        return False
    fields = tuple(names[1:])  # (the lambda's own names, or those of the lambda the expression holds)
    return all(f.isidentifier() for f in fields) and digest in _named_tuple_new(fields)


@functools.lru_cache(maxsize=256)
def _named_tuple_new(fields: tuple[str, ...]) -> tuple[str, ...]:
    """``code_digest`` of the expression that ``collections.namedtuple`` compiles for
    ``fields``, and of the ``__new__`` it makes (Python 3.11's ``collections/__init__.py``)."""
    arguments = ", ".join(fields) + ("," if len(fields) == 1 else "")
    try:
        code = compile(
            f"lambda _cls, {arguments}: _tuple_new(_cls, ({arguments}))",
            "<string>",
            "eval",
            dont_inherit=True,
        )
    except (SyntaxError, ValueError):
        return ()
    return (code_digest(code), *(code_digest(c) for c in code.co_consts if type(c) is types.CodeType))


def code_index(code: types.CodeType, into: dict | None = None) -> dict:
    """{(first line, qualified name): {code_digest}} of ``code`` and the code nested in it."""
    into = {} if into is None else into
    into.setdefault((code.co_firstlineno, code.co_qualname), set()).add(code_digest(code))
    for constant in code.co_consts:
        if type(constant) is types.CodeType:
            code_index(constant, into)
    return into


@functools.lru_cache(maxsize=16)
def _text_index(source: bytes) -> dict | None:
    """``code_index`` of a file's text, compiled as an import compiles it (nothing runs)."""
    try:
        return code_index(compile(source, "<graded>", "exec", dont_inherit=True, optimize=0))
    except (SyntaxError, ValueError, RecursionError, MemoryError, OverflowError):
        return None


@functools.lru_cache(maxsize=1024)
def _library_index(path: str) -> dict | None:
    """``code_index`` of a library file (a regular file, read without following a link at
    its end and without blocking), or None if there is none."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            return None
        with os.fdopen(descriptor, "rb", closefd=False) as data:
            source = data.read(MAX_LIBRARY_FILE + 1)
    except OSError:
        return None
    finally:
        os.close(descriptor)
    return _text_index.__wrapped__(source) if len(source) <= MAX_LIBRARY_FILE else None


#: The modules frozen into Python under another name than their code's file names.
FROZEN_AS = {
    "importlib._bootstrap": "_frozen_importlib",
    "importlib._bootstrap_external": "_frozen_importlib_external",
}


@functools.lru_cache(maxsize=64)
def _frozen_index(module: str) -> dict | None:
    """``code_index`` of a module frozen into Python (``posixpath``), as Python holds it."""
    module = FROZEN_AS.get(module, module)
    try:
        return code_index(_imp.get_frozen_object(module)) if _imp.is_frozen(module) else None
    except (ImportError, ValueError, TypeError):
        return None
