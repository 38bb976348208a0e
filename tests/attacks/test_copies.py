"""Near-copies of ptlab's own answers (docs/grading-security.md): the library's functions
with the names changed and one or more edits that change nothing (a dead statement, a
swapped product, a moved assignment, a split return, an unused parameter, a no-op wrapper,
an extra method), built here from the library's source. Each is found by
``ptlab.untrusted.copies`` and named with its similarity; no honest answer of
``tests/exercises`` is; and a near-copy of chapter 6 scores 0 in a whole grading run."""

from __future__ import annotations

import ast
import inspect
import textwrap
import tomllib
from pathlib import Path

import pytest

from ptlab.cli import main
from ptlab.exercises import chapter
from ptlab.grading.cli import MATERIALS
from ptlab.untrusted.copies import (
    MIN_COPIED_TOKENS,
    THRESHOLD,
    Answers,
    copied_class,
    copies_in,
    describe_copies,
    functions_in,
    is_a_copy,
    resolve,
    similarities,
)

#: The honest population: students' own right answers and typical wrong ones.
EXERCISES = Path(__file__).parents[1] / "exercises"
TEMPLATES = Path(chapter(1).template).parent
#: Similarity kept clear of THRESHOLD on either side by every file measured here (the
#: measured extremes are in ptlab/untrusted/copies.py's docstring).
MARGIN = 0.10


# -- edits that change nothing ------------------------------------------------------------


def _local_names(function: ast.FunctionDef) -> set[str]:
    names = {a.arg for a in function.args.args + function.args.kwonlyargs} - {"self"}
    for node in ast.walk(function):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            names.add(node.id)
    return names


def renamed(function: ast.FunctionDef) -> ast.FunctionDef:
    """Every parameter and local variable renamed, docstrings and annotations dropped."""
    names = {name: f"my_{i}" for i, name in enumerate(sorted(_local_names(function)))}
    for node in ast.walk(function):
        if isinstance(node, ast.Name) and node.id in names:
            node.id = names[node.id]
        elif isinstance(node, ast.arg):
            node.arg, node.annotation = names.get(node.arg, node.arg), None
        elif isinstance(node, ast.FunctionDef):
            node.returns = None
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            if isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
                node.body = body[1:] or [ast.Pass()]
    return function


def _statement(text: str) -> list[ast.stmt]:
    return ast.parse(textwrap.dedent(text)).body


def _middle(function: ast.FunctionDef) -> int:
    return len(function.body) // 2


def dead_assignment(function: ast.FunctionDef) -> None:
    function.body[_middle(function) : _middle(function)] = _statement("unused = 0")


def dead_branch(function: ast.FunctionDef) -> None:
    function.body[_middle(function) : _middle(function)] = _statement("if False:\n    pass")


def unused_parameter(function: ast.FunctionDef) -> None:
    function.args.kwonlyargs.append(ast.arg("spare"))
    function.args.kw_defaults.append(ast.Constant(None))


def self_assignment(function: ast.FunctionDef) -> None:
    name = sorted(a.arg for a in function.args.args if a.arg != "self")[0]
    function.body[:0] = _statement(f"{name} = {name}")


def _reads(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def reordered(function: ast.FunctionDef) -> None:
    """Two adjacent independent assignments swapped (the first such pair at any depth); a
    function without one gets its last two statements' order kept and a dead one instead."""
    for node in ast.walk(function):
        body = getattr(node, "body", None)
        for i in range(len(body) - 1 if isinstance(body, list) else 0):
            first, second = body[i], body[i + 1]
            if isinstance(first, ast.Assign) and isinstance(second, ast.Assign):
                written = [_reads(t) for t in (first.targets[0], second.targets[0])]
                if not written[0] & _reads(second) and not written[1] & _reads(first):
                    body[i], body[i + 1] = second, first
                    return
    dead_assignment(function)


def split_returns(function: ast.FunctionDef) -> None:
    """``return f(x)`` written ``result = f(x); return result``, everywhere."""
    for node in ast.walk(function):
        for name in ("body", "orelse"):
            body = getattr(node, name, None)
            if isinstance(body, list):
                for i in reversed(range(len(body))):
                    if isinstance(body[i], ast.Return) and body[i].value is not None:
                        value = body[i].value
                        body[i : i + 1] = [
                            ast.Assign([ast.Name("result", ast.Store())], value, lineno=0),
                            ast.Return(ast.Name("result", ast.Load())),
                        ]


def commuted(function: ast.FunctionDef) -> None:
    """``a * b`` written ``b * a``, and ``a + b`` ``b + a``, everywhere."""
    for node in ast.walk(function):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult | ast.Add):
            node.left, node.right = node.right, node.left


EDITS = {
    "dead assignment": [dead_assignment],
    "dead branch": [dead_branch],
    "unused parameter": [unused_parameter],
    "self assignment": [self_assignment],
    "reordered": [reordered],
    "split return": [split_returns],
    "commuted": [commuted],
    "wrapped": [],  # (the wrapper is made by _file)
    "all at once": [dead_assignment, dead_branch, unused_parameter, reordered, split_returns, commuted],
}


# -- near-copies of whole exercise files ----------------------------------------------------

