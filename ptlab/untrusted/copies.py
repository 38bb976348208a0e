"""Copies of ptlab's own answers in a student's code, renamed, padded or shuffled.

A copier changes what does not change the code: names, docstrings, annotations, the order
of independent statements, the operands of ``*``; and adds what does nothing: a dead
``x = 0``, ``if False: pass``, an unused parameter, a helper that only passes its
arguments on. An exact comparison of syntax trees misses every such copy, so this module
compares them the way plagiarism detectors do (MOSS's k-grams of normalised tokens):

* ``tokens``: each statement of a function's body as a sequence of tokens, one per node
  of its syntax tree, a compound statement's header (``if x > 0``) one sequence and each
  statement of its bodies another. Every variable, argument and attribute of ``self`` is
  one token ``N`` (the student names them); the library's attributes are kept by name
  (``.throughput``, ``.dtype``, ``.where``: ``np.where`` and ``numpy.where`` alike).
  Docstrings, annotations, parameters (defaults too), ``pass`` and constants standing
  alone are dropped; numbers go by value (``2`` is ``2.0``), other constants are kept. An
  assignment or a ``return`` is what it computes (``y = f(x); return y`` holds ``return
  f(x)``), ``a += b`` is ``a + b``, and the operands of commutative operators (``+ * & |
  ^ == != and or``) and of ``<``/``>`` are put in one order;
* ``grams``: the set of the hashed runs of ``NGRAM`` consecutive tokens within each
  statement (a shorter statement is one run; winnowing, which MOSS uses to keep a
  sample of the grams of large programs, is not needed for functions this small). A
  dead statement, a moved one or a renamed variable changes none of the library's grams;
  an edit inside an expression changes the few that overlap it;
* a student's function is compared with what it reaches: its own grams and those of the
  functions of the same file it names, transitively (a no-op wrapper reaches the copy it
  wraps; halves of a copy in two helpers are reached together);
* similarity = the share of the library function's grams found there (padding the copy
  does not lower it), after removing the grams of the code the exercise files give
  (``templates/``: their functions, and the code their hints quote between double
  backquotes): what a student is handed is no evidence of copying.

A student's function is a copy of a library answer from ``THRESHOLD`` similarity.
Measured (``tests/attacks/test_copies.py`` checks the figures): the honest answers of
``tests/exercises`` (right ones, wrong ones, the templates as handed out) are at most
0.74 similar to any answer that weighs enough to count alone (``ray_triangle``: the
Moller-Trumbore steps are the same in every version); every near-copy of chapters 3, 6,
7 and 9 (each edit above alone, and all at once) is 1.00 similar to the answers it copies.
``THRESHOLD`` = 0.85 leaves 0.11 below it and 0.15 above it; the tests ask for 0.10.

A formula of a few terms can be written in only a few ways (``alpha2 / (pi * d * d)``), so
matching such a function alone is no evidence: honest answers of chapter 9 match GGX's
``D``, ``G1`` and ``G2`` entirely (43 tokens together), and of chapter 3 ``reflect`` (16).
A file (or a class, for ``ptlab grade``) is a copy when the answers it copies weigh
``MIN_COPIED_TOKENS`` tokens together; the lightest near-copy, the three methods of
chapter 6's ``Diffuse``, weighs 69 (``trace_paths`` alone 78, chapter 3's three
functions 135).

The grader looks for copies in the file's text (``copies_in``); the student's process
looks at everything compiled there at run time too (``ptlab.untrusted.confinement``), so
a copy that is assembled or decoded at run time is found as well.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import textwrap
import zlib
from collections.abc import Iterable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

#: Tokens per gram: long enough that honest code shares few grams with the library's,
#: short enough that an edit every few statements leaves most grams whole.
NGRAM = 6
#: Share of a library function's grams from which a student's function is its copy:
#: between the honest 0.74 and the copied 1.00 of the module docstring.
THRESHOLD = 0.85
#: Tokens of copied answers from which a file (or a class) counts as a copy: between the
#: honest 43 and the copied 69 of the module docstring.
MIN_COPIED_TOKENS = 56
#: The methods of a class that are its answer (the homework's three, and the weight).
ANSWER_METHODS = ("eval", "pdf", "sample", "sample_weight")
#: The methods ``ptlab grade`` grades: a class is a copy when each of these it writes is.
GRADED_METHODS = ("eval", "pdf", "sample")
#: The exercise files handed to students, whose code is not evidence of copying.
TEMPLATES = Path(__file__).resolve().parents[1] / "exercises" / "templates"

FunctionNode = ast.FunctionDef | ast.AsyncFunctionDef

_COMMUTATIVE = (ast.Add, ast.Mult, ast.BitAnd, ast.BitOr, ast.BitXor)
_SYMMETRIC = (ast.Eq, ast.NotEq, ast.Is, ast.IsNot)
_MIRRORED = {ast.Gt: ast.Lt, ast.GtE: ast.LtE}
#: Fields that a copier may change freely (or that only say how a name is used).
_DROPPED_FIELDS = {"ctx", "type_comment", "decorator_list", "returns", "annotation", "type_params"}


@dataclass(frozen=True)
class Answer:
    """One function of ptlab's answers, as ``grams`` sees it.

    Attributes:
        origin: where it is (``ptlab.integrators.path.trace_paths``).
        grams: its grams that no exercise file gives.
        size: the tokens of its statements that hold such grams (what a copy of it weighs).
    """

    origin: str
    grams: frozenset[int]
    size: int


@dataclass(frozen=True)
class Answers:
    """The answers a student's code may not copy, and the grams the exercise files give."""

    answers: tuple[Answer, ...] = ()
    given: frozenset[int] = frozenset()

    def __bool__(self) -> bool:
        return bool(self.answers)


