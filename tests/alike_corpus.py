"""What grade-all's pairs of alike students (``ptlab.course.alike``) are measured on: the
honest answers of ``tests/exercises`` and the library's own answers, chapter by chapter,
and copies of them as a student who copies another's file hands it in (names changed,
statements and functions reordered, dead code added). ``tests/course/test_alike.py`` and
``scripts/alike_scores.py`` use them."""

from __future__ import annotations

import ast
import inspect
import random
import textwrap
import tomllib
from dataclasses import dataclass
from pathlib import Path

from ptlab.course import all_chapters
from ptlab.course.sandbox.copies import resolve

EXERCISES = Path(__file__).parent / "exercises"
PATCHED = tomllib.loads((EXERCISES / "wrong_answers.toml").read_text(encoding="utf-8"))
#: Files of ``tests/exercises`` written from another of them, not apart from it (they share
#: its helpers line for line): the same author's, for the measurement.
DERIVED = {
    # _column, reflect and refract's steps are 03_right_own_code's, renamed.
    "03_wrong_eta_inverted.py": "03_right_own_code.py",
    # direct_light and scatter are 07_right_own_code's, a few names and lines changed.
    "07_right_own_random.py": "07_right_own_code.py",
    # "its pieces and its loop are right": 07_right_own_code's, and the fake beside them.
    "07_wrong_furnace_fake.py": "07_right_own_code.py",
    # 09_right_walter's file with sample rewritten (its first 38 lines are the same).
    "09_right_heitz.py": "09_right_walter.py",
}


@dataclass(frozen=True)
class Honest:
    """One honest submission.

    Attributes:
        label: what it is (a file of ``tests/exercises``, a wrong answer's name, "ptlab").
        author: whose work it is: submissions of one author are not independent.
        source: its text.
    """

    label: str
    author: str
    source: str


def honest(number: int) -> list[Honest]:
    """Chapter ``number``'s honest submissions: each file of ``tests/exercises``, each wrong
    answer of ``wrong_answers.toml`` (its right answer's author's), and the library's own
    answers (their sources, as one submission)."""
    found = [
        Honest(path.name, DERIVED.get(path.name, path.name), path.read_text(encoding="utf-8"))
        for path in sorted(EXERCISES.glob(f"{number:02d}_*.py"))
    ]
    for name, wrong in PATCHED.items():
        if name.startswith(f"{number:02d}_"):
            text = (EXERCISES / wrong["base"]).read_text(encoding="utf-8")
            for replacement in wrong["replace"]:
                text = text.replace(replacement["old"], replacement["new"])
            found.append(Honest(name, DERIVED.get(wrong["base"], wrong["base"]), text))
    (found_chapter,) = [c for c in all_chapters() if c.number == number]
    library = [textwrap.dedent(inspect.getsource(resolve(answer))) for answer in found_chapter.answers]
    found.append(Honest("ptlab", "ptlab", "\n\n".join(library)))
    return found


def copied(source: str, seed: int = 0) -> str:
    """``source`` as a copier hands it in: every name it binds changed (not those of its
    top-level functions and classes, which the grader asks for), its top-level definitions
    and independent statements reordered, docstrings and comments gone, dead code added."""
    tree = ast.parse(source)
    _Renamer(_bound_names(tree)).visit(tree)
    rng = random.Random(seed)
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(node, ast.FunctionDef | ast.ClassDef | ast.Module):
            _drop_docstring(node)
            _swap_independent(node.body, rng)
            if isinstance(node, ast.FunctionDef):
                node.body[:0] = ast.parse("unused = 0\nif False:\n    pass").body
    definitions = [s for s in tree.body if isinstance(s, ast.FunctionDef | ast.ClassDef)]
    rest = [s for s in tree.body if not isinstance(s, ast.FunctionDef | ast.ClassDef)]
    tree.body = rest + definitions[::-1]
    return ast.unparse(ast.fix_missing_locations(tree))


def _bound_names(tree: ast.Module) -> dict[str, str]:
    """{name: new name} for the variables, parameters and nested functions of ``tree``."""
    top = {s.name for s in tree.body if isinstance(s, ast.FunctionDef | ast.ClassDef)}
    imported = {
        alias.asname or alias.name.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Import | ast.ImportFrom)
        for alias in node.names
    }
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
        elif isinstance(node, ast.arg) and node.arg not in ("self", "cls"):
            names.add(node.arg)
        elif isinstance(node, ast.FunctionDef) and node.name.startswith("_"):
            names.add(node.name)
    return {name: f"v{k}" for k, name in enumerate(sorted(names - top - imported))}


class _Renamer(ast.NodeTransformer):
    def __init__(self, names: dict[str, str]):
        self.names = names

    def visit_Name(self, node: ast.Name) -> ast.Name:
        node.id = self.names.get(node.id, node.id)
        return node

    def visit_arg(self, node: ast.arg) -> ast.arg:
        node.arg = self.names.get(node.arg, node.arg)
        return node

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.FunctionDef:
        node.name = self.names.get(node.name, node.name)
        self.generic_visit(node)
        return node


def _drop_docstring(node) -> None:
    body = node.body
    if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and len(body) > 1:
        del body[0]


def _swap_independent(body: list[ast.stmt], rng: random.Random) -> None:
    """Swap neighbouring assignments that neither reads nor writes what the other writes,
    each pair with probability 1/2."""
    for k in range(len(body) - 1):
        first, second = body[k], body[k + 1]
        if not all(isinstance(s, ast.Assign) for s in (first, second)):
            continue
        if _written(first) & (_used(second) | _written(second)) or _written(second) & _used(first):
            continue
        if rng.random() < 0.5:
            body[k], body[k + 1] = second, first


def _written(statement: ast.stmt) -> set[str]:
    return {n.id for n in ast.walk(statement) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}


def _used(statement: ast.stmt) -> set[str]:
    return {n.id for n in ast.walk(statement) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
