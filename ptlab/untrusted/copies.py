"""Copies of ptlab's own answers in a student's code, with the names changed or not.

Renaming the variables of the library's function and deleting its docstring gives the
library's answer under a student's name. ``fingerprint`` keeps what such a copy keeps: a
function's syntax tree with every identifier (variables, arguments, attributes, function
and class names), docstring, annotation and no-op statement dropped, and its operations,
their order and its constants kept. A student who writes the code does not produce the same
tree; one who copies it does, however the names were changed.

A formula of a few terms can be written in only a few ways (``alpha2 / (pi * d * d)``), so
matching such a function alone is no evidence: a file is a copy when the library's answers
it holds add up to ``MIN_COPIED_NODES`` nodes of syntax tree (the library's ``Diffuse`` has
200 in its three methods, ``trace_paths`` 249, GGX's ``D`` 46).

The grader looks for copies in the file's text (``copies_in``); the student's process
looks at everything compiled there at run time too (``ptlab.untrusted.confinement``), so
a copy that is assembled or decoded at run time is found as well.
"""

from __future__ import annotations

import ast
import copy
import hashlib
import importlib
import inspect
import textwrap
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

#: Nodes of copied syntax tree from which a file counts as a copy (see the module docstring).
MIN_COPIED_NODES = 100
#: The methods of a class that are its answer (the homework's three, and the weight).
ANSWER_METHODS = ("eval", "pdf", "sample", "sample_weight")

FunctionNode = ast.FunctionDef | ast.AsyncFunctionDef


@dataclass(frozen=True)
class Answer:
    """One function of ptlab's answers, as ``fingerprint`` sees it.

    Attributes:
        origin: where it is (``ptlab.integrators.path.trace_paths``).
        nodes: the size of its normalised syntax tree.
    """

    origin: str
    nodes: int


class _Anonymise(ast.NodeTransformer):
    """Drops what a copier can change without changing what the code computes."""

    def visit_Name(self, node: ast.Name) -> ast.AST:  # noqa: N802 (ast's visitor names)
        return ast.Name(id="_", ctx=ast.Load())

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:  # noqa: N802
        self.generic_visit(node)
        return ast.Attribute(value=node.value, attr="_", ctx=ast.Load())

    def visit_arg(self, node: ast.arg) -> ast.AST:
        return ast.arg(arg="_")

    def visit_alias(self, node: ast.alias) -> ast.AST:
        return ast.alias(name="_")

    def visit_FunctionDef(self, node: FunctionNode) -> ast.AST:  # noqa: N802
        node.name, node.returns, node.decorator_list = "_", None, []
        return self._body(node)

    visit_AsyncFunctionDef = visit_FunctionDef  # noqa: N815

    def visit_ClassDef(self, node: ast.ClassDef) -> ast.AST:  # noqa: N802
        node.name, node.decorator_list = "_", []
        return self._body(node)

    def visit_AnnAssign(self, node: ast.AnnAssign) -> ast.AST | None:  # noqa: N802
        if node.value is None:
            return None
        return self.visit(ast.Assign(targets=[node.target], value=node.value))

    def visit_Global(self, node: ast.Global) -> None:  # noqa: N802
        return None

    visit_Nonlocal = visit_Global  # noqa: N815

    def visit_ExceptHandler(self, node: ast.ExceptHandler) -> ast.AST:  # noqa: N802
        node.name = "_" if node.name else None
        return self.generic_visit(node)

    def generic_visit(self, node: ast.AST) -> ast.AST:
        for name in ("body", "orelse", "finalbody"):
            if isinstance(getattr(node, name, None), list):
                setattr(node, name, _statements(getattr(node, name)))
        return super().generic_visit(node)

    def _body(self, node):
        node = self.generic_visit(node)
        node.body = _statements(node.body) or [ast.Pass()]
        return node


def _statements(body: list) -> list:
    """``body`` without docstrings, strings standing alone and ``pass``."""
    return [
        s
        for s in body
        if not (
            isinstance(s, ast.Pass)
            or (
                isinstance(s, ast.Expr)
                and isinstance(s.value, ast.Constant)
                and isinstance(s.value.value, str)
            )
        )
    ]