@dataclass(frozen=True)
class Copy:
    """A student's function found to be (mostly) a library answer.

    Attributes:
        line: where the student's function starts.
        name: the student's function.
        answer: the library's answer it copies.
        similarity: the share of the answer's grams found in it (0..1).
    """

    line: int
    name: str
    answer: Answer
    similarity: float


# -- normalised tokens and grams ----------------------------------------------------------


def tokens(function: ast.AST) -> list[list[str]]:
    """The normalised tokens of ``function``'s body, one list per statement (a compound
    statement's header is one, each statement of its bodies another; see the module
    docstring)."""
    body = function.body if isinstance(function, FunctionNode | ast.Module) else [function]
    out: list[list[str]] = []
    for statement in _statements(body):
        out.extend(_statement_tokens(statement))
    return out


def _statement_tokens(statement: ast.stmt) -> list[list[str]]:
    if isinstance(statement, ast.Assign | ast.AnnAssign | ast.AugAssign | ast.Return | ast.Expr):
        # What is computed, not where it goes: ``y = f(x); return y`` holds ``return f(x)``.
        value = getattr(statement, "value", None)
        if isinstance(statement, ast.AugAssign):
            line = _binop(statement.op, [statement.target, statement.value])
        else:
            line = _tokens(value) if value is not None else []
        targets = getattr(statement, "targets", None) or [getattr(statement, "target", None)]
        for target in targets:
            if target is not None and not isinstance(target, ast.Name):
                line += ["=", *_tokens(target)]  # (``hit.throughput[rows] = ...``)
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
                    header.extend(_tokens(child))
    out = [header]
    for body in bodies:
        for child in _statements(body):
            out.extend(_statement_tokens(child))
    return out


def _tokens(node: ast.AST) -> list[str]:
    if isinstance(node, ast.Name):
        return ["N"]
    if isinstance(node, ast.Attribute) and _is_dotted(node):
        # The student names its own attributes (``self.albedo``), not the library's
        # (``hit.throughput``, ``wi.dtype``, ``np.where``), whatever its variables are called.
        return ["N"] if _is_self(node) else [f".{node.attr}"]
    if isinstance(node, ast.Constant):
        return [_constant(node.value)]
    if isinstance(node, ast.AugAssign):
        return ["Assign", *_tokens(node.target), *_binop(node.op, [node.target, node.value])]
    if isinstance(node, ast.AnnAssign):
        return ["Assign", *_tokens(node.target), *_tokens(node.value)] if node.value else []
    if isinstance(node, ast.BinOp):
        return _binop(node.op, [node.left, node.right])
    if isinstance(node, ast.BoolOp):
        return [f"BoolOp:{type(node.op).__name__}", *_sorted_operands(node.values)]
    if isinstance(node, ast.Compare) and len(node.ops) == 1:
        return _comparison(node)
    if isinstance(node, ast.Global | ast.Nonlocal | ast.Pass):
        return []
    return _node_and_children(node)


def _comparison(node: ast.Compare) -> list[str]:
    """``a > b`` as ``b < a`` reads, and the operands of ``==`` and ``!=`` in sorted order."""
    op, left, right = type(node.ops[0]), node.left, node.comparators[0]
    if op in _MIRRORED:
        op, left, right = _MIRRORED[op], right, left
    if op in _SYMMETRIC:
        return [f"Compare:{op.__name__}", *_sorted_operands([left, right])]
    return [f"Compare:{op.__name__}", *_tokens(left), *_tokens(right)]


