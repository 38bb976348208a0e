"""Copies of ptlab's own answers in a student's code, however they are dressed.

A copier changes what does not change the code: names, docstrings, annotations, the order
of independent statements, the operands of ``*``; writes an operator as a function
(``operator.mul(a, b)``, ``np.multiply(a, b)``, ``a.__mul__(b)``), an attribute through
``getattr``, a function through an alias; splits a function into helpers or inlines them;
and adds what does nothing (a dead ``x = 0``, ``if False: pass``, an unused parameter).
Plagiarism detectors for teaching (MOSS, JPlag) compare token streams after normalising
what such edits change, and so does this module: the student's file and the library's
answers are put back into one form (``ptlab.course.sandbox.canonical``) and compared by their
fingerprints (``ptlab.course.sandbox.fingerprints``: the hashed runs of their tokens, with
names, docstrings and layout left out).

* A student's function is compared with what it reaches: its own grams and those of the
  functions of the same file it names or had inlined, transitively (a no-op wrapper
  reaches the copy it wraps; the parts of a function split into helpers are reached
  together). Its similarity to an answer is the share of the answer's grams found there
  (padding the copy does not lower it); from ``THRESHOLD`` it copies that answer.
* What the exercise files dictate is no evidence. An answer's grams leave out the runs of
  tokens of the templates' code and of the code their hints quote between double
  backquotes; its weight (``Answer.size``) counts only its tokens that say what it
  computes (names of libraries, constants, operators: not variables, calls or layout)
  and that lie in none of those runs, in no expression written there, and in no call of
  something the exercise files name made with names and constants (``as_completed(
  futures)``). A formula (a function that returns one arithmetic expression of its
  parameters, ``alpha2 / (pi * d * d)``) weighs nothing: whoever follows the paper writes
  it so. A file (or a class, for ``ptlab grade``) is a copy when the answers it copies
  weigh ``MIN_COPIED_TOKENS`` together, each library function once, and the message says
  what it found and what it weighs (``describe_copies``).

The answers are the library's functions as they are today and as earlier releases wrote
them (``ptlab/course/sandbox/past_answers.json``, which ``scripts/past_answers.py`` makes from
git history): a student may copy last year's release or a fork. ``scripts/copy_detection.py``
measures the rate at which rewritten copies of every chapter's answers are found and how
close honest answers come (docs/grading-security.md has the figures);
``tests/attacks/test_copies.py`` checks them.

The grader looks for copies in the file's text (``copies_in``); the student's process
looks at everything compiled there at run time too (``ptlab.course.sandbox.confinement``), so
a copy that is assembled or decoded at run time is found as well.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import json
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

from ptlab.course.sandbox.canonical import canonical
from ptlab.course.sandbox.canonical_names import HELPER_SIZE, bindings, helper_of, inlined_helpers, returned
from ptlab.course.sandbox.fingerprints import (
    GIVEN_MARK,
    NGRAM,
    PLAIN,
    Tokenizer,
    canonical_grams,
    functions_in,
    run_hash,
    runs,
    unmarked,
)

# (re-exported: the detector's importers read the fingerprints from here)
from ptlab.course.sandbox.fingerprints import grams as grams
from ptlab.course.sandbox.fingerprints import tokens as tokens
from ptlab.course.sandbox.syntax_trees import FunctionNode, dotted_name, node_count, tree_copy

#: Share of a library function's grams from which a student's function is its copy: honest
#: answers stay under 0.66, copies above 0.95 (docs/grading-security.md, as measured).
THRESHOLD = 0.85
#: Weight of copied answers (``Answer.size``) from which a file (or a class) counts as a
#: copy: an honest file comes within 0.10 of THRESHOLD to 10 at most, chapter 4's answer
#: weighs 20, chapter 2's 16 (docs/grading-security.md, as measured).
MIN_COPIED_TOKENS = 18
#: The methods of a class that are its answer (the homework's three, and the weight).
ANSWER_METHODS = ("eval", "pdf", "sample", "sample_weight")
#: The methods ``ptlab grade`` grades: a class is a copy when each of these it writes is.
GRADED_METHODS = ("eval", "pdf", "sample")
#: The exercise files handed to students, whose code is not evidence of copying.
TEMPLATES = Path(__file__).resolve().parents[1] / "templates"
#: Earlier releases' answers (``scripts/past_answers.py`` writes it; graders only).
PAST_ANSWERS = Path(__file__).resolve().with_name("past_answers.json")
#: The attribute of a library function that says whether it is a small helper.
_SMALL = "ptlab_small_helper"


@dataclass(frozen=True)
class Answer:
    """One function of ptlab's answers, as ``grams`` sees it.

    Attributes:
        origin: where it is (``ptlab.integrators.path.trace_paths``), and for an earlier
            release's version, when (``... (as of 2026-11-27, 10d12b8)``).
        grams: its grams that no exercise file gives.
        size: its tokens that no exercise file gives (what a copy of it weighs).
    """

    origin: str
    grams: frozenset[int]
    size: int

    @property
    def function(self) -> str:
        """The library function this is a version of (``origin`` without its date)."""
        return self.origin.split(" (as of ")[0]


@dataclass(frozen=True)
class Answers:
    """The answers a student's code may not copy, and the grams the exercise files give."""

    answers: tuple[Answer, ...] = ()
    given: frozenset[int] = frozenset()
    #: (dotted name, canonical function) of the small helpers of the answers' modules: a
    #: copy that imports one rather than pasting it has it inlined all the same.
    helpers: tuple[tuple[str, FunctionNode], ...] = ()

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
        weight: what the copy weighs: the largest ``Answer.size`` of the versions of the
            answer it copies (its most similar version may be a lighter one).
    """

    line: int
    name: str
    answer: Answer
    similarity: float
    weight: int = 0


# -- what the exercise files give -----------------------------------------------------------


@dataclass(frozen=True)
class _Given:
    """What the exercise files give: the grams of their code and of the code their hints
    quote, and the ``run_hash`` of every expression written there."""

    grams: frozenset[int]
    expressions: frozenset[int]
    names: frozenset[str]


@cache
def _given() -> _Given:
    found_grams: set[int] = set()
    expressions: set[int] = set()
    names: set[str] = set()
    for path in sorted(TEMPLATES.glob("*.py")):
        tree = ast.parse(path.read_bytes(), filename=str(path))
        # A hint is read with the file's imports (``np.zeros`` in a hint is ``numpy.zeros``).
        imports = [s for s in tree.body if isinstance(s, ast.Import | ast.ImportFrom)]
        for part in (tree, *(ast.Module([*imports, *hint], []) for hint in _hints(tree))):
            form = canonical(part)
            for line in PLAIN.lines(form):
                found_grams |= {gram for _, _, gram in runs(line)}
                names |= {token for token in line if token.startswith(".")}
            for node in ast.walk(form):
                run = PLAIN.expression(node) if isinstance(node, ast.expr) else []
                if len(run) >= 2:
                    expressions.add(run_hash(run))
                    found_grams |= {gram for _, _, gram in runs(run) if len(run) < NGRAM}
    return _Given(frozenset(found_grams), frozenset(expressions), frozenset(names))


def template_grams() -> frozenset[int]:
    """The grams of the code of the exercise files and of the code their hints quote."""
    return _given().grams


def _hints(tree: ast.Module) -> Iterator[list[ast.stmt]]:
    """The statements of the code that ``tree``'s strings quote between double backquotes
    (a fragment such as ``[a:b]`` or ``.astype(t)`` read as applied to a name)."""
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Constant) and isinstance(node.value, str)):
            continue
        for hint in re.findall(r"``(.+?)``", node.value, flags=re.DOTALL):
            text = " ".join(hint.split())
            for attempt in (text, f"_{text}", f"{text} pass"):
                try:
                    yield ast.parse(attempt).body
                    break
                except SyntaxError:
                    continue  # (words, not code, or another fragment)


# -- the library's side ------------------------------------------------------------------


def answers_of(names: Iterable[str], solution: Path | None = None) -> Answers:
    """The ``Answers`` of the functions ``names`` (dotted: a function, or a class whose
    ``ANSWER_METHODS`` it defines) and of every function in ``solution``, the chapter's
    answer file, as they are and as earlier releases wrote them, less what the exercise
    files give."""
    names = tuple(names)
    helpers = library_helpers(names)
    functions = answer_sources(names, solution)
    functions += _past_functions({origin for origin, _, _ in functions})
    answers: dict[frozenset[int], Answer] = {}
    for origin, context, qualname in functions:
        answer = read_answer(origin, context, qualname, helpers)
        answers.setdefault(answer.grams, answer)
    kept = tuple(answer for answer in answers.values() if answer.grams)
    return Answers(kept, _given().grams, helpers)


def library_helpers(names: Iterable[str]) -> tuple[tuple[str, FunctionNode], ...]:
    """The small helpers (``_column``) of the modules that define the answers ``names``, as
    ``Answers.helpers`` holds them."""
    modules = sorted({_module_of(_unwrapped(resolve(name))) for name in names})
    return tuple(helper for module in modules for helper in _module_helpers(module))


@cache
def _module_helpers(module: str) -> tuple[tuple[str, FunctionNode], ...]:
    tree = _module_tree(module)
    found = []
    for node in tree.body:
        if isinstance(node, FunctionNode) and _is_small_helper(node):
            context = answer_context(tree, node.name, module)  # (not None: the module defines it)
            if context is not None:
                found.append((f"{module}.{node.name}", _defined(canonical(context, inline=False), node.name)))
    return tuple(found)


def _unwrapped(value):
    return inspect.unwrap(getattr(value, "__func__", value))


def _module_of(value) -> str:
    """The name of the module that defines the library's function or class ``value``."""
    module = inspect.getmodule(value)
    if module is None:
        raise ValueError(f"{value!r} is defined in no module")
    return module.__name__


