"""A chapter's kit: ptlab as the student's process sees it, without the chapter's answers.

The student's process (``ptlab.course.sandbox.sandbox``) sees no ptlab but its kit. A kit is a
copy of the renderer's source in which every definition the chapter leaves out is a stub:
the function keeps its name and parameters (so the modules that import it still import,
and the grader's objects still unpickle), and its body only raises ``NotInKitError``. A
class left out keeps its name and its fields, and each of its methods is such a stub; a
module left out has all its functions and methods stubbed. What a chapter leaves out is
its answer and everything that computes the same thing another way (chapter 6 leaves out
``Diffuse``, the microfacet material, which is a diffuse one with ``ks = 0``, and the
hemisphere warps; ``ptlab.course.chapters`` says each chapter's list).

Whatever ptlab has for the grader is never in a kit: the exercises (their checks,
references and answer files; only ``ptlab.course.given``, the objects checks hand to the
student's code, stays), the statistical graders, the command line, and the grader's side
of ``ptlab.course.sandbox`` (the child's side, which talks to the grader, stays). What is not
in the student's view of the file system cannot be imported, read, reloaded or compiled
again, whatever the student's code does.

Kits are made once per grading process, in a folder only its user can enter, and their
bytecode is compiled there (the sandbox mounts them read-only).
"""

from __future__ import annotations

import ast
import atexit
import compileall
import hashlib
import os
import py_compile
import shutil
import tempfile
import threading
import types
from pathlib import Path

from ptlab.course.sandbox.copies import resolve

#: The package whose kit is made.
PTLAB = Path(__file__).resolve().parents[2]
#: Parts of ptlab that are the grader's, never in any kit (relative to the package).
GRADERS_PARTS = ("course", "grading", "cli.py", "__main__.py")
#: Of those, the modules a kit has all the same, by folder: of ``ptlab.course.sandbox``, what
#: the student's process runs to talk to the grader; of ``ptlab.course``, the objects
#: that checks send to the student's code (each package's ``__init__`` is left empty).
KEPT_OF_GRADERS = {
    "course/sandbox": (
        "child.py",
        "channel.py",
        "plain_data.py",
        "confinement.py",
        # (the copy detector, which ``confinement`` runs, and the modules it is made of)
        "copies.py",
        "canonical.py",
        "canonical_names.py",
        "canonical_syntax.py",
        "canonical_blocks.py",
        "fingerprints.py",
        "syntax_trees.py",
        "ownership.py",
        "shown.py",
    ),
    "course": ("given.py",),
}

_lock = threading.Lock()
_made: dict[tuple[str, ...], Path] = {}
_root: Path | None = None


class KitError(ValueError):
    """A name a chapter leaves out that ptlab does not define (a typo in a chapter's list)."""


def kit_for(left_out: tuple[str, ...]) -> Path:
    """The folder of a kit (it holds ``ptlab/``) without the dotted names ``left_out``
    (modules, classes, functions of ptlab); made on first use, then reused."""
    key = tuple(sorted({defined_as(name) for name in left_out}))
    with _lock:
        if key not in _made:
            _made[key] = _make(key, _kits_folder() / _name(key))
        return _made[key]


def defined_as(name: str) -> str:
    """The dotted name under which ``name`` is defined (``ptlab.materials.Diffuse`` is
    ``ptlab.materials.diffuse.Diffuse``); a module is its own name.

    Raises ``KitError`` when ptlab has no such thing."""
    try:
        value = resolve(name)
    except (ImportError, AttributeError):
        raise KitError(
            f"a chapter leaves out {name}, which is not a module, class or function of ptlab"
        ) from None
    if isinstance(value, types.ModuleType):
        return value.__name__
    module, qualname = getattr(value, "__module__", None), getattr(value, "__qualname__", None)
    if not (isinstance(module, str) and isinstance(qualname, str)):
        raise KitError(f"a chapter leaves out {name}, which is not a module, class or function of ptlab")
    return f"{module}.{qualname}"


def _kits_folder() -> Path:
    global _root
    if _root is None:
        _root = Path(tempfile.mkdtemp(prefix="ptlab-kits-"))
        atexit.register(_remove, _root, os.getpid())
    return _root


def _remove(folder: Path, owner: int) -> None:
    """Remove the kits when the process that made them ends (not a fork of it)."""
    if os.getpid() == owner:
        shutil.rmtree(folder, ignore_errors=True)


def _name(key: tuple[str, ...]) -> str:
    return hashlib.sha256("\n".join(key).encode()).hexdigest()[:16]


def _make(left_out: tuple[str, ...], folder: Path) -> Path:
    package = folder / "ptlab"
    unused = set(left_out)
    for source in sorted(PTLAB.rglob("*.py")):
        relative = source.relative_to(PTLAB)
        if not _in_kit(relative):
            continue
        target = package / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        module = ".".join(("ptlab", *relative.with_suffix("").parts)).removesuffix(".__init__")
        if relative.name == "__init__.py" and relative.parent.as_posix() in KEPT_OF_GRADERS:
            target.write_text('"""Only what the student\'s process needs of this package."""\n')
            continue
        names = {name for name in left_out if name == module or name.startswith(module + ".")}
        if names:
            text, found = _stubbed(source.read_text(encoding="utf-8"), module, names)
            unused -= found
            target.write_text(text, encoding="utf-8")
        else:
            shutil.copyfile(source, target)
    if unused:
        raise KitError(f"a chapter leaves out what ptlab does not define: {', '.join(sorted(unused))}")
    # The sandbox mounts the kit read-only: compile it now, and have Python trust the
    # bytecode without looking at the sources' times (the kit never changes).
    compileall.compile_dir(package, quiet=1, invalidation_mode=py_compile.PycInvalidationMode.UNCHECKED_HASH)
    for path in (folder, *folder.rglob("*")):
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return folder


def _in_kit(relative: Path) -> bool:
    if relative.parts[0] not in GRADERS_PARTS:
        return True
    kept = KEPT_OF_GRADERS.get(relative.parent.as_posix(), ())
    return relative.name in ("__init__.py", *kept) if kept else False


def _stubbed(source: str, module: str, names: set[str]) -> tuple[str, set[str]]:
    """``source`` with the definitions ``names`` (dotted, under ``module``) stubbed, and
    which of ``names`` were found."""
    tree = ast.parse(source)
    found = {module} & names
    _stub_within(tree.body, module, module in names, names, found)
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            dotted = f"{module}.{node.name}"
            found |= {dotted} & names
            _stub_within(node.body, dotted, module in names or dotted in names, names, found)
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n", found


def _stub_within(body: list[ast.stmt], owner: str, every: bool, names: set[str], found: set[str]) -> None:
    """Stub the functions of ``body`` (of ``owner``: a module or a class) that ``names``
    holds, or all of them (``every``); add the names stubbed to ``found``."""
    for node in body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            dotted = f"{owner}.{node.name}"
            if every or dotted in names:
                _stub(node, dotted)
                found.add(dotted)


def _stub(function: ast.FunctionDef | ast.AsyncFunctionDef, dotted: str) -> None:
    """Make ``function``'s body one ``raise NotInKitError(...)`` (its decorators and
    parameters stay, so that properties, class methods and signatures look the same)."""
    message = (
        f"{dotted} is left out of the kit your code is graded with: it is, or computes, "
        f"what your code must do itself"
    )
    body = ast.parse(f"raise __import__('ptlab.errors').errors.NotInKitError({message!r})").body
    function.body = body