def _node_and_children(node: ast.AST) -> list[str]:
    """Any other node: its label, then its children's tokens (statements reduced)."""
    out = [_label(node)]
    for name, value in ast.iter_fields(node):
        if name in _DROPPED_FIELDS or (name == "args" and isinstance(node, FunctionNode | ast.Lambda)):
            continue  # (parameters too: their names and defaults change nothing)
        if name in ("body", "orelse", "finalbody") and isinstance(value, list):
            value = _statements(value)
        for child in value if isinstance(value, list) else [value]:
            if isinstance(child, ast.AST):
                out.extend(_tokens(child))
    return out


def _label(node: ast.AST) -> str:
    kind = type(node).__name__
    op = getattr(node, "op", None)
    if isinstance(node, ast.Compare):
        return kind + ":" + ",".join(type(o).__name__ for o in node.ops)
    return f"{kind}:{type(op).__name__}" if isinstance(op, ast.AST) else kind


def _is_self(node: ast.Attribute) -> bool:
    return isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")


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


def _binop(op: ast.operator, operands: list[ast.AST]) -> list[str]:
    label = f"BinOp:{type(op).__name__}"
    if not isinstance(op, _COMMUTATIVE):
        return [label, *_tokens(operands[0]), *_tokens(operands[1])]
    flat: list[ast.AST] = []  # (a + b) + c, a + (b + c) and c + b + a are one sum
    while operands:
        operand = operands.pop()
        if isinstance(operand, ast.BinOp) and type(operand.op) is type(op):
            operands += [operand.left, operand.right]
        else:
            flat.append(operand)
    return [label, f"#{len(flat)}", *_sorted_operands(flat)]


def _sorted_operands(operands: list[ast.AST]) -> list[str]:
    return [token for part in sorted(_tokens(o) for o in operands) for token in part]


def _statements(body: list) -> list:
    """``body`` without docstrings, constants standing alone (``...``) and ``pass``."""
    return [
        s
        for s in body
        if not (isinstance(s, ast.Pass) or (isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)))
    ]


def grams(function: ast.AST) -> frozenset[int]:
    """The hashed runs of ``NGRAM`` consecutive ``tokens`` within each statement of
    ``function`` (a shorter statement is one run; one of a single token says nothing). The
    hash is the same in every process: the student's process compares with the grader's."""
    found: set[int] = set()
    for line in tokens(function):
        found |= _line_grams(line)
    return frozenset(found)


def _line_grams(line: list[str]) -> set[int]:
    if len(line) < 2:
        return set()
    ids = [zlib.crc32(token.encode()) for token in line]
    return {hash(tuple(ids[i : i + NGRAM])) for i in range(max(1, len(ids) - NGRAM + 1))}


def _answer(origin: str, function: FunctionNode, given: frozenset[int]) -> Answer:
    """``function``'s Answer: its grams and the tokens of its statements, less what is given."""
    size = 0
    for line in tokens(function):
        if _line_grams(line) - given:
            size += len(line)
    return Answer(origin, grams(function) - given, size)


def functions_in(tree: ast.AST) -> list[FunctionNode]:
    """Every function in ``tree``, nested ones and methods included."""
    return [node for node in ast.walk(tree) if isinstance(node, FunctionNode)]


# -- the library's side ------------------------------------------------------------------


def answers_of(names: Iterable[str], solution: Path | None = None) -> Answers:
    """The ``Answers`` of the functions ``names`` (dotted: a function, or a class whose
    ``ANSWER_METHODS`` it defines) and of every function in ``solution``, the chapter's
    answer file, less the grams the exercise files give."""
    given = template_grams()
    functions = [pair for name in names for pair in _library_functions(name)]
    if solution is not None:
        tree = ast.parse(solution.read_bytes(), filename=str(solution))
        functions += [(f"{solution.name}:{node.name}", node) for node in functions_in(tree)]
    found: dict[frozenset[int], Answer] = {}
    for origin, node in functions:
        answer = _answer(origin, node, given)
        found.setdefault(answer.grams, answer)
    return Answers(tuple(answer for answer in found.values() if answer.grams), given)


@cache
def template_grams() -> frozenset[int]:
    """The grams of every function of the exercise files (the code students are given)."""
    given: set[int] = set()
    for path in sorted(TEMPLATES.glob("*.py")):
        tree = ast.parse(path.read_bytes(), filename=str(path))
        for node in functions_in(tree):
            given |= grams(node)
        for node in ast.walk(tree):  # (the code the docstrings' hints give, ``like this``)
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                given |= _hint_grams(node.value)
    return frozenset(given)


def _hint_grams(text: str) -> set[int]:
    found: set[int] = set()
    for hint in re.findall(r"``(.+?)``", text, flags=re.DOTALL):
        try:
            found |= grams(ast.parse(" ".join(hint.split())))
        except SyntaxError:
            continue  # (words, not code)
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