def answer_sources(names: Iterable[str], solution: Path | None = None) -> list[tuple[str, ast.Module, str]]:
    """(origin, context, qualified name) of today's version of each answer ``answers_of``
    reads (its context as ``answer_context`` makes it)."""
    found = [source for name in names for source in _library_functions(name)]
    return found + (_solution_functions(solution) if solution is not None else [])


def read_answer(
    origin: str, context: ast.Module, qualname: str, helpers: Iterable[tuple[str, FunctionNode]] = ()
) -> Answer:
    """The Answer of the function ``qualname`` of ``context`` (``answer_context``): the grams
    of its canonical form (with ``helpers``, ``Answers.helpers``) and the tokens of its own
    code (its helpers not inlined: each counts once, as an answer of its own), less what
    the exercise files give; a formula (``_is_formula``) weighs nothing."""
    given = _given()
    function = _defined(canonical(context, helpers=helpers), qualname)
    kept = {gram for line in PLAIN.lines(function) for _, _, gram in runs(line)} - given.grams
    size = 0
    tokenizer = Tokenizer(given.expressions, given.names)
    for marked in tokenizer.lines(_defined(canonical(context, inline=False), qualname)):
        line = unmarked(marked)
        covered = [token.startswith(GIVEN_MARK) for token in marked]
        for start, end, gram in runs(line):
            if gram in given.grams:
                covered[start:end] = [True] * (end - start)
        if len(line) >= 2:
            size += sum(
                1 for token, given in zip(line, covered, strict=True) if not given and _is_content(token)
            )
    return Answer(origin, frozenset(kept), 0 if _is_formula(function) else size)


