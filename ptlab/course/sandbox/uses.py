"""What a file the grader can read may use: the allowlist of the reading of its text.

``ptlab.course.sandbox.readable`` reads the code that runs when a submission is imported, and the
code a graded name reaches, node by node (``FileUses.problem``). A readable file computes
with what its text shows; it does not reach Python's machinery that makes code from data
or finds objects by a name built at run time, whatever the spelling. The list was drawn
from what right answers use (the exercise files, the library's answers, the test answers
of ``tests/exercises``, with ``readable/``). A readable file may use:

* **built-ins**, but not ``exec``, ``eval``, ``compile``, ``__import__``, ``breakpoint``,
  ``help``, ``__build_class__``, ``__builtins__``; ``getattr``, ``setattr`` and
  ``delattr`` only called, with a constant name that is no dunder (a module's attribute by
  a constant name is judged as that attribute); ``hasattr`` with a constant name (it hands
  back a bool); ``globals()``, ``locals()`` and ``vars()`` only read by iterating them
  (``for name in globals()``, ``len``, ``in``), never looked up, changed, stored or handed
  on; ``type(x)`` and ``x.__class__`` only compared, tested (``isinstance``) or asked their
  ``__name__``, never called or kept (``type(f)`` is ``types.FunctionType``), and never
  ``type`` with three arguments. A function's own variable of such a name (a parameter
  ``compile``, ``eval = material.eval``) is not the built-in;
* **dunder attributes and names** that name things or run the data model's own methods
  (``HARMLESS_DUNDERS``, ``DUNDER_NAMES``): ``super().__init__``, ``f.__name__``,
  ``__file__``, ``object.__setattr__(self, "albedo", value)``; not ``__globals__``,
  ``__code__``, ``__dict__``, ``__closure__``, ``__subclasses__``, ``__self__``,
  ``__builtins__``...; nor the attributes of frames, tracebacks, generators, code objects
  and cells, nor ``ctypes``, nor a trace function's (``INTERNALS``);
* **modules** of ``MODULES``: NumPy, SciPy, embreex and ptlab (the chapter's kit: not
  ``ptlab.course.sandbox``, whose modules in the kit are the grader's end), and the standard
  library's modules that compute (``math``, ``functools``, ``dataclasses``,
  ``concurrent.futures``...), with what each allows: of ``sys``, ``os``, ``types``,
  ``traceback`` a list of harmless attributes, of ``gc`` only ``collect`` and its kind (not
  the objects it finds); ``types.FunctionType`` and its kind only in
  type tests; ``importlib`` only for ``importlib.util.find_spec("name")`` tested against
  None (whether a package is installed); ``operator.attrgetter`` with constant names. Not
  ``marshal``, ``pickle``, ``importlib`` otherwise, ``runpy``, ``gc.get_objects``, ``inspect``,
  ``ctypes``, ``codecs``, ``subprocess``, ``builtins``, ``sys.modules``, ``sys.settrace``,
  ``threading.settrace``, nor a module's private names (``_x``). A use is resolved in the
  grader's own copy of the module, attribute by attribute, so that a module reached
  through another (``dataclasses.sys``, ``typing.types.FunctionType``) is judged as
  itself. A module with any such limit is used through its attributes only
  (``sys.float_info``), never handed on as a value (``xp = np``), whose attributes the
  text would no longer show. A module that is neither one of these, nor a file of the
  submission, nor of the standard library cannot be imported where the student's code
  runs, and is not judged (``try: import numba`` costs nothing).

A module of the standard library missing from the list is refused, even if it is
harmless: the list grows with what honest answers are seen to need, and its message names
the module.
"""

from __future__ import annotations

import ast
import functools
import importlib
import sys
import types
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeGuard

#: In ``MODULES``: every public attribute of the module is allowed.
ALL = None
#: In ``MODULES``: the module is not allowed (a part of one that is).
NOT_ALLOWED = False