#: Per chapter: its imports, its functions {exercise name: library function} and its class
#: (exercise name, library class, the methods copied).
CHAPTERS = {
    3: dict(
        imports="import numpy as np\nfrom ptlab.vectors import dot\nfrom ptlab.scattering import _column\n",
        functions={
            "reflect": "ptlab.scattering.reflect",
            "refract": "ptlab.scattering.refract",
            "fresnel": "ptlab.scattering.fresnel_dielectric",
        },
    ),
    6: dict(
        imports=(
            "import math\nimport numpy as np\nfrom ptlab.materials.base import Material\n"
            "from ptlab.sampling import cosine_hemisphere_around, uniform_hemisphere_around\n"
            "from ptlab.vectors import dot\n"
        ),
        cls=("Lambertian", "ptlab.materials.Diffuse", ("eval", "pdf", "sample")),
        init="    def __init__(self, albedo=(0.8, 0.8, 0.8)):\n"
        "        self.albedo = np.asarray(albedo, dtype=np.float32)\n"
        "        self.sampling = 'cosine'\n",
    ),
    7: dict(
        imports="import numpy as np\nfrom ptlab.integrators.path import *  # noqa\n",
        functions={
            name: f"ptlab.integrators.path.{name}"
            for name in ("direct_light", "russian_roulette", "scatter", "trace_paths")
        },
    ),
    9: dict(
        imports=(
            "import math\nimport numpy as np\nfrom ptlab.materials.base import Material\n"
            "from ptlab.materials.microfacet import *  # noqa\n"
        ),
        functions={name: f"ptlab.materials.microfacet.{name}" for name in ("D", "G1", "G2", "Lambda")},
        cls=("GGXMetal", "ptlab.materials.microfacet.Microfacet", ("eval", "pdf", "sample")),
        init="    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling='ggx'):\n"
        "        pass\n",
    ),
}


def _edited(source: str, edit: str) -> list[ast.FunctionDef]:
    """The library function ``source`` renamed and edited as ``EDITS[edit]`` says; wrapped,
    it is a private helper and a function of its name that only calls it."""
    function = renamed(ast.parse(textwrap.dedent(source)).body[0])
    for step in EDITS[edit]:
        step(function)
    if edit != "wrapped":
        return [function]
    name, function.name = function.name, f"_{function.name}_impl"
    method = function.args.args[:1] and function.args.args[0].arg == "self"
    call = f"self.{function.name}" if method else function.name
    wrapper = _statement(
        f"def {name}({'self, ' if method else ''}*args, **kwargs):\n    return {call}(*args, **kwargs)"
    )[0]
    return [wrapper, function]


def near_copy(number: int, edit: str) -> str:
    """Chapter ``number``'s exercise file made of the library's answers, edited by ``edit``."""
    spec = CHAPTERS[number]
    parts = [spec["imports"]]
    for name, library in spec.get("functions", {}).items():
        for function in _edited(inspect.getsource(resolve(library)), edit):
            if not function.name.startswith("_"):
                function.name = name
            parts.append(ast.unparse(ast.fix_missing_locations(function)))
    if "cls" in spec:
        name, library, methods = spec["cls"]
        body = [spec["init"]]
        for method in methods:
            for function in _edited(inspect.getsource(resolve(f"{library}.{method}")), edit):
                body.append(textwrap.indent(ast.unparse(ast.fix_missing_locations(function)), "    "))
        if edit in ("all at once", "wrapped"):  # (an extra method of the student's own)
            body.append("    def describe(self):\n        return 'a material of my own'")
        parts.append(f"class {name}(Material):\n" + "\n\n".join(body))
    return "\n\n\n".join(parts) + "\n"


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
    files.update({f"template {p.name}": p.read_text() for p in sorted(TEMPLATES.glob("*.py"))})
    return files


def _number(name: str) -> int:
    return int(name.removeprefix("template ")[:2])


def best_similarities(text: str, answers: Answers) -> dict[str, float]:
    """{library answer: the similarity of the file's function most like it}."""
    found = similarities(ast.parse(text), answers)
    return {answer.origin: found[answer.origin].similarity if answer.origin in found else 0.0 for answer in answers.answers}


# -- the tests --------------------------------------------------------------------------------


@pytest.mark.parametrize("edit", list(EDITS))
@pytest.mark.parametrize("number", sorted(CHAPTERS))
def test_a_near_copy_of_the_librarys_answers_is_found_and_named(number, edit):
    text = near_copy(number, edit)
    ast.parse(text)  # (a file a student could hand in)
    found = copies_in(ast.parse(text), chapter(number).rules.fingerprints)
    assert is_a_copy(found), (edit, text)
    copied = {copy.answer.origin for copy in found}
    expected = set(CHAPTERS[number].get("functions", {}).values())
    if "cls" in CHAPTERS[number]:
        expected |= {f"{CHAPTERS[number]['cls'][1]}.{m}" for m in CHAPTERS[number]["cls"][2]}
    assert expected <= copied | _not_in_rules(number), (expected - copied, found)
    assert all(copy.similarity >= THRESHOLD + MARGIN for copy in found), found
    message = describe_copies(found, f"{number:02d}.py")
    assert f"{found[0].name} is {found[0].similarity:.0%} {found[0].answer.origin}, at {number:02d}.py:" in message


def _not_in_rules(number: int) -> set[str]:
    """The library functions a near-copy holds that its chapter does not count as answers."""
    origins = {answer.origin for answer in chapter(number).rules.fingerprints.answers}
    spec = CHAPTERS[number]
    held = set(spec.get("functions", {}).values())
    if "cls" in spec:
        held |= {f"{spec['cls'][1]}.{m}" for m in spec["cls"][2]}
    return held - origins