def fingerprint(function: FunctionNode) -> tuple[str, int]:
    """(digest, size) of ``function``'s normalised syntax tree (see the module docstring)."""
    tree = _Anonymise().visit(copy.deepcopy(function))  # (the visitor changes what it visits)
    text = ast.dump(tree, annotate_fields=False, include_attributes=False)
    return hashlib.sha256(text.encode()).hexdigest(), sum(1 for _ in ast.walk(tree))


def functions_in(tree: ast.AST) -> list[FunctionNode]:
    """Every function in ``tree``, nested ones and methods included."""
    return [node for node in ast.walk(tree) if isinstance(node, FunctionNode)]


# -- the library's side ------------------------------------------------------------------


def answers_of(names: Iterable[str], solution: Path | None = None) -> dict[str, Answer]:
    """{digest: Answer} of the functions ``names`` (dotted: a function, or a class whose
    ``ANSWER_METHODS`` it defines) and of every function in ``solution``, the chapter's
    answer file."""
    found: dict[str, Answer] = {}
    for name in names:
        for origin, node in _library_functions(name):
            digest, nodes = fingerprint(node)
            found.setdefault(digest, Answer(origin, nodes))
    if solution is not None:
        tree = ast.parse(solution.read_bytes(), filename=str(solution))
        for node in functions_in(tree):
            digest, nodes = fingerprint(node)
            found.setdefault(digest, Answer(f"{solution.name}:{node.name}", nodes))
    return found


def resolve(name: str):
    """The object a dotted name stands for (``ptlab.materials.Diffuse``)."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            value = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attribute in parts[cut:]:
            value = getattr(value, attribute)
        return value
    raise ImportError(f"no module in {name!r}")


def _library_functions(name: str) -> list[tuple[str, FunctionNode]]:
    value = resolve(name)
    if inspect.isclass(value):
        methods = [(f"{name}.{m}", value.__dict__[m]) for m in ANSWER_METHODS if m in value.__dict__]
    else:
        methods = [(name, value)]
    found = []
    for origin, function in methods:
        node = ast.parse(textwrap.dedent(inspect.getsource(function))).body[0]
        found.append((origin, node))
    return found


# -- the student's side -------------------------------------------------------------------


def copies_in(tree: ast.AST, answers: dict[str, Answer]) -> list[tuple[int, Answer]]:
    """(line, answer) of every function in ``tree`` that is one of ``answers``."""
    found = []
    for node in functions_in(tree):
        answer = answers.get(fingerprint(node)[0])
        if answer is not None:
            found.append((node.lineno, answer))
    return found


def copied_class(tree: ast.Module, name: str, answers: dict[str, Answer]) -> list[tuple[int, Answer]]:
    """The copies among the ``ANSWER_METHODS`` that the top-level class ``name`` defines, if
    every one it defines is a copy; else [] (a class that writes some of them itself is the
    student's, as a subclass that overrides some is)."""
    classes = [node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == name]
    methods = (
        [node for node in classes[-1].body if isinstance(node, FunctionNode) and node.name in ANSWER_METHODS]
        if classes
        else []
    )
    found = copies_in(ast.Module(body=methods, type_ignores=[]), answers)
    return found if methods and len(found) == len(methods) else []


def is_a_copy(found: list[tuple[int, Answer]]) -> bool:
    """Whether the copies ``copies_in`` found add up to a copied answer."""
    return sum(answer.nodes for _, answer in found) >= MIN_COPIED_NODES


def describe_copies(found: list[tuple[int, Answer]], file: str) -> str:
    """ "a copy of ptlab's own answer (ptlab.x.f at 07.py:12, ...)"."""
    places = ", ".join(f"{answer.origin} at {file}:{line}" for line, answer in found[:3])
    more = f" and {len(found) - 3} more" if len(found) > 3 else ""
    return f"a copy of ptlab's own answer, with the names changed ({places}{more})"
