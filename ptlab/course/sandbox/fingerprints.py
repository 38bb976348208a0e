"""Fingerprints of code: its normalised tokens, and the hashed runs of them (its grams).

* ``tokens``: each statement of a function's body, in its canonical form
  (``ptlab.course.sandbox.canonical``), as a sequence of tokens, one per node of its syntax
  tree, a compound statement's header (``if x > 0``) one sequence and each statement of its
  bodies another. Every variable, argument and attribute of ``self`` is one token ``N``
  (the student names them), and so is what ptlab defines (a copy may import it or paste it:
  the kit leaves some of it out); other attributes and what other imports name are kept by
  their last name (``.throughput``, ``.where``). Docstrings, annotations, parameters
  (defaults too), ``pass`` and constants standing alone are dropped; numbers go by value
  (``2`` is ``2.0``). An assignment or a ``return`` is what it computes (``y = f(x); return
  y`` holds ``return f(x)``), ``a += b`` is ``a + b``, and the operands of commutative
  operators (``+ * & | ^ == != and or``) and of ``<``/``>`` are put in one order.
* ``grams``: the set of the hashed runs of ``NGRAM`` consecutive tokens within each
  statement (a shorter statement is one run). Winnowing (Schleimer, Wilkerson and Aiken,
  "Winnowing: local algorithms for document fingerprinting", SIGMOD 2003), which MOSS uses
  to keep a sample of the grams of large programs, is not needed for functions this
  small: every gram is kept. A dead statement, a moved one or a renamed variable changes
  none of the library's grams.

``ptlab.course.sandbox.copies`` looks for the library's answers' grams in a student's.
"""

from __future__ import annotations

import ast
import zlib
from collections.abc import Iterator, Sequence

from ptlab.course.sandbox.canonical import canonical
from ptlab.course.sandbox.syntax_trees import FunctionNode, statements_of

#: Tokens per gram: long enough that honest code shares few grams with the library's,
#: short enough that an edit every few statements leaves most grams whole.
NGRAM = 6
#: The mark of a token inside an expression that an exercise file writes (evidence only).
GIVEN_MARK = "\x00"

_COMMUTATIVE = (ast.Add, ast.Mult, ast.BitAnd, ast.BitOr, ast.BitXor)
_SYMMETRIC = (ast.Eq, ast.NotEq, ast.Is, ast.IsNot)
_MIRRORED = {ast.Gt: ast.Lt, ast.GtE: ast.LtE}
#: Fields that a copier may change freely (or that only say how a name is used).
_DROPPED_FIELDS = {"ctx", "type_comment", "decorator_list", "returns", "annotation", "type_params"}


def tokens(function: ast.AST) -> list[list[str]]:
    """The normalised tokens of ``function``'s body (or a module's), one list per statement
    (a compound statement's header is one, each statement of its bodies another), read in
    its ``canonical`` form (see the module docstring)."""
    return PLAIN.lines(canonical(function))


def grams(function: ast.AST) -> frozenset[int]:
    """The hashed runs of ``NGRAM`` consecutive ``tokens`` within each statement of
    ``function`` (a shorter statement is one run; one of a single token says nothing). The
    hash is the same in every process: the student's process compares with the grader's."""
    return canonical_grams(canonical(function))


def canonical_grams(node: ast.AST) -> frozenset[int]:
    """``grams`` of a tree already in its canonical form."""
    return frozenset(gram for line in PLAIN.lines(node) for _, _, gram in runs(line))


def runs(line: list[str]) -> Iterator[tuple[int, int, int]]:
    """(start, end, gram) of each run of ``NGRAM`` tokens of ``line`` (one run if it is
    shorter; none for a single token)."""
    if len(line) < 2:
        return
    ids = [zlib.crc32(token.encode()) for token in line]
    for start in range(max(1, len(ids) - NGRAM + 1)):
        end = min(len(ids), start + NGRAM)
        yield start, end, hash(tuple(ids[start:end]))


def run_hash(line: list[str]) -> int:
    """The gram of ``line`` taken as one run (what ``runs`` gives a line shorter than NGRAM)."""
    return hash(tuple(zlib.crc32(token.encode()) for token in line))