def _is_content(token: str) -> bool:
    """Whether ``token`` says what the code computes (a name of the library or of an import,
    a constant, an operator), not only how it is laid out (a variable ``N``, a call, a
    tuple, a loop, an assignment): only such tokens weigh (``Answer.size``)."""
    return token.startswith((".", "C:", "BinOp:", "UnaryOp:", "Compare:", "BoolOp:", "IfExp"))


#: What a formula may call besides operators: the numeric functions and constants of NumPy
#: and ``math`` (``_is_formula``).
FORMULA_NAMES = frozenset(
    {
        *("sqrt", "exp", "log", "log2", "log10", "abs", "power", "square", "sign", "copysign"),
        *("maximum", "minimum", "fmax", "fmin", "clip", "where", "floor", "ceil", "hypot"),
        *("sin", "cos", "tan", "arcsin", "arccos", "arctan", "arctan2", "asin", "acos", "atan", "atan2"),
        *("pi", "e", "inf", "float32", "float64", "astype"),
    }
)


def _is_formula(function: FunctionNode) -> bool:
    """Whether ``function`` (canonical) is a formula: its body comes down to returning one
    expression of operators, numbers, its parameters and ``FORMULA_NAMES`` (``alpha2 /
    (pi * d * d)``). Everyone who follows the paper writes such a function the same way:
    copying one is no evidence."""
    value = returned(function.body)
    if value is None:
        return False
    for node in ast.walk(value):
        if isinstance(node, ast.Attribute) and node.attr not in FORMULA_NAMES:
            return False
        kinds = (
            ast.expr | ast.expr_context | ast.operator | ast.unaryop | ast.cmpop | ast.boolop | ast.keyword
        )
        if not isinstance(node, kinds):
            return False
        if isinstance(node, ast.Lambda | ast.ListComp | ast.DictComp | ast.SetComp | ast.GeneratorExp):
            return False
    return True


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