#: What may only be a type test (``isinstance(f, types.FunctionType)``, an annotation):
#: called, these make functions and code from data.
TYPE_TESTS = frozenset(
    f"types.{name}"
    for name in (
        "AsyncGeneratorType",
        "BuiltinFunctionType",
        "BuiltinMethodType",
        "CellType",
        "ClassMethodDescriptorType",
        "CodeType",
        "CoroutineType",
        "FrameType",
        "FunctionType",
        "GeneratorType",
        "GetSetDescriptorType",
        "LambdaType",
        "MemberDescriptorType",
        "MethodDescriptorType",
        "MethodWrapperType",
        "ModuleType",
        "TracebackType",
        "WrapperDescriptorType",
    )
)
#: The modules a readable file may use, and which of their attributes: ``ALL``, a set, or
#: ``NOT_ALLOWED``. A module falls under its nearest listed parent (``numpy.linalg`` under
#: ``numpy``); one of the standard library that falls under none is not allowed.
MODULES: dict[str, frozenset[str] | bool | None] = {
    # What the exercises compute with.
    "numpy": ALL,
    "numpy.ctypeslib": NOT_ALLOWED,  # memory by address, and shared libraries loaded
    "numpy.distutils": NOT_ALLOWED,  # runs commands
    "numpy.f2py": NOT_ALLOWED,  # compiles and loads code
    "numpy.testing": NOT_ALLOWED,
    "scipy": ALL,
    "embreex": ALL,
    "ptlab": ALL,  # (the chapter's kit: its answers and the graders are not in it)
    "ptlab.course.sandbox": NOT_ALLOWED,  # the grader's end in the student's process
    # The standard library's modules that compute, and hold no way to code from data.
    **dict.fromkeys(
        (
            "__future__",
            "abc",
            "array",
            "base64",  # (data: what it decodes is bytes, which only what is refused makes code of)
            "bisect",
            "cmath",
            "collections",
            "colorsys",
            "concurrent",
            "contextlib",
            "copy",
            "csv",
            "dataclasses",
            "datetime",
            "decimal",
            "enum",
            "fnmatch",
            "fractions",
            "functools",
            "glob",
            "hashlib",
            "heapq",
            "io",
            "itertools",
            "json",
            "keyword",
            "logging",
            "math",
            "multiprocessing",
            "numbers",
            "operator",
            "pathlib",
            "posixpath",
            "pprint",
            "queue",
            "random",
            "re",
            "reprlib",
            "statistics",
            "string",
            "struct",
            "textwrap",
            "threading",
            "time",
            "typing",
            "warnings",
            "weakref",
            "zlib",
        ),
        ALL,
    ),
    "logging.config": NOT_ALLOWED,  # listen() runs what it is sent
    "multiprocessing.connection": NOT_ALLOWED,  # unpickles the bytes it is sent
    "multiprocessing.reduction": NOT_ALLOWED,
    "sys": frozenset(
        {
            "argv",
            "byteorder",
            "exc_info",
            "exception",
            "executable",
            "exit",
            "flags",
            "float_info",
            "float_repr_style",
            "getdefaultencoding",
            "getfilesystemencoding",
            "getrecursionlimit",
            "getsizeof",
            "hash_info",
            "implementation",
            "int_info",
            "maxsize",
            "maxunicode",
            "platform",
            "setrecursionlimit",
            "stderr",
            "stdin",
            "stdout",
            "thread_info",
            "version",
            "version_info",
        }
    ),
    "os": frozenset(
        {
            "PathLike",
            "cpu_count",
            "curdir",
            "devnull",
            "environ",
            "extsep",
            "fsdecode",
            "fsencode",
            "fspath",
            "get_terminal_size",
            "getcwd",
            "getenv",
            "getloadavg",
            "getpid",
            "getppid",
            "linesep",
            "listdir",
            "makedirs",
            "mkdir",
            "name",
            "pardir",
            "path",
            "pathsep",
            "process_cpu_count",
            "remove",
            "rename",
            "replace",
            "rmdir",
            "scandir",
            "sched_getaffinity",
            "sep",
            "stat",
            "times",
            "unlink",
            "urandom",
            "walk",
        }
    ),
    "types": frozenset(
        {
            "DynamicClassAttribute",
            "EllipsisType",
            "GenericAlias",
            "MappingProxyType",
            "MethodType",
            "NoneType",
            "NotImplementedType",
            "SimpleNamespace",
            "UnionType",
        }
    )
    | frozenset(name.rpartition(".")[2] for name in TYPE_TESTS),
    "traceback": frozenset(
        {
            "format_exc",
            "format_exception",
            "format_exception_only",
            "format_stack",
            "print_exc",
            "print_exception",
            "print_stack",
        }
    ),
    # Collecting garbage, yes; the objects it finds (get_objects, get_referrers), no.
    "gc": frozenset({"collect", "disable", "enable", "isenabled"}),
    "importlib": frozenset({"util"}),
    "importlib.util": frozenset({"find_spec"}),
}
#: Members of the modules above that a readable file may not use.
NOT_MEMBERS = frozenset(
    {
        "multiprocessing.Pipe",  # (a connection: see above)
        "string.Formatter",  # get_field: an object by a name built at run time
        "threading.getprofile",
        "threading.gettrace",
        "threading.setprofile",
        "threading.settrace",
        "typing.ForwardRef",  # (evaluates a string)
        "typing.get_type_hints",  # (evaluates strings)
    }
)
#: What may only tell whether a package is installed (``find_spec("numba") is not None``).
AVAILABILITY_TESTS = frozenset({"importlib.util.find_spec"})
#: What may only be called with constant names (that are no dunders).
CONSTANT_NAMES = frozenset({"operator.attrgetter", "operator.methodcaller"})

