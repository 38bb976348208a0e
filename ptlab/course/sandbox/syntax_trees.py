"""Small readings of Python's syntax trees that the canonical form, the fingerprints and the
copy detector share (``ptlab.course.sandbox.canonical``, ``fingerprints``, ``copies``): a tree's
copy and size, the dotted name an expression spells, the statements of a body that do
something, the name a statement assigns.
"""

from __future__ import annotations

import ast
from typing import Any

#: A function's definition, plain or ``async``.
FunctionNode = ast.FunctionDef | ast.AsyncFunctionDef


def tree_copy(node: Any) -> Any:
    """A copy of the syntax tree (or list of trees) ``node`` (several times as fast as
    ``copy.deepcopy``, which the student's process pays for at every compile)."""
    if isinstance(node, list):
        return [tree_copy(item) for item in node]
    if not isinstance(node, ast.AST):
        return node
    new = node.__class__()
    for field, value in ast.iter_fields(node):
        setattr(new, field, tree_copy(value))
    for attribute in node._attributes:
        if hasattr(node, attribute):
            setattr(new, attribute, getattr(node, attribute))
    return new


def node_count(node: ast.AST) -> int:
    """The nodes of the syntax tree ``node``."""
    return sum(1 for _ in ast.walk(node))


def dotted_name(node: ast.AST | None) -> str | None:
    """``a.b.c`` for the expression ``a.b.c``, else None."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return ".".join(reversed(parts))


def dotted_node(dotted: str, like: ast.AST) -> ast.expr:
    """The expression that reads ``dotted`` (``numpy.where``), placed where ``like`` is."""
    parts = dotted.lstrip(".").split(".")
    node: ast.expr = ast.Name(parts[0], ast.Load())
    for part in parts[1:]:
        node = ast.Attribute(node, part, ast.Load())
    return ast.copy_location(node, like)


def identifier(node: ast.AST) -> str | None:
    """The constant string ``node`` holds, if it is an identifier (a name ``getattr`` reads)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value.isidentifier():
        return node.value
    return None


def statements_of(body: list) -> list:
    """``body`` without docstrings, constants standing alone (``...``) and ``pass``."""
    return [
        s
        for s in body
        if not (isinstance(s, ast.Pass) or (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)))
    ]


def assigned_name(statement: ast.AST) -> str | None:
    """The name ``statement`` assigns, if it assigns one name (``x = ...``), else None."""
    if isinstance(statement, ast.Assign) and len(statement.targets) == 1:
        target = statement.targets[0]
        return target.id if isinstance(target, ast.Name) else None
    return None
