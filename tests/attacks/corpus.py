"""The copy detector's corpus: every chapter's answers as a student who copies them would
hand them in, and the honest answers they must be told from.

A copier's file is the chapter's answer file (``ptlab/course/solutions/``) with every
import of what the chapter's kit leaves out replaced by the library's code of it (which
the kit no longer has), and each of the chapter's answers (``Chapter.answers``) copied
alone the same way: the library's definition, what it needs of the left-out code, and
imports of the rest. ``tests/attacks/rewriters.py`` then dresses them;
``scripts/copy_detection.py`` and ``tests/attacks/test_copies.py`` measure the detector
on both.
"""

from __future__ import annotations

import ast
import copy
import inspect
import tomllib
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from attacks.rewriters import rewritten
from ptlab.course import all_chapters, chapter
from ptlab.course.sandbox.copies import (
    MIN_COPIED_TOKENS,
    THRESHOLD,
    Answer,
    Copy,
    copied_tokens,
    copies_in,
    is_a_copy,
    resolve,
    similarities,
)
from ptlab.course.sandbox.kit import defined_as

#: The honest answers: students' own right answers and typical wrong ones.
EXERCISES = Path(__file__).parents[1] / "exercises"


@dataclass(frozen=True)
class Copied:
    """A file a copier would hand in.

    Attributes:
        chapter: the chapter it is graded for.
        name: what it copies: ``"solution"``, or an answer's dotted name.
        source: its text.
    """

    chapter: int
    name: str
    source: str


def chapters() -> list[int]:
    return [found.number for found in all_chapters()]


@cache
def copied_files(number: int) -> tuple[Copied, ...]:
    """Chapter ``number``'s answers as a copier hands them in: its answer file, and each
    of its answers alone (see the module docstring)."""
    found = chapter(number)
    paster = _Paster(found.rules.left_out)
    files = [Copied(number, "solution", paster.file(ast.parse(found.solution.read_text())))]
    for name in found.answers:
        module, _, attribute = name.rpartition(".")
        wanted = ast.parse(f"from {module} import {attribute}")
        files.append(Copied(number, name, _Paster(found.rules.left_out).file(wanted)))
    return tuple(files)


