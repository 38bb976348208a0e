"""Is a graded name the student's own code, or the library's answer under the student's name?

Read from the file's source (``ast``), without running it, so nothing the file does at
import can change the verdict. A name is the library's own answer when the file's last
top-level binding of it is

* an import from ptlab (``from ptlab.integrators.path import trace_paths``), or an
  assignment of one (``trace_paths = path.trace_paths``);
* a function whose whole body returns the library's function of the same name
  (``def trace_paths(*args): return path.trace_paths(*args)``);
* a class that writes none of ``eval``, ``pdf``, ``sample`` itself but inherits them from
  a ptlab material (``class Lambertian(ptlab.materials.Diffuse): pass``); the interface
  classes ``Material`` and ``DeltaMaterial`` implement nothing, and do not count.

The process that runs the file also reports where each graded function's code lives
(``ptlab.course.sandbox.child``), which catches what only happens at run time (an
``importlib`` call, ``exec``). Neither can see the library's code copied into the file:
that is for a course's review (docs/grading-security.md).
"""

from __future__ import annotations

import ast

from ptlab.materials.base import HOMEWORK_METHODS

#: The homework's three functions: what a material must have, and what is graded of it.
MATERIAL_METHODS = HOMEWORK_METHODS
#: ptlab classes that a student's material may subclass: they only declare the interface.
INTERFACES = ("Material", "DeltaMaterial")


def library_answer(tree: ast.Module, name: str) -> str | None:
    """The dotted name of the ptlab answer that ``name`` is in the file, or None."""
    imported = _ptlab_imports(tree)
    classes = {node.name: node for node in tree.body if isinstance(node, ast.ClassDef)}
    binding = _last_binding(tree, name)
    if isinstance(binding, ast.Import | ast.ImportFrom):
        return imported.get(name)
    if isinstance(binding, ast.Assign | ast.AnnAssign):
        return _origin(binding.value, imported) if binding.value is not None else None
    if isinstance(binding, ast.FunctionDef):
        return _returns_library_function(binding, imported)
    if isinstance(binding, ast.ClassDef):
        return _inherited_material(binding, imported, classes)
    return None


def _ptlab_imports(tree: ast.Module) -> dict[str, str]:
    """{name in the file: dotted ptlab name} for the file's top-level imports from ptlab."""
    found = {}
    for node in _top_level(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and _is_ptlab(node.module or ""):
            for alias in node.names:
                found[alias.asname or alias.name] = f"{node.module}.{alias.name}"
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if _is_ptlab(alias.name):
                    local = alias.asname or alias.name.split(".")[0]
                    found[local] = alias.name if alias.asname else local
    return found


def _is_ptlab(module: str) -> bool:
    return module == "ptlab" or module.startswith("ptlab.")


def _top_level(tree: ast.Module) -> list[ast.stmt]:
    """The module's statements, including those inside top-level ``if`` and ``try`` blocks."""
    statements = []
    for node in tree.body:
        statements.append(node)
        if isinstance(node, ast.If | ast.Try):
            for block in (
                node.body,
                node.orelse,
                getattr(node, "finalbody", []),
                *[handler.body for handler in getattr(node, "handlers", [])],
            ):
                statements.extend(block)
    return statements


def _last_binding(tree: ast.Module, name: str) -> ast.stmt | None:
    found: ast.stmt | None = None
    for node in _top_level(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            if node.name == name:
                found = node
        elif isinstance(node, ast.Import | ast.ImportFrom):
            if any((alias.asname or alias.name.split(".")[0]) == name for alias in node.names):
                found = node
        elif isinstance(node, ast.Assign):
            if any(isinstance(t, ast.Name) and t.id == name for t in node.targets):
                found = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.target.id == name:
            found = node
    return found


def _origin(expression: ast.expr, imported: dict[str, str]) -> str | None:
    """The dotted ptlab name an expression like ``path.trace_paths`` stands for, or None."""
    if isinstance(expression, ast.Name):
        return imported.get(expression.id)
    if isinstance(expression, ast.Attribute):
        base = _origin(expression.value, imported)
        return f"{base}.{expression.attr}" if base else None
    return None


def _returns_library_function(function: ast.FunctionDef, imported: dict[str, str]) -> str | None:
    body = function.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]  # the docstring
    if len(body) == 1 and isinstance(body[0], ast.Return) and isinstance(body[0].value, ast.Call):
        origin = _origin(body[0].value.func, imported)
        if origin and origin.rsplit(".", 1)[-1] == function.name:
            return origin
    return None


def _inherited_material(
    cls: ast.ClassDef, imported: dict[str, str], classes: dict[str, ast.ClassDef]
) -> str | None:
    """The ptlab material that ``cls`` takes its material methods from, if neither it nor
    any of its bases in the file writes one of them."""
    if _writes_material_methods(cls, classes, set()):
        return None
    return _library_base(cls, imported, classes, set())


def _writes_material_methods(cls: ast.ClassDef, classes: dict[str, ast.ClassDef], seen: set[str]) -> bool:
    """Whether ``cls`` or one of its bases in the file defines a material method."""
    seen.add(cls.name)
    if any(
        isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.name in MATERIAL_METHODS
        for node in cls.body
    ):
        return True
    return any(
        _writes_material_methods(classes[base.id], classes, seen)
        for base in cls.bases
        if isinstance(base, ast.Name) and base.id in classes and base.id not in seen
    )


def _library_base(
    cls: ast.ClassDef, imported: dict[str, str], classes: dict[str, ast.ClassDef], seen: set[str]
) -> str | None:
    """The first ptlab base of ``cls`` (or of its bases in the file) that is no interface."""
    seen.add(cls.name)
    for base in cls.bases:
        origin = _origin(base, imported)
        if origin and origin.rsplit(".", 1)[-1] not in INTERFACES:
            return origin
        if isinstance(base, ast.Name) and base.id in classes and base.id not in seen:
            found = _library_base(classes[base.id], imported, classes, seen)
            if found:
                return found
    return None