#: Built-ins that make code from data or reach objects by names built at run time.
CODE_BUILTINS = frozenset(
    {"exec", "eval", "compile", "__import__", "breakpoint", "help", "__build_class__", "__builtins__"}
)
#: Built-ins that reach an attribute by its name: called, with a constant name, only.
BY_NAME = frozenset({"getattr", "setattr", "delattr", "hasattr"})
#: The same, as methods (``object.__setattr__(self, "albedo", value)``).
BY_NAME_METHODS = frozenset({"__getattr__", "__getattribute__", "__setattr__", "__delattr__"})
#: Built-ins that hand out a namespace: read by iterating it, only.
NAMESPACES = frozenset({"globals", "locals", "vars"})
#: Dunder attributes that name things or run the data model's own methods of an object.
HARMLESS_DUNDERS = frozenset(
    {
        *("__init__", "__new__", "__post_init__", "__init_subclass__", "__class_getitem__"),
        *("__name__", "__qualname__", "__module__", "__doc__", "__file__", "__version__"),
        *("__wrapped__", "__all__", "__slots__", "__enter__", "__exit__", "__call__"),
        *("__iter__", "__next__", "__len__", "__contains__", "__getitem__", "__setitem__"),
        *("__delitem__", "__missing__", "__repr__", "__str__", "__format__", "__hash__"),
        *("__bool__", "__eq__", "__ne__", "__lt__", "__le__", "__gt__", "__ge__"),
        *("__float__", "__int__", "__index__", "__complex__", "__round__", "__copy__"),
        *("__deepcopy__", "__sizeof__", "__neg__", "__pos__", "__abs__", "__invert__"),
        *("__array__", "__array_ufunc__", "__array_function__", "__array_priority__"),
        *(
            f"__{prefix}{operation}__"
            for operation in (
                *("add", "sub", "mul", "matmul", "truediv", "floordiv", "mod", "pow"),
                *("and", "or", "xor", "lshift", "rshift", "divmod"),
            )
            for prefix in ("", "r", "i")
        ),
    }
)
#: Dunder names a file may read (``__name__`` of the module, ``__file__``).
DUNDER_NAMES = frozenset(
    {"__name__", "__file__", "__doc__", "__debug__", "__qualname__", "__module__", "__all__", "__version__"}
)
#: What the type of an object may be asked, as ``type(x).__name__``.
TYPE_NAMES = frozenset({"__name__", "__qualname__", "__module__"})
#: Attributes of frames, tracebacks, generators, code objects and cells (the way to another
#: function's globals and code, and to the student's process's own machinery), and of ctypes
#: (memory by address), whatever object they are asked of.
INTERNALS = frozenset(
    {
        *("f_back", "f_builtins", "f_code", "f_globals", "f_locals", "f_lasti", "f_lineno"),
        *("f_trace", "f_trace_lines", "f_trace_opcodes", "tb_frame", "tb_next", "tb_lasti"),
        *("gi_code", "gi_frame", "gi_yieldfrom", "cr_code", "cr_frame", "cr_await", "cr_origin"),
        *("ag_code", "ag_frame", "ag_await", "cell_contents", "co_code", "co_consts", "co_names"),
        *("co_varnames", "co_filename", "co_firstlineno", "co_qualname", "co_lnotab"),
        *("co_linetable", "co_exceptiontable", "co_freevars", "co_cellvars", "co_flags"),
        *("ctypes", "_ctypes", "ctypeslib", "pythonapi", "settrace", "setprofile", "gettrace"),
        *("getprofile", "_getframe", "_current_frames", "_current_exceptions"),
    }
)
#: Calls that hand their argument back as it was, or show it: a namespace read, or the
#: result of ``type(x)``, may go into them.
READERS = frozenset({"len", "list", "sorted", "tuple", "set", "print", "str", "repr", "format"})
#: The hint ``find_spec`` misused gets (a catalogue key of ``ptlab.course.messages``).
IMPORTLIB_HINT = "unreadable.hint.importlib"


