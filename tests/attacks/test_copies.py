"""Near-copies of ptlab's own answers (docs/grading-security.md): the library's functions
with the names changed and one or more edits that change nothing (a dead statement, a
swapped product, a moved assignment, a split return, an unused parameter, a no-op wrapper,
an extra method), built here from the library's source. Each is found by
``ptlab.untrusted.copies`` and named with its similarity; no honest answer of
``tests/exercises`` is; and a near-copy of chapter 6 scores 0 in a whole grading run."""

from __future__ import annotations

import ast
import inspect
import json
import re
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
        docstring = (
            isinstance(body, list)
            and body
            and isinstance(body[0], ast.Expr)
            and isinstance(body[0].value, ast.Constant)
            and isinstance(body[0].value.value, str)
        )
        if docstring:
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
        init="    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling='ggx'):\n        pass\n",
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
        body += [
            textwrap.indent(ast.unparse(ast.fix_missing_locations(function)), "    ")
            for method in methods
            for function in _edited(inspect.getsource(resolve(f"{library}.{method}")), edit)
        ]
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
    return {a.origin: found[a.origin].similarity if a.origin in found else 0.0 for a in answers.answers}


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
    first = found[0]
    message = describe_copies(found, f"{number:02d}.py")
    said = f"{first.name} is {first.similarity:.0%} {first.answer.origin}, at {number:02d}.py:{first.line}"
    assert said in message, message


def _not_in_rules(number: int) -> set[str]:
    """The library functions a near-copy holds that its chapter does not count as answers."""
    origins = {answer.origin for answer in chapter(number).rules.fingerprints.answers}
    spec = CHAPTERS[number]
    held = set(spec.get("functions", {}).values())
    if "cls" in spec:
        held |= {f"{spec['cls'][1]}.{m}" for m in spec["cls"][2]}
    return held - origins


@pytest.mark.parametrize("name", list(honest_files()))
def test_no_honest_answer_is_taken_for_a_copy(name):
    text = honest_files()[name]
    number = _number(name)
    answers = chapter(number).rules.fingerprints
    assert not is_a_copy(copies_in(ast.parse(text), answers)), name
    # Clear of the threshold: lowered by MARGIN it still finds no copy.
    sims = best_similarities(text, answers)
    near = [a for a in answers.answers if sims[a.origin] >= THRESHOLD - MARGIN]
    assert sum(a.size for a in near) < MIN_COPIED_TOKENS, [(a.origin, sims[a.origin]) for a in near]
    if number in (6, 9):  # (and ``ptlab grade``'s reading of the class)
        cls = {6: "Lambertian", 9: "GGXMetal"}[number]
        assert copied_class(ast.parse(text), cls, MATERIALS.fingerprints) == []


def test_the_threshold_lies_between_honest_answers_and_near_copies_with_its_margin():
    """The figures in ptlab/untrusted/copies.py's docstring: the most similar honest
    function to an answer that weighs enough to count alone, and the least similar
    near-copy of a copied answer."""
    honest = max(
        (sim, name, origin)
        for name, text in honest_files().items()
        for origin, sim in best_similarities(text, chapter(_number(name)).rules.fingerprints).items()
        if _size(_number(name), origin) >= MIN_COPIED_TOKENS / 2
    )
    copies = min(
        (copy.similarity, number, edit, copy.answer.origin)
        for number in CHAPTERS
        for edit in EDITS
        for copy in copies_in(ast.parse(near_copy(number, edit)), chapter(number).rules.fingerprints)
    )
    print(f"most similar honest answer: {honest}; least similar near-copy: {copies}")
    assert honest[0] + MARGIN <= THRESHOLD <= copies[0] - MARGIN, (honest, copies)


def _size(number: int, origin: str) -> int:
    return next(a.size for a in chapter(number).rules.fingerprints.answers if a.origin == origin)


def test_the_code_the_exercise_files_give_is_no_evidence_of_copying():
    from ptlab.untrusted.copies import template_grams

    given = template_grams()
    # The given helper of chapter 8 (``accelerator_for``) is in the library's answer too,
    # and a hint's code (``RenderSetup(...)``) in its docstring: neither counts.
    template = (TEMPLATES / "08_parallel.py").read_text()
    helper = next(f for f in functions_in(ast.parse(template)) if f.name == "accelerator_for")
    from ptlab.untrusted.copies import grams

    assert grams(helper)
    assert grams(helper) <= given
    hint = grams(ast.parse('RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width)'))
    assert hint <= given
    for number in range(1, 11):
        answers = chapter(number).rules.fingerprints
        assert all(not (answer.grams & given) for answer in answers.answers)
        # The exercise file as handed out (given code, hints, stubs) shares nothing with them.
        template = Path(chapter(number).template).read_text()
        assert set(best_similarities(template, answers).values()) == {0.0}, number


def test_a_class_is_a_copy_when_each_graded_method_it_writes_is_one():
    text = near_copy(6, "all at once")  # (with a method of the student's own added)
    tree = ast.parse(text)
    found = copied_class(tree, "Lambertian", MATERIALS.fingerprints)
    assert {copy.name for copy in found} == {"eval", "pdf", "sample"}
    assert is_a_copy(found)
    # One graded method of the student's own makes the class the student's, as overriding
    # one of an inherited class does (``ptlab grade`` lets a material inherit the others).
    own = ast.parse((EXERCISES / "06_right_uniform.py").read_text())
    own_eval = next(f for f in functions_in(own) if f.name == "eval")
    lambertian = next(c for c in tree.body if isinstance(c, ast.ClassDef) and c.name == "Lambertian")
    lambertian.body = [f for f in lambertian.body if getattr(f, "name", "") != "eval"] + [own_eval]
    assert copied_class(tree, "Lambertian", MATERIALS.fingerprints) == []


def test_a_near_copy_of_the_librarys_diffuse_is_a_working_material():
    # (so that the 0 of the grading run below is the copy's verdict, not a broken file)
    import numpy as np

    from ptlab.materials import Diffuse

    namespace: dict = {}
    exec(compile(near_copy(6, "all at once"), "06_diffuse.py", "exec"), namespace)
    copy, library = namespace["Lambertian"]((0.5, 0.6, 0.7)), Diffuse((0.5, 0.6, 0.7), sampling="cosine")
    rng = np.random.default_rng(0)
    wo, wi, n = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in rng.normal(size=(3, 64, 3)))
    u = rng.random((64, 2))
    for method, arguments in (("eval", (wo, wi, n)), ("pdf", (wo, wi, n)), ("sample", (wo, n, u))):
        assert np.allclose(getattr(copy, method)(*arguments), getattr(library, method)(*arguments)), method


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_near_copy_of_chapter_6_scores_nothing_in_a_grading_run(tmp_path, capsys):
    path = tmp_path / "06_diffuse.py"
    path.write_text(near_copy(6, "all at once"))
    assert main(["exercise", "check", "6", str(path), "--json", str(tmp_path / "r.json")]) == 1
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["score"] == 0, result
    out = capsys.readouterr().out
    assert "a copy of ptlab's own answer, with the names changed" in out
    assert re.search(r"(eval|pdf|sample) is \d+% ptlab\.materials\.Diffuse\.(eval|pdf|sample)", out), out