def _library_functions(name: str) -> list[tuple[str, ast.Module, str]]:
    """(origin, context, qualified name) of the library's answer ``name`` (each answer
    method of a class), its context read from its module as ``answer_context`` says."""
    value = resolve(name)
    if inspect.isclass(value):
        methods = [(f"{name}.{m}", value.__dict__[m]) for m in ANSWER_METHODS if m in value.__dict__]
    else:
        methods = [(name, value)]
    found = []
    for origin, function in methods:
        function = _unwrapped(function)
        module = _module_of(function)
        context = answer_context(_module_tree(module), function.__qualname__, module)
        if context is not None:
            found.append((origin, context, function.__qualname__))
    return found


@cache
def _module_tree(module: str) -> ast.Module:
    return ast.parse(inspect.getsource(importlib.import_module(module)))


def _solution_functions(solution: Path) -> list[tuple[str, ast.Module, str]]:
    tree = ast.parse(solution.read_bytes(), filename=str(solution))
    found = []
    for qualname in _qualnames(tree):
        context = answer_context(tree, qualname)
        if context is not None:
            found.append((f"{solution.name}:{qualname.split('.')[-1]}", context, qualname))
    return found


def _qualnames(tree: ast.Module) -> list[str]:
    """The qualified names of ``tree``'s functions and of its classes' methods."""
    found = []
    for node in tree.body:
        if isinstance(node, FunctionNode):
            found.append(node.name)
        elif isinstance(node, ast.ClassDef):
            found += [f"{node.name}.{m.name}" for m in node.body if isinstance(m, FunctionNode)]
    return found


def _defined(tree: ast.Module, qualname: str) -> FunctionNode:
    """The function ``qualname`` (``trace_paths``, ``Diffuse.eval``) of ``tree``."""
    body = tree.body
    *owners, name = qualname.split(".")
    for owner in owners:
        body = next(n for n in body if isinstance(n, ast.ClassDef) and n.name == owner).body
    return next(n for n in body if isinstance(n, FunctionNode) and n.name == name)