@dataclass(frozen=True)
class Use:
    """What the grader finds at a dotted name of a library (``library_use``).

    Attributes:
        refused: the dotted name of the first module or attribute on the way that is not
            allowed, or None.
        condition: ``"type test"``, ``"availability test"``, ``"constant names"`` or None:
            the only way it may be used.
        closed: it is a module with a limit (``MODULES``), whose attributes the text must
            show: it may not be handed on as a value.
        name: the dotted name of what has a condition, where it is defined
            (``types.FunctionType`` for ``typing.types.FunctionType``).
    """

    refused: str | None = None
    condition: str | None = None
    closed: bool = False
    name: str = ""


@functools.lru_cache(maxsize=4096)
def library_use(dotted: str) -> Use:
    """What ``dotted`` (``numpy.linalg.norm``, ``dataclasses.sys.modules``) is, as the
    grader's own copy of the modules resolves it, attribute by attribute."""
    parts = dotted.split(".")
    if not importable_here(parts[0]):
        return Use()  # (nothing of it can be imported where the student's code runs)
    if not module_allowed(parts[0]):
        return Use(refused=parts[0])
    found = _import(parts[0])
    for attribute in parts[1:]:
        if found is None or _is_dunder(attribute):
            return Use()  # (nothing there, or a dunder, which the reading of the node judges)
        if not isinstance(found, types.ModuleType):
            break  # (an attribute of a class or a function: the reading of the node judges it)
        found = _member(found, attribute)
        if isinstance(found, Use):
            return found
    return Use() if found is None else _judged(found)


def _member(module: types.ModuleType, attribute: str):
    """``module.attribute`` if a readable file may use it, a ``Use`` that refuses it, or
    None if there is none (the file sets it, or its code fails where it runs)."""
    member = f"{module.__name__}.{attribute}"
    if (
        _policy(member) is NOT_ALLOWED
        or attribute.startswith("_")
        or not _member_allowed(module.__name__, attribute)
    ):
        return Use(refused=member)  # (a part listed as not allowed: ptlab.course.sandbox; a private name)
    inside = _attribute(module, attribute)
    if isinstance(inside, types.ModuleType) and not module_allowed(inside.__name__):
        return Use(refused=inside.__name__)
    return inside


def _judged(found) -> Use:
    """What the end of a dotted name may be used for: a module handed on if it is open,
    an object of the lists above only as they say."""
    if isinstance(found, types.ModuleType):
        return Use(closed=not _is_open(found.__name__))
    name = _conditions().get(id(found))
    if name in _FORBIDDEN_BY_IDENTITY:
        return Use(refused=name)
    for condition, names in (
        ("type test", TYPE_TESTS),
        ("availability test", AVAILABILITY_TESTS),
        ("constant names", CONSTANT_NAMES),
    ):
        if name in names:
            return Use(condition=condition, name=name)
    return Use()


def module_allowed(name: str) -> bool:
    """Whether the module ``name`` is one a readable file may use (``MODULES``)."""
    return _policy(name) is not NOT_ALLOWED


def star_names(module: str) -> list[str] | None:
    """The names ``from module import *`` binds (its ``__all__``, or its public names), as
    the grader's copy of it says; None if it is not a module a readable file may use."""
    if not (importable_here(module.split(".")[0]) and module_allowed(module)):
        return None
    found = _import(module)
    if not isinstance(found, types.ModuleType):
        return None
    names = getattr(found, "__all__", None)
    if not (isinstance(names, list | tuple) and all(isinstance(n, str) for n in names)):
        names = [name for name in vars(found) if not name.startswith("_")]
    return list(names)


def _is_dunder(name: str) -> bool:
    return len(name) > 4 and name.startswith("__") and name.endswith("__")