def public_names(number: int) -> frozenset[str]:
    """What the grader looks up in chapter ``number``'s file: the exercise file's functions
    and classes, and their methods (a rewrite keeps these names)."""
    tree = ast.parse(Path(chapter(number).template).read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
        if isinstance(node, ast.ClassDef):
            names |= {m.name for m in node.body if isinstance(m, ast.FunctionDef)}
    return frozenset(names | {"eval", "pdf", "sample", "sample_weight", "emission", "is_delta"})


class _Paster:
    """A module whose imports of left-out library code are replaced by that code.

    Args:
        left_out: the dotted names a chapter's kit leaves out (modules, classes, functions).
    """

    def __init__(self, left_out: tuple[str, ...]):
        self.left_out = {defined_as(name) for name in left_out}
        self.imports: dict[str, ast.stmt] = {}
        self.imported: dict[str, set[str]] = {}
        self.pasted: dict[str, ast.stmt] = {}
        self.pasting: set[str] = set()
        self.renamed: dict[str, str] = {}  # (library name: its name in the file, if another)
        self.taken: set[str] = set()

    def file(self, tree: ast.Module) -> str:
        """``tree``'s text with its imports of left-out code replaced by that code (under the
        name the import gives it; one the file defines itself is taken as ``library_NAME``)."""
        self.taken = {name for node in tree.body for name in _defined_names(node)}
        for statement in tree.body:
            if isinstance(statement, ast.ImportFrom):
                for alias in statement.names:
                    if alias.asname:
                        self.renamed[alias.name] = alias.asname
        body = []
        for statement in tree.body:
            if isinstance(statement, ast.ImportFrom) and (statement.module or "").startswith("ptlab"):
                kept = [a for a in statement.names if not self._paste_import(statement.module, a)]
                if kept:
                    body.append(ast.ImportFrom(statement.module, kept, 0))
            elif not _is_docstring(statement):
                body.append(statement)
        froms = [
            ast.ImportFrom(m, [ast.alias(n) for n in sorted(names)], 0) for m, names in self.imported.items()
        ]
        pasted = [_Renamed(self.renamed).visit(node) for node in self.pasted.values()]
        module = ast.Module([*self.imports.values(), *froms, *pasted, *body], [])
        return ast.unparse(ast.fix_missing_locations(module)) + "\n"

    def _paste_import(self, module: str, alias: ast.alias) -> bool:
        """Paste the definition ``from module import alias`` names, if it is left out."""
        dotted = defined_as(f"{module}.{alias.name}")
        value = resolve(f"{module}.{alias.name}")
        if not (inspect.isclass(value) or inspect.isfunction(value)) or not self._is_left_out(dotted):
            return False
        self._paste(value.__module__, value.__qualname__)
        return True

    def _is_left_out(self, dotted: str) -> bool:
        return any(dotted == name or dotted.startswith(name + ".") for name in self.left_out)

    def _paste(self, module: str, name: str) -> None:
        key = f"{module}.{name}"
        if key in self.pasted or key in self.pasting:
            return
        self.pasting.add(key)
        tree = _module_tree(module)
        node = copy.deepcopy(next(n for n in tree.body if getattr(n, "name", None) == name))
        if name in self.taken and name not in self.renamed:
            self.renamed[name] = f"library_{name}"
        node.name = self.renamed.get(name, name)
        for statement in tree.body:
            if isinstance(statement, ast.Import | ast.ImportFrom):
                self.imports.setdefault(ast.unparse(statement), statement)
        defined = _module_level(tree)
        local = {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
        local |= {a.arg for a in ast.walk(node) if isinstance(a, ast.arg)}
        for used in sorted({n.id for n in ast.walk(node) if isinstance(n, ast.Name)} - local):
            if used not in defined or used == name:
                continue
            if isinstance(defined[used], ast.FunctionDef | ast.ClassDef) and self._is_left_out(
                f"{module}.{used}"
            ):
                self._paste(module, used)
            else:
                self.imported.setdefault(module, set()).add(used)
        self.pasted[key] = node
        self.pasting.discard(key)


class _Renamed(ast.NodeTransformer):
    """The library's code with the names of what was pasted under another name changed."""

    def __init__(self, renamed: dict[str, str]):
        self.renamed = renamed

    def visit_Name(self, node: ast.Name) -> ast.Name:
        node.id = self.renamed.get(node.id, node.id)
        return node


@cache
def _module_tree(module: str) -> ast.Module:
    return ast.parse(inspect.getsource(resolve(module)))


def _module_level(tree: ast.Module) -> dict[str, ast.stmt]:
    """{name: the statement that defines it} for the functions, classes and assigned names of
    a module's top level."""
    found: dict[str, ast.stmt] = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            found[node.name] = node
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                if isinstance(target, ast.Name):
                    found[target.id] = node
    return found


def _defined_names(node: ast.stmt) -> list[str]:
    if isinstance(node, ast.FunctionDef | ast.ClassDef):
        return [node.name]
    targets = node.targets if isinstance(node, ast.Assign) else []
    return [t.id for t in targets if isinstance(t, ast.Name)]


def _is_docstring(statement: ast.stmt) -> bool:
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant)


# -- the honest population ------------------------------------------------------------------


def honest_files() -> dict[str, str]:
    """{name: text} of every honest file: the right and wrong answers of tests/exercises
    (the wrong_answers.toml patches applied), and the exercise templates as handed out."""
    files = {p.name: p.read_text() for p in sorted(EXERCISES.glob("[0-9][0-9]_*.py"))}
    for name, wrong in tomllib.loads((EXERCISES / "wrong_answers.toml").read_text()).items():
        text = files[wrong["base"]]
        for replacement in wrong["replace"]:
            text = text.replace(replacement["old"], replacement["new"])
        files[f"{name}.py"] = text
    templates = Path(chapter(1).template).parent
    files.update({f"template {p.name}": p.read_text() for p in sorted(templates.glob("*.py"))})
    return files


def chapter_of(name: str) -> int:
    """The chapter an honest file (as ``honest_files`` names it) is graded for."""
    return int(name.removeprefix("template ")[:2])


# -- measuring the detector on both -------------------------------------------------------


@dataclass(frozen=True)
class Detection:
    """A rewritten copy put to the detector.

    Attributes:
        copied: the copier's file before the rewrite.
        rewrite: the rewrite's name (``rewriters.REWRITES``).
        found: the copies ``copies_in`` found in the rewritten file.
    """

    copied: Copied
    rewrite: str
    found: tuple[Copy, ...]

    @property
    def detected(self) -> bool:
        return is_a_copy(list(self.found))


@cache
def weighty(copied: Copied) -> bool:
    """Whether ``copied``, as copied, weighs enough to count as a copy alone: a lighter one
    (a formula, or code the exercise file spells out) cannot be told from honest work."""
    return copied_tokens(copies_in(ast.parse(copied.source), chapter(copied.chapter).rules.fingerprints)) >= (
        MIN_COPIED_TOKENS
    )


def detection(copied: Copied, rewrite: str) -> Detection:
    """``copied`` put through ``rewrite`` and then to the detector."""
    text = rewritten(copied.source, rewrite, public_names(copied.chapter))
    return Detection(
        copied, rewrite, tuple(copies_in(ast.parse(text), chapter(copied.chapter).rules.fingerprints))
    )


@dataclass(frozen=True)
class HonestScore:
    """How like a library answer an honest file's most similar function is.

    Attributes:
        file: the honest file (``honest_files``' name).
        answer: the library answer.
        similarity: the share of its grams found in the file's most similar function.
    """

    file: str
    answer: Answer
    similarity: float


def honest_scores() -> list[HonestScore]:
    """Every honest file's similarity to every answer of its chapter it shares a gram with."""
    scores = []
    for name, text in honest_files().items():
        answers = chapter(chapter_of(name)).rules.fingerprints
        found = similarities(ast.parse(text), answers).values()
        scores.extend(HonestScore(name, copied.answer, copied.similarity) for copied in found)
    return scores


def near_weight(scores: list[HonestScore], file: str, below: float) -> int:
    """What the answers an honest file comes within ``below`` of the threshold to weigh
    (each library function once): how far it is from being taken for a copy."""
    heaviest: dict[str, int] = {}
    for score in scores:
        if score.file == file and score.similarity >= THRESHOLD - below:
            function = score.answer.function
            heaviest[function] = max(heaviest.get(function, 0), score.answer.size)
    return sum(heaviest.values())