def answer_context(tree: ast.Module, qualname: str, module: str | None = None) -> ast.Module | None:
    """What of the module ``tree`` its function ``qualname`` (``trace_paths``,
    ``Diffuse.eval``) is read with, as a copy of it would carry it: the module's imports,
    its aliases and small helpers (which ``canonical`` resolves and inlines), the function
    (in its class, with the class's small helpers), and, if ``module`` names the module, an
    import from it of the module's classes and constants that the function uses. None if
    the module has no such function. Docstrings are left out."""
    *owners, name = qualname.split(".")
    if len(owners) > 1:
        return None
    owner = (
        next((n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == owners[0]), None)
        if owners
        else None
    )
    body = owner.body if owner is not None else ([] if owners else tree.body)
    target = next((n for n in body if isinstance(n, FunctionNode) and n.name == name), None)
    if target is None:
        return None
    kept: list[ast.stmt] = [n for n in tree.body if n is not target and _is_context(n)]
    if owner is not None:
        methods: list[ast.stmt] = [
            n for n in owner.body if n is target or (isinstance(n, FunctionNode) and _is_small_helper(n))
        ]
        kept.append(ast.ClassDef(name=owner.name, bases=[], keywords=[], body=methods, decorator_list=[]))
    else:
        kept.append(target)
    if module:
        defined = {t.id for n in tree.body if isinstance(n, ast.Assign | ast.AnnAssign) for t in _targets(n)}
        defined |= {n.name for n in tree.body if isinstance(n, ast.ClassDef)}
        bound = {name for n in kept for name, _, _ in bindings(n, {})} | {
            t.id for n in kept if isinstance(n, ast.Assign) for t in _targets(n)
        }
        used = {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
        imported = sorted((used & defined) - bound)
        if imported:
            kept.insert(0, ast.ImportFrom(module, [ast.alias(n) for n in imported], 0))
    context = ast.Module(tree_copy(kept), [])
    for node in ast.walk(context):
        block = getattr(node, "body", None)
        if (
            isinstance(block, list)
            and block
            and isinstance(block[0], ast.Expr)
            and isinstance(block[0].value, ast.Constant)
        ):
            # (The node has a body, read above; ast.AST does not declare one.)
            node.body = block[1:] or [ast.Pass()]  # type: ignore[attr-defined]
    return ast.fix_missing_locations(context)


def _targets(node: ast.Assign | ast.AnnAssign) -> list[ast.Name]:
    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
    return [t for t in targets if isinstance(t, ast.Name)]


def _is_context(node: ast.stmt) -> bool:
    """Whether a module's statement ``node`` goes with any of its functions (``answer_context``)."""
    if isinstance(node, ast.Import | ast.ImportFrom):
        return True
    if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
        return isinstance(node.value, ast.Lambda) or dotted_name(node.value) is not None
    return isinstance(node, FunctionNode) and _is_small_helper(node)


def _is_small_helper(node: FunctionNode) -> bool:
    """Whether ``node`` is a small helper once in its canonical form (``if c: return a``
    then ``return b`` is one); worked out once per node."""
    if _SMALL not in node.__dict__:
        small = node_count(node) <= 2 * HELPER_SIZE  # (a bigger one is none, whatever dead code it drops)
        node.__dict__[_SMALL] = small and helper_of(canonical(node, inline=False)) is not None
    return node.__dict__[_SMALL]


@cache
def past_answers() -> tuple[dict, ...]:
    """The earlier releases' answers (``PAST_ANSWERS``): each ``origin`` (as ``answers_of``
    names it), ``qualname``, ``commit``, ``date`` and ``source`` (its ``answer_context``)."""
    if not PAST_ANSWERS.is_file():
        return ()
    return tuple(json.loads(PAST_ANSWERS.read_text(encoding="utf-8"))["answers"])


def _past_functions(origins: set[str]) -> list[tuple[str, ast.Module, str]]:
    """(origin, context, qualified name) of the earlier releases' versions of ``origins``."""
    return [
        (
            f"{past['origin']} (as of {past['date']}, {past['commit']})",
            ast.parse(past["source"]),
            past["qualname"],
        )
        for past in past_answers()
        if past["origin"] in origins
    ]


# -- the student's side -------------------------------------------------------------------


def similarity(student: frozenset[int], answer: Answer) -> float:
    """The share of ``answer``'s grams found in ``student``'s."""
    return len(answer.grams & student) / len(answer.grams)


def copies_in(tree: ast.AST, answers: Answers, only: Iterable[FunctionNode] | None = None) -> list[Copy]:
    """For each library function of which some function in ``tree`` (or of ``only``,
    functions of ``tree``) copies a version in ``answers``, the version copied most and the
    student's function most similar to it (``Copy.weight``: the heaviest version copied)."""
    if not answers:
        return []
    reach, candidates = _prepared(tree, answers, only)
    # Only answers the whole file holds enough of can be copied by one of its functions
    # (this keeps the check cheap on big modules compiled at run time).
    possible = [a for a in answers.answers if similarity(reach.everything, a) >= THRESHOLD]
    if not possible:
        return []
    found = similarities(tree, Answers(tuple(possible), answers.given), candidates, reach)
    versions: dict[str, list[Copy]] = {}
    for copied in found.values():
        if copied.similarity >= THRESHOLD:
            versions.setdefault(copied.answer.function, []).append(copied)
    # Of each library function, the version most like the student's, weighing what the
    # heaviest version it copies weighs.
    best = [
        replace(
            max(copies, key=lambda c: (c.similarity, c.answer.size)),
            weight=max(c.answer.size for c in copies),
        )
        for copies in versions.values()
    ]
    return sorted(best, key=lambda copied: (copied.line, copied.answer.origin))


def similarities(
    tree: ast.AST, answers: Answers, only: Iterable[FunctionNode] | None = None, reach: _Reach | None = None
) -> dict[str, Copy]:
    """{answer's origin: the function of ``tree`` (or of ``only``) most similar to it}, for
    every answer some function shares a gram with. (``reach``, with ``only`` taken from its
    functions, is what ``copies_in`` has made already.)"""
    if reach is None:
        reach, only = _prepared(tree, answers, only)
    found: dict[str, Copy] = {}
    for node in reach.functions if only is None else only:
        student = reach(node)
        for answer in answers.answers:
            score = similarity(student, answer)
            best = found.get(answer.origin)
            if score > 0 and (best is None or score > best.similarity):
                found[answer.origin] = Copy(node.lineno, node.name, answer, score)
    return found


def _prepared(
    tree: ast.AST, answers: Answers, only: Iterable[FunctionNode] | None
) -> tuple[_Reach, list[FunctionNode] | None]:
    """The ``_Reach`` of ``tree``'s canonical form, and its functions that ``only`` names."""
    functions = functions_in(canonical(tree, helpers=answers.helpers))
    if only is None:
        return _Reach(functions, answers), None
    wanted = {(node.lineno, node.col_offset, node.name) for node in only}
    return _Reach(functions, answers), [f for f in functions if (f.lineno, f.col_offset, f.name) in wanted]


class _Reach:
    """A function's grams, with those of the functions of its file that it names (as far
    as they are answers' grams: nothing else counts)."""

    def __init__(self, functions: list[FunctionNode], answers: Answers):
        self.functions = functions
        self.by_name: dict[str, list[FunctionNode]] = {}
        for node in functions:
            self.by_name.setdefault(node.name, []).append(node)
        relevant = frozenset().union(*(a.grams for a in answers.answers))
        self.own = {id(node): canonical_grams(node) & relevant for node in functions}
        self.everything = frozenset().union(*self.own.values())
        self.named: dict[int, list[FunctionNode]] = {}
        self.done: dict[int, frozenset[int]] = {}

    def __call__(self, function: FunctionNode) -> frozenset[int]:
        if id(function) not in self.done:
            seen, todo = {id(function)}, [function]
            union: set[int] = set()
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
            names: set[str] = set()
            for inner in ast.walk(node):
                if isinstance(inner, ast.Name):
                    names.add(inner.id)
                elif isinstance(inner, ast.Attribute):
                    names.add(inner.attr)
                elif isinstance(inner, FunctionNode):
                    names |= inlined_helpers(inner)
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


def copied_tokens(found: list[Copy]) -> int:
    """What the answers copied in ``found`` weigh together (``Answer.size``), each library
    function once (the heaviest of its versions found)."""
    heaviest: dict[str, int] = {}
    for copied in found:
        function = copied.answer.function
        heaviest[function] = max(heaviest.get(function, 0), copied.answer.size, copied.weight)
    return sum(heaviest.values())


def is_a_copy(found: list[Copy]) -> bool:
    """Whether the copies ``copies_in`` found add up to a copied answer."""
    return copied_tokens(found) >= MIN_COPIED_TOKENS


def describe_copies(found: list[Copy], file: str) -> str:
    """ "a copy of ptlab's own answer, with the names changed (120 tokens of it that the
    exercise file does not give: trace_paths is 93% ptlab.x.f, at 07.py:12; ...)": what was
    found, and what it weighs beyond the code the exercise file gives."""
    places = "; ".join(
        f"{copied.name} is {copied.similarity:.0%} {copied.answer.origin}, at {file}:{copied.line}"
        for copied in found[:3]
    )
    more = f" and {len(found) - 3} more" if len(found) > 3 else ""
    weight = copied_tokens(found)
    return (
        f"a copy of ptlab's own answer, with the names changed ({weight} tokens of it that the "
        f"exercise file does not give: {places}{more})"
    )