def _policy(name: str):
    """``MODULES``' entry for the module ``name``: its nearest listed parent's (or, for a
    module of the standard library under none, ``NOT_ALLOWED``)."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        prefix = ".".join(parts[:end])
        if prefix in MODULES:
            return MODULES[prefix]
    return NOT_ALLOWED


def _member_allowed(module: str, attribute: str) -> bool:
    if f"{module}.{attribute}" in NOT_MEMBERS:
        return False
    policy = _policy(module)
    return policy is ALL or (isinstance(policy, frozenset) and attribute in policy)


def importable_here(top: str) -> bool:
    """Whether a module named ``top`` can be imported where the student's code runs: one
    of the standard library, a package it may import, or ptlab (its kit)."""
    return top in sys.stdlib_module_names or top in sys.builtin_module_names or top in _listed_tops()


@functools.cache
def _listed_tops() -> frozenset[str]:
    return frozenset(name.split(".")[0] for name in MODULES)


@functools.lru_cache(maxsize=512)
def _import(name: str):
    """The grader's copy of the module ``name`` (only modules ``MODULES`` allows, which
    importing cannot harm, and no private one: ``ptlab.__main__`` would run), or None."""
    if not module_allowed(name) or any(part.startswith("_") for part in name.split(".")[1:]):
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return importlib.import_module(name)
    except Exception:  # (not installed here, or it fails to import: nothing to resolve)
        return None


def _attribute(module: types.ModuleType, attribute: str):
    """``module.attribute`` in the grader's copy: the attribute, or the submodule of that
    name (imported if it is allowed), or None."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (deprecated names warn: numpy.core)
            return getattr(module, attribute)
    except Exception:  # (a module's __getattr__ may raise anything)
        return _import(f"{module.__name__}.{attribute}")


@functools.cache
def _is_open(name: str) -> bool:
    """Whether the module ``name`` may be handed on as a value: it allows every public
    attribute, holds no part or member that is not allowed, and every module it holds may
    be handed on too."""
    if _policy(name) is not ALL or any(
        key.startswith(name + ".") and value is not ALL for key, value in MODULES.items()
    ):
        return False
    if any(member.startswith(name + ".") for member in NOT_MEMBERS | TYPE_TESTS | CONSTANT_NAMES):
        return False
    module = _import(name)
    if module is None:
        return False
    _opening.add(name)
    try:
        for attribute, value in list(vars(module).items()):
            if attribute.startswith("_") or not isinstance(value, types.ModuleType):
                continue
            if value.__name__ in _opening:
                continue
            if not (module_allowed(value.__name__) and _is_open(value.__name__)):
                return False
        return True
    finally:
        _opening.discard(name)


_opening: set[str] = set()


@functools.cache
def _conditions() -> dict[int, str]:
    """{id: dotted name} of the objects the lists above name, and of the code-making
    built-ins, to know them wherever a module hands them on (``typing.types.FunctionType``)."""
    import builtins

    found = {
        id(getattr(builtins, name)): name
        for name in CODE_BUILTINS | BY_NAME | NAMESPACES
        if hasattr(builtins, name)
    }
    for dotted in sorted(TYPE_TESTS | AVAILABILITY_TESTS | CONSTANT_NAMES | NOT_MEMBERS):
        module, _, name = dotted.rpartition(".")
        value = getattr(_import_anyway(module), name, None)
        if value is not None:
            found.setdefault(id(value), dotted)  # (the first name of one object: FunctionType)
    return found


#: Of ``_conditions``' names, those that are refused wherever they are met.
_FORBIDDEN_BY_IDENTITY = CODE_BUILTINS | BY_NAME | NAMESPACES | NOT_MEMBERS


def _import_anyway(name: str):
    """A module of the standard library the lists name (the grader's own copy)."""
    try:
        return importlib.import_module(name)
    except ImportError:
        return None


# -- the nodes of a file ----------------------------------------------------------------