def unmarked(line: list[str]) -> list[str]:
    """``line`` without the marks of given tokens."""
    return [token.removeprefix(GIVEN_MARK) for token in line]


class Tokenizer:
    """The token lines of a canonical tree (``tokens``). With ``given`` (the ``run_hash``
    of every expression the exercise files write), the tokens of such an expression carry
    the mark ``GIVEN_MARK``: they are no evidence of copying."""

    def __init__(self, given: frozenset[int] = frozenset(), named: frozenset[str] = frozenset()):
        self.given, self.named = given, named

    def lines(self, node: ast.AST) -> list[list[str]]:
        """The token lines of the statements of ``node`` (a function or a module), or of
        ``node`` itself (a statement)."""
        body = node.body if isinstance(node, FunctionNode | ast.Module) else [node]
        out: list[list[str]] = []
        for statement in statements_of(body):
            out.extend(self.statement(statement))
        return out

    def statement(self, statement: ast.stmt) -> list[list[str]]:
        """The token lines of ``statement``: one, or a compound statement's header and
        the lines of each statement of its bodies."""
        if isinstance(statement, ast.Assign | ast.AnnAssign | ast.AugAssign | ast.Return | ast.Expr):
            # What is computed, not where it goes: ``y = f(x); return y`` holds ``return f(x)``.
            value = getattr(statement, "value", None)
            if isinstance(statement, ast.AugAssign):
                line = self.binop(statement.op, [statement.target, statement.value])
            else:
                line = self.expression(value) if value is not None else []
            targets = getattr(statement, "targets", None) or [getattr(statement, "target", None)]
            for target in targets:
                if target is not None and not isinstance(target, ast.Name):
                    line += ["=", *self.expression(target)]  # (``hit.throughput[rows] = ...``)
            return [line]
        header, bodies = [_label(statement)], []
        for name, value in ast.iter_fields(statement):
            if name in _DROPPED_FIELDS or (name == "args" and isinstance(statement, FunctionNode)):
                continue
            if isinstance(value, list) and value and isinstance(value[0], ast.stmt | ast.excepthandler):
                bodies.append(value)
            else:
                for child in value if isinstance(value, list) else [value]:
                    if isinstance(child, ast.AST):
                        header.extend(self.expression(child))
        out = [header]
        for body in bodies:
            for child in statements_of(body):
                out.extend(self.statement(child))
        return out

    def expression(self, node: ast.AST) -> list[str]:
        """The tokens of ``node``, each marked ``GIVEN_MARK`` if the exercise files write
        the expression (``given``) or it calls what they name (``named``) with names and
        constants."""
        out = self._expression(node)
        if (self.given and len(out) >= 2 and run_hash(unmarked(out)) in self.given) or self._named_call(
            node, out
        ):
            return [token if token.startswith(GIVEN_MARK) else GIVEN_MARK + token for token in out]
        return out

    def _named_call(self, node: ast.AST, out: list[str]) -> bool:
        """Whether ``node`` calls what the exercise files name with names and constants
        (``as_completed(futures)``): the file says to call it; the names are the student's."""
        if not (self.named and isinstance(node, ast.Call) and len(out) >= 2):
            return False
        arguments = [*node.args, *(k.value for k in node.keywords)]
        plain = (ast.Name, ast.Constant, ast.Starred)
        leaves = all(
            isinstance(a, plain) or (isinstance(a, ast.Attribute) and _is_dotted(a)) for a in arguments
        )
        return leaves and out[1].removeprefix(GIVEN_MARK) in self.named

    def _expression(self, node: ast.AST) -> list[str]:
        if isinstance(node, ast.Name):
            return ["N"]
        if isinstance(node, ast.Attribute) and _is_dotted(node):
            # The student names its own attributes (``self.albedo``), not the library's
            # (``hit.throughput``, ``wi.dtype``, ``np.where``), whatever its variables are
            # called. What ptlab defines a copy may import or paste into the file (the kit
            # leaves some out): either way it is a name (``ptlab.vectors.dot`` as ``dot``).
            return ["N"] if _is_self(node) or _root(node) == "ptlab" else [f".{node.attr}"]
        if isinstance(node, ast.Constant):
            return [_constant(node.value)]
        if isinstance(node, ast.AugAssign):
            return ["Assign", *self.expression(node.target), *self.binop(node.op, [node.target, node.value])]
        if isinstance(node, ast.AnnAssign):
            return (
                ["Assign", *self.expression(node.target), *self.expression(node.value)] if node.value else []
            )
        if isinstance(node, ast.BinOp):
            return self.binop(node.op, [node.left, node.right])
        if isinstance(node, ast.BoolOp):
            return [f"BoolOp:{type(node.op).__name__}", *self.sorted_operands(node.values)]
        if isinstance(node, ast.Compare) and len(node.ops) == 1:
            return self.comparison(node)
        if isinstance(node, ast.Global | ast.Nonlocal | ast.Pass):
            return []
        return self.node_and_children(node)

    def comparison(self, node: ast.Compare) -> list[str]:
        """``a > b`` as ``b < a`` reads, and the operands of ``==`` and ``!=`` in sorted order."""
        op, left, right = type(node.ops[0]), node.left, node.comparators[0]
        if op in _MIRRORED:
            op, left, right = _MIRRORED[op], right, left
        if op in _SYMMETRIC:
            return [f"Compare:{op.__name__}", *self.sorted_operands([left, right])]
        return [f"Compare:{op.__name__}", *self.expression(left), *self.expression(right)]

    def node_and_children(self, node: ast.AST) -> list[str]:
        """Any other node: its label, then its children's tokens (statements reduced)."""
        out = [_label(node)]
        for name, value in ast.iter_fields(node):
            if name in _DROPPED_FIELDS or (name == "args" and isinstance(node, FunctionNode | ast.Lambda)):
                continue  # (parameters too: their names and defaults change nothing)
            if name in ("body", "orelse", "finalbody") and isinstance(value, list):
                value = statements_of(value)
            for child in value if isinstance(value, list) else [value]:
                if isinstance(child, ast.AST):
                    out.extend(self.expression(child))
        return out

    def binop(self, op: ast.operator, operands: list[ast.AST]) -> list[str]:
        label = f"BinOp:{type(op).__name__}"
        if not isinstance(op, _COMMUTATIVE):
            return [label, *self.expression(operands[0]), *self.expression(operands[1])]
        flat: list[ast.AST] = []  # (a + b) + c, a + (b + c) and c + b + a are one sum
        while operands:
            operand = operands.pop()
            if isinstance(operand, ast.BinOp) and type(operand.op) is type(op):
                operands += [operand.left, operand.right]
            else:
                flat.append(operand)
        return [label, f"#{len(flat)}", *self.sorted_operands(flat)]

    def sorted_operands(self, operands: Sequence[ast.AST]) -> list[str]:
        parts = sorted((self.expression(o) for o in operands), key=unmarked)
        return [token for part in parts for token in part]