def similarity(student: frozenset[int], answer: Answer) -> float:
    """The share of ``answer``'s grams found in ``student``'s."""
    return len(answer.grams & student) / len(answer.grams)


def copies_in(tree: ast.AST, answers: Answers, only: Iterable[FunctionNode] | None = None) -> list[Copy]:
    """For each of ``answers`` that some function in ``tree`` (or of ``only``, functions of
    ``tree``) copies, the student's function most similar to it."""
    if not answers:
        return []
    reach = _Reach(functions_in(tree), answers)
    # Only answers the whole file holds enough of can be copied by one of its functions
    # (this keeps the check cheap on big modules compiled at run time).
    possible = [a for a in answers.answers if similarity(reach.everything, a) >= THRESHOLD]
    if not possible:
        return []
    found = similarities(tree, Answers(tuple(possible), answers.given), only, reach)
    copied = [copy for copy in found.values() if copy.similarity >= THRESHOLD]
    return sorted(copied, key=lambda copy: (copy.line, copy.answer.origin))


def similarities(
    tree: ast.AST, answers: Answers, only: Iterable[FunctionNode] | None = None, reach: _Reach | None = None
) -> dict[str, Copy]:
    """{answer's origin: the function of ``tree`` (or of ``only``) most similar to it}, for
    every answer some function shares a gram with."""
    reach = reach or _Reach(functions_in(tree), answers)
    found: dict[str, Copy] = {}
    for node in reach.functions if only is None else only:
        student = reach(node)
        for answer in answers.answers:
            score = similarity(student, answer)
            best = found.get(answer.origin)
            if score > 0 and (best is None or score > best.similarity):
                found[answer.origin] = Copy(node.lineno, node.name, answer, score)
    return found


class _Reach:
    """A function's grams, with those of the functions of its file that it names (as far
    as they are answers' grams: nothing else counts)."""

    def __init__(self, functions: list[FunctionNode], answers: Answers):
        self.functions = functions
        self.by_name: dict[str, list[FunctionNode]] = {}
        for node in functions:
            self.by_name.setdefault(node.name, []).append(node)
        relevant = frozenset().union(*(a.grams for a in answers.answers))
        self.own = {id(node): grams(node) & relevant for node in functions}
        self.everything = frozenset().union(*self.own.values())
        self.named: dict[int, list[FunctionNode]] = {}
        self.done: dict[int, frozenset[int]] = {}

    def __call__(self, function: FunctionNode) -> frozenset[int]:
        if id(function) not in self.done:
            seen, todo, union = {id(function)}, [function], set()
            while todo:
                node = todo.pop()
                union |= self.own[id(node)]
                for called in self._named(node):
                    if id(called) not in seen:
                        seen.add(id(called))
                        todo.append(called)
            self.done[id(function)] = frozenset(union)
        return self.done[id(function)]

    def _named(self, node: FunctionNode) -> list[FunctionNode]:
        if id(node) not in self.named:
            names = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
            names |= {n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)}
            self.named[id(node)] = [f for name in names & self.by_name.keys() for f in self.by_name[name]]
        return self.named[id(node)]


def copied_class(tree: ast.Module, name: str, answers: Answers) -> list[Copy]:
    """The copies among the ``GRADED_METHODS`` that the top-level class ``name`` defines,
    if each one it defines is a copy (with the helpers of the file it calls); else [] (a
    class that writes one of them itself is the student's, as a subclass that overrides
    one is). Its other methods, added or not, change nothing."""
    classes = [node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == name]
    methods = (
        [node for node in classes[-1].body if isinstance(node, FunctionNode) and node.name in GRADED_METHODS]
        if classes
        else []
    )
    found = copies_in(tree, answers, only=methods)
    copied = {copy.name for copy in found}
    return found if methods and all(method.name in copied for method in methods) else []


def is_a_copy(found: list[Copy]) -> bool:
    """Whether the copies ``copies_in`` found add up to a copied answer."""
    return sum(copy.answer.size for copy in found) >= MIN_COPIED_TOKENS


def describe_copies(found: list[Copy], file: str) -> str:
    """ "a copy of ptlab's own answer, with the names changed (trace_paths is 93% ptlab.x.f,
    at 07.py:12; ...)"."""
    places = "; ".join(
        f"{copy.name} is {copy.similarity:.0%} {copy.answer.origin}, at {file}:{copy.line}"
        for copy in found[:3]
    )
    more = f" and {len(found) - 3} more" if len(found) > 3 else ""
    return f"a copy of ptlab's own answer, with the names changed ({places}{more})"