class FileUses:
    """The reading of one file's nodes against the allowlist (see the module docstring).

    Args:
        tree: the file's syntax tree.
        aliases: {name in the file: dotted name it was imported as}.
        library_name: the dotted name an alias's use stands for in a library
            (``helpers.np.load`` is ``numpy.load`` when ``helpers`` is a file of the
            submission that imports numpy as np), or None if it is the submission's own.
    """

    def __init__(self, tree: ast.Module, aliases: dict[str, str], library_name: Callable[[str], str | None]):
        self.aliases, self.library_name = aliases, library_name
        self.parents: dict[int, ast.AST] = {
            id(child): node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)
        }
        self.local = function_locals(tree)

    def parent(self, node: ast.AST) -> ast.AST | None:
        return self.parents.get(id(node))

    def problem(self, node: ast.AST) -> str | None:
        """What ``node`` (itself, not its children) uses that a readable file may not, as
        the message names it, or None."""
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
            return self._name(node)
        if isinstance(node, ast.Attribute):
            return self._attribute(node)
        if isinstance(node, ast.Call):
            return _unpickles(node)
        if isinstance(node, ast.ImportFrom) and any(a.name == "*" for a in node.names) and node.level == 0:
            module = node.module or ""
            if (
                self.library_name(module) is not None
                and star_names(module) is None
                and importable_here(module.split(".")[0])
            ):
                return f"from {module} import *"
        return None

    # -- names -------------------------------------------------------------------------

    def _name(self, node: ast.Name) -> str | None:
        name = node.id
        if id(node) in self.local:
            return None  # (a variable of a function: not the built-in, nor the import)
        if name in self.aliases:
            return self._library(node, self.aliases[name]) if self._chain_top(node) is node else None
        if name in CODE_BUILTINS:
            return name
        if name in BY_NAME:
            return self._by_name(node)
        if name in NAMESPACES:
            call = self._called(node)
            return None if call is not None and self._read_only(call) else f"{name}()"
        if name == "type":
            return self._type(node)
        if name == "__class__":
            return None if self._type_result_ok(node) else "__class__"
        if _is_dunder(name) and name not in DUNDER_NAMES:
            return name
        return None

    def _attribute(self, node: ast.Attribute) -> str | None:
        attribute = node.attr
        if attribute in INTERNALS:
            return f".{attribute}"
        if _is_dunder(attribute) and not self._dunder_ok(node):
            return f".{attribute}"
        if self._chain_top(node) is not node:
            return None
        dotted = self._dotted(node)
        return self._library(node, dotted) if dotted is not None else None

    def _dunder_ok(self, node: ast.Attribute) -> bool:
        if node.attr in HARMLESS_DUNDERS:
            return True
        if node.attr == "__class__":
            return self._type_result_ok(node)
        if node.attr in BY_NAME_METHODS:
            call = self._called(node)
            return call is not None and _constant_name_among(call.args[:2])
        return False

    def _library(self, node: ast.AST, dotted: str) -> str | None:
        """Whether the use ``node`` of the library's ``dotted`` is allowed (see ``Use``)."""
        library = self.library_name(dotted)
        if library is None:
            return None
        use = library_use(library)
        if use.refused is not None:
            return use.refused
        if use.closed:  # (``node`` ends the chain: the module itself is the value)
            return f"{dotted} as a value"
        ok = {
            None: True,
            "type test": self._in_type_test(node),
            "availability test": self._availability_test(node),
            "constant names": self._constant_names(node),
        }[use.condition]
        return None if ok else use.name

    def _by_name(self, node: ast.Name) -> str | None:
        """``getattr`` and its kind: called, with a constant name that is no dunder; a
        module's attribute so reached is judged as that attribute. (``hasattr`` hands back
        a bool, whatever the constant name.)"""
        call = self._called(node)
        if call is None or len(call.args) < 2 or any(isinstance(a, ast.Starred) for a in call.args):
            return node.id
        target, name = call.args[0], call.args[1]
        if not (isinstance(name, ast.Constant) and isinstance(name.value, str)):
            return f"{node.id}() with a name built at run time"
        if node.id == "hasattr":
            return None
        if _is_dunder(name.value) or name.value in INTERNALS:
            return f"{node.id}(..., {name.value!r})"
        dotted = self._dotted(target)
        return self._library(call, f"{dotted}.{name.value}") if dotted is not None else None

    def _type(self, node: ast.Name) -> str | None:
        call = self._called(node)
        if call is None:
            parent = self.parent(node)
            in_class = isinstance(parent, ast.keyword | ast.ClassDef)
            return None if in_class or self._in_type_test(node) else "type"
        if len(call.args) == 1 and not call.keywords and self._type_result_ok(call):
            return None
        return "type(name, bases, namespace)" if len(call.args) == 3 else "type(...)"

    # -- where a node is ---------------------------------------------------------------

    def _called(self, node: ast.AST) -> ast.Call | None:
        parent = self.parent(node)
        return parent if isinstance(parent, ast.Call) and parent.func is node else None

    def _chain_top(self, node: ast.AST) -> ast.AST:
        """The outermost attribute of the chain ``node`` begins (``a.b.c`` for ``a``)."""
        parent = self.parent(node)
        while isinstance(parent, ast.Attribute) and parent.value is node:
            node, parent = parent, self.parent(parent)
        return node

    def _dotted(self, node: ast.AST) -> str | None:
        """The dotted name an expression like ``np.linalg.norm`` stands for, through the
        file's imports (its base a name imported, not a variable of a function)."""
        attributes = []
        while isinstance(node, ast.Attribute):
            attributes.append(node.attr)
            node = node.value
        if not isinstance(node, ast.Name) or node.id not in self.aliases or id(node) in self.local:
            return None
        return ".".join([self.aliases[node.id], *reversed(attributes)])

    def _is_builtin_call(self, node: ast.AST | None, names) -> TypeGuard[ast.Call]:
        return (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in names
            and id(node.func) not in self.local
        )

    def _in_type_test(self, node: ast.AST) -> bool:
        """Whether ``node`` is a class tested against: the second argument of ``isinstance``
        or ``issubclass`` (alone, in a tuple, in ``A | B``), a side of a comparison, or in an
        annotation."""
        child, parent = node, self.parent(node)
        while isinstance(parent, ast.Tuple) or (
            isinstance(parent, ast.BinOp) and isinstance(parent.op, ast.BitOr)
        ):
            child, parent = parent, self.parent(parent)
        if self._is_builtin_call(parent, ("isinstance", "issubclass")):
            return len(parent.args) == 2 and parent.args[1] is child
        if isinstance(parent, ast.Compare | ast.MatchClass):
            return True
        return self._in_annotation(node)

    def _in_annotation(self, node: ast.AST) -> bool:
        child, parent = node, self.parent(node)
        while isinstance(parent, ast.expr):
            child, parent = parent, self.parent(parent)
        if isinstance(parent, ast.arg | ast.AnnAssign):
            return parent.annotation is child
        return isinstance(parent, ast.FunctionDef | ast.AsyncFunctionDef) and parent.returns is child

    def _type_result_ok(self, node: ast.AST) -> bool:
        """Whether ``type(x)`` or ``x.__class__`` at ``node`` is only compared, tested or
        named (never called, kept or handed on: ``type(f)`` is ``types.FunctionType``)."""
        parent = self.parent(node)
        if isinstance(parent, ast.Compare | ast.FormattedValue):
            return True
        if isinstance(parent, ast.Attribute) and parent.value is node:
            return parent.attr in TYPE_NAMES
        if self._is_builtin_call(parent, ("isinstance", "issubclass", "id", "hash", *READERS)):
            return node in parent.args
        return self._in_type_test(node)

    def _read_only(self, call: ast.Call) -> bool:
        """Whether the namespace ``call`` (``globals()``) hands out is only iterated: in a
        ``for``, a comprehension, ``in``, ``len``, ``sorted``..., or its ``items()``,
        ``keys()`` or ``values()`` so."""
        parent = self.parent(call)
        if isinstance(parent, ast.Attribute) and parent.attr in ("items", "keys", "values"):
            outer = self._called(parent)
            return outer is not None and not outer.args and self._iterated(outer)
        if isinstance(parent, ast.Compare):
            return call in parent.comparators and all(isinstance(op, ast.In | ast.NotIn) for op in parent.ops)
        return self._iterated(call)

    def _iterated(self, node: ast.AST) -> bool:
        parent = self.parent(node)
        if isinstance(parent, ast.For | ast.AsyncFor | ast.comprehension):
            return parent.iter is node
        return self._is_builtin_call(parent, READERS) and node in parent.args

    def _availability_test(self, node: ast.AST) -> bool:
        """Whether ``node`` (``find_spec``) is called on a constant name and the result only
        tested: ``find_spec("numba") is not None``, ``if find_spec("numba"):``."""
        call = self._called(node)
        if call is None or call.keywords or len(call.args) != 1 or _text(call.args[0]) is None:
            return False
        parent = self.parent(call)
        if isinstance(parent, ast.Compare):
            sides = [parent.left, *parent.comparators]
            others = [side for side in sides if side is not call]
            return (
                len(sides) == 2
                and isinstance(parent.ops[0], ast.Is | ast.IsNot | ast.Eq | ast.NotEq)
                and isinstance(others[0], ast.Constant)
                and others[0].value is None
            )
        if isinstance(parent, ast.If | ast.While | ast.IfExp | ast.Assert):
            return parent.test is call
        if isinstance(parent, ast.BoolOp) or (
            isinstance(parent, ast.UnaryOp) and isinstance(parent.op, ast.Not)
        ):
            return True
        return self._is_builtin_call(parent, ("bool",))

    def _constant_names(self, node: ast.AST) -> bool:
        call = self._called(node)
        if call is None or not call.args or call.keywords:
            return False
        name = _text(call.args[0])
        return (
            name is not None
            and not any(_is_dunder(p) for p in name.split("."))
            and all(not isinstance(a, ast.Starred) for a in call.args)
        )