#: The tokenizer that marks no token as given (``tokens``, ``grams``).
PLAIN = Tokenizer()


def _label(node: ast.AST) -> str:
    kind = type(node).__name__
    op = getattr(node, "op", None)
    if isinstance(node, ast.Compare):
        return kind + ":" + ",".join(type(o).__name__ for o in node.ops)
    return f"{kind}:{type(op).__name__}" if isinstance(op, ast.AST) else kind


def _is_self(node: ast.Attribute) -> bool:
    return isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")


def _root(node: ast.AST) -> str | None:
    """The name a dotted name starts with (``np`` of ``np.linalg.norm``)."""
    while isinstance(node, ast.Attribute):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _is_dotted(node: ast.AST) -> bool:
    while isinstance(node, ast.Attribute):
        node = node.value
    return isinstance(node, ast.Name)


def _constant(value) -> str:
    if isinstance(value, bool) or value is None or value is Ellipsis:
        return f"C:{value!r}"
    if isinstance(value, int | float):
        return f"C:{float(value)!r}" if abs(value) < 2**53 else f"C:{value!r}"
    return f"C:{type(value).__name__}:{value!r}"


def functions_in(tree: ast.AST) -> list[FunctionNode]:
    """Every function in ``tree``, nested ones and methods included."""
    return [node for node in ast.walk(tree) if isinstance(node, FunctionNode)]