def _text(node: ast.AST) -> str | None:
    """The string ``node`` is a constant of, or None."""
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


def _constant_name_among(arguments: list[ast.expr]) -> bool:
    """Whether the name in ``object.__setattr__(self, "name", v)`` (or a bound method's
    ``("name", v)``) is a constant that is no dunder."""
    texts = [text for text in map(_text, arguments) if text is not None]
    return bool(texts) and not any(_is_dunder(text) or text in INTERNALS for text in texts)


def _unpickles(call: ast.Call) -> str | None:
    """``numpy.load`` and ``read_array`` with ``allow_pickle`` not False: a pickle in an
    ``.npy`` file runs code when it is loaded."""
    function = call.func
    name = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", "")
    if name not in ("load", "read_array"):
        return None
    for keyword in call.keywords:
        if keyword.arg == "allow_pickle" and not (
            isinstance(keyword.value, ast.Constant) and keyword.value.value is False
        ):
            return "allow_pickle"
        if keyword.arg is None:  # (**options: allow_pickle may be among them)
            return "allow_pickle"
    return None


# -- which names are a function's variables ----------------------------------------------

FunctionNode = ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
Comprehension = ast.ListComp | ast.SetComp | ast.DictComp | ast.GeneratorExp


def function_locals(tree: ast.AST) -> set[int]:
    """The ids of the ``Name`` nodes that read a variable of a function (its own, or an
    enclosing function's): not a module's global or a built-in. (Names bound in a class's
    body are not: Python looks them up in the globals and built-ins too.)"""
    found: set[int] = set()
    todo: list[tuple[ast.AST, frozenset[str]]] = [(tree, frozenset())]
    while todo:
        node, bound = todo.pop()
        if isinstance(node, ast.Name):
            if isinstance(node.ctx, ast.Load) and node.id in bound:
                found.add(id(node))
            continue
        if isinstance(node, FunctionNode):
            outside = [*node.args.defaults, *(d for d in node.args.kw_defaults if d is not None)]
            if not isinstance(node, ast.Lambda):
                outside += [*node.decorator_list, *annotations_of(node)]
            todo += [(part, bound) for part in outside]
            inner = bound | _variables_of(node)
            todo += [(part, inner) for part in (node.body if isinstance(node.body, list) else [node.body])]
            continue
        if isinstance(node, Comprehension):
            inner = bound | {
                n.id for g in node.generators for n in ast.walk(g.target) if isinstance(n, ast.Name)
            }
            todo += [(child, inner) for child in ast.iter_child_nodes(node)]
            continue
        todo += [(child, bound) for child in ast.iter_child_nodes(node)]
    return found


def annotations_of(function: ast.FunctionDef | ast.AsyncFunctionDef) -> list[ast.expr]:
    arguments = function.args
    every = [
        *arguments.posonlyargs,
        *arguments.args,
        *arguments.kwonlyargs,
        arguments.vararg,
        arguments.kwarg,
    ]
    found = [a.annotation for a in every if a is not None and a.annotation is not None]
    return found + ([function.returns] if function.returns is not None else [])


def _variables_of(function: FunctionNode) -> frozenset[str]:
    """The names a function binds in its own scope: its parameters, and what its body
    assigns or defines (not in the functions, classes and comprehensions it holds, and not
    what it declares global). What it imports is not: a name imported is the module's,
    wherever it is imported (``FileUses`` follows it)."""
    arguments = function.args
    names = {
        a.arg
        for a in (
            *arguments.posonlyargs,
            *arguments.args,
            *arguments.kwonlyargs,
            arguments.vararg,
            arguments.kwarg,
        )
        if a is not None
    }
    if isinstance(function, ast.Lambda):
        return frozenset(names)
    declared_global: set[str] = set()
    todo: list[ast.AST] = list(function.body)
    while todo:
        node = todo.pop()
        if isinstance(node, ast.Global):
            declared_global.update(node.names)
        elif isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
            names.add(node.id)
        elif isinstance(node, ast.ExceptHandler | ast.MatchAs | ast.MatchStar) and node.name:
            names.add(node.name)
        elif isinstance(node, ast.MatchMapping) and node.rest:
            names.add(node.rest)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            names.add(node.name)
            todo += [*node.decorator_list, *getattr(node, "bases", []), *getattr(node, "keywords", [])]
            if not isinstance(node, ast.ClassDef):
                todo += [*node.args.defaults, *(d for d in node.args.kw_defaults if d is not None)]
            continue
        if isinstance(node, ast.Lambda | Comprehension):
            if isinstance(node, Comprehension):  # (a walrus in it binds in the function)
                names.update(
                    n.target.id
                    for n in ast.walk(node)
                    if isinstance(n, ast.NamedExpr) and isinstance(n.target, ast.Name)
                )
            continue
        todo += ast.iter_child_nodes(node)
    return frozenset(names - declared_global)
