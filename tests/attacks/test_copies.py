"""Copies of ptlab's own answers, however they are dressed (docs/grading-security.md): every
chapter's answers as a copier hands them in (``corpus.py``), put through the mechanical
rewrites of ``rewriters.py``, are found and named, at the rate the project asks for; no
honest answer of ``tests/exercises`` comes near; what the exercise file dictates is no
evidence; a copy of an earlier release's answer is found too; and the rewrite the issue
measured (operators as ``operator`` calls, attributes through ``getattr``) scores nothing in
a grading run. ``scripts/copy_detection.py`` measures every rewrite of every copy; these
tests take a sample that runs in seconds: every rewrite of each chapter's answer file, and
two of each answer copied alone."""

from __future__ import annotations

import ast
import json
import re
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from attacks.corpus import (
    EXERCISES,
    Detection,
    chapter_of,
    chapters,
    copied_files,
    detection,
    honest_files,
    honest_scores,
    near_weight,
    public_names,
    weighty,
)
from attacks.hostile import SUBMISSIONS
from attacks.rewriters import REWRITES, rewritten
from ptlab.cli import main
from ptlab.course import chapter
from ptlab.course.grade_command import MATERIALS
from ptlab.course.sandbox.copies import (
    MIN_COPIED_TOKENS,
    THRESHOLD,
    Answers,
    canonical,
    copied_class,
    copied_tokens,
    copies_in,
    describe_copies,
    functions_in,
    grams,
    is_a_copy,
    template_grams,
)

#: The share of rewritten copies that must be found (the project's requirement).
REQUIRED_RATE = 0.95
#: Similarity kept clear of THRESHOLD on either side: by honest answers (below) and by the
#: answers a copy holds (above), for answers that weigh half of MIN_COPIED_TOKENS or more.
MARGIN = 0.10
#: Weight kept clear of MIN_COPIED_TOKENS by the answers an honest file comes within MARGIN
#: of THRESHOLD to (measured: 10 tokens, chapter 8 written from the hints).
WEIGHT_MARGIN = 6
#: The rewrite each answer copied alone is put through here (the answer files get all).
SAMPLED_REWRITES = ("all at once",)


@cache
def sampled_detections(number: int) -> tuple[Detection, ...]:
    """Chapter ``number``'s weighty copies put to the detector: its answer file through every
    rewrite, each answer copied alone through ``SAMPLED_REWRITES``."""
    found = []
    for copied in copied_files(number):
        if weighty(copied):
            rewrites = REWRITES if copied.name == "solution" else SAMPLED_REWRITES
            found += [detection(copied, rewrite) for rewrite in rewrites]
    return tuple(found)


@pytest.mark.parametrize("number", chapters())
def test_rewritten_copies_of_a_chapters_answers_are_found_at_the_required_rate(number):
    found = sampled_detections(number)
    missed = [(d.copied.name, d.rewrite, copied_tokens(list(d.found))) for d in found if not d.detected]
    assert len(found) - len(missed) >= REQUIRED_RATE * len(found), missed
    for result in found:
        if result.detected:  # (named: which function copies which answer, and how much)
            message = describe_copies(list(result.found), f"{number:02d}.py")
            first = result.found[0]
            where = f"{first.answer.origin}, at {number:02d}.py:{first.line}"
            assert f"{first.name} is {first.similarity:.0%} {where}" in message
            assert f"({copied_tokens(list(result.found))} tokens of it" in message


def test_the_chapters_that_a_copy_can_be_told_in_are_those_whose_answers_weigh_enough():
    """A copy is found from MIN_COPIED_TOKENS tokens beyond what the exercise file gives:
    chapter 2's Moller-Trumbore and chapter 10's heuristics are lighter (everyone writes them
    alike); every other chapter's answer file is heavy enough to be found when copied."""
    light = {number for number in chapters() if not any(weighty(c) for c in copied_files(number))}
    assert light == {2, 10}, light


def test_the_issues_rewrite_of_chapter_7_is_found():
    """The 35-line rewrite the issue measured: chapter 7's answer with its operators as
    ``operator`` calls and its attributes read through ``getattr`` (the best match fell to
    0.38 and the copy scored 12/12)."""
    solution = next(c for c in copied_files(7) if c.name == "solution")
    text = rewritten(solution.source, "operators and getattr", public_names(7))
    assert "getattr(operator, 'mul')(" in text
    assert "def trace_paths(" in text
    found = copies_in(ast.parse(text), chapter(7).rules.fingerprints)
    assert is_a_copy(found)
    copied = {c.answer.function for c in found}
    assert {f"ptlab.integrators.path.{name}" for name in ("scatter", "trace_paths", "direct_light")} <= copied
    assert min(c.similarity for c in found if c.weight >= MIN_COPIED_TOKENS / 2) >= THRESHOLD + MARGIN


@pytest.mark.parametrize(
    ("name", "answers"),
    [
        ("07_copy_through_a_dict_of_lambdas.py", ("scatter", "trace_paths", "direct_light")),
        ("06_copy_through_a_dict_of_lambdas.py", ("Diffuse.eval", "Diffuse.pdf")),
    ],
)
def test_a_copy_called_through_a_dict_of_lambdas_is_found(name, answers):
    """The red-team student's two scripts (NumPy respelt, then every operator called through
    a module-level dict of lambdas) had full marks: the table's lambdas are inlined where
    they are called and NumPy's spellings read as one, so the copy is found again."""
    text = (SUBMISSIONS / name).read_text()
    assert "OPS['Mult'](" in text
    assert "np.select([" in text
    found = copies_in(ast.parse(text), chapter(chapter_of(name)).rules.fingerprints)
    assert is_a_copy(found), [(c.name, c.similarity) for c in found]
    module = {7: "ptlab.integrators.path", 6: "ptlab.materials"}[chapter_of(name)]
    assert {f"{module}.{answer}" for answer in answers} <= {c.answer.function for c in found}


@pytest.mark.parametrize("name", list(honest_files()))
def test_no_honest_answer_is_taken_for_a_copy(name):
    text = honest_files()[name]
    number = chapter_of(name)
    assert not is_a_copy(copies_in(ast.parse(text), chapter(number).rules.fingerprints)), name
    # Clear of the thresholds: what it comes within MARGIN of copying weighs little.
    weight = near_weight([s for s in _honest_scores() if s.file == name], name, MARGIN)
    assert weight <= MIN_COPIED_TOKENS - WEIGHT_MARGIN, (name, weight)
    if number in (6, 9):  # (and ``ptlab grade``'s reading of the class)
        cls = {6: "Lambertian", 9: "GGXMetal"}[number]
        assert copied_class(ast.parse(text), cls, MATERIALS.fingerprints) == []


@cache
def _honest_scores():
    return tuple(honest_scores())


def test_the_threshold_lies_between_honest_answers_and_copies_with_its_margin():
    """Of the answers that weigh half of MIN_COPIED_TOKENS or more: the honest function most
    like one, and the copy least like the answer it copies (in every sampled rewrite)."""
    honest = max(
        (s.similarity, s.file, s.answer.origin)
        for s in _honest_scores()
        if s.answer.size >= MIN_COPIED_TOKENS / 2
    )
    copies = min(
        (c.similarity, d.copied.chapter, d.copied.name, d.rewrite, c.answer.origin)
        for number in chapters()
        for d in sampled_detections(number)
        for c in d.found
        if c.weight >= MIN_COPIED_TOKENS / 2
    )
    print(f"most similar honest answer: {honest}; least similar copy: {copies}")
    assert honest[0] + MARGIN <= THRESHOLD <= copies[0] - MARGIN, (honest, copies)


def test_what_the_exercise_file_dictates_is_no_evidence():
    """Chapter 8 written from its exercise file's hints is the library's answer nearly token
    for token (the hints spell it out): it is no copy, and what it shares with the answer
    weighs almost nothing: the template's code and hints, and the calls it names with the
    student's own variables, are not evidence."""
    text = (EXERCISES / "08_right_from_hints.py").read_text()
    answers = chapter(8).rules.fingerprints
    found = copies_in(ast.parse(text), answers)
    assert {c.answer.function for c in found} <= {
        "ptlab.rendering.jobs.make_tiles",
        "08_parallel.py:render_parallel",
    }
    assert copied_tokens(found) <= MIN_COPIED_TOKENS - WEIGHT_MARGIN
    weights = {a.origin: a.size for a in answers.answers}
    assert weights["08_parallel.py:render_parallel"] <= 6
    assert weights["ptlab.rendering.jobs.make_tiles"] <= 6
    # The given helper of chapter 8 (``accelerator_for``), and a hint's code in a docstring.
    given = template_grams()
    template = ast.parse(Path(chapter(8).template).read_text())
    helper = next(f for f in functions_in(canonical(template)) if f.name == "accelerator_for")
    assert grams(helper)
    assert grams(helper) <= given
    assert grams(ast.parse('RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width)')) <= given
    for number in chapters():
        answers = chapter(number).rules.fingerprints
        assert all(not (answer.grams & given) for answer in answers.answers), number
        # The exercise file as handed out (given code, hints, stubs) is not like any of them.
        template = Path(chapter(number).template).read_text()
        assert not copies_in(ast.parse(template), answers), number


def test_a_copy_of_an_earlier_releases_answer_is_found_and_dated():
    text = (SUBMISSIONS / "06_diffuse_of_an_earlier_release.py").read_text()
    answers = chapter(6).rules.fingerprints
    found = copies_in(ast.parse(text), answers)
    assert is_a_copy(found)
    message = describe_copies(found, "06_diffuse.py")
    assert re.search(
        r"eval is 100% ptlab\.materials\.Diffuse\.eval \(as of 2026-11-27, [0-9a-f]{7}\)", message
    )
    today = Answers(
        tuple(a for a in answers.answers if "(as of" not in a.origin), answers.given, answers.helpers
    )
    assert not is_a_copy(copies_in(ast.parse(text), today))  # (today's answers alone miss it)


def test_the_earlier_releases_answers_are_kept_as_source():
    """The data file holds sources (which the detector reads again whatever its
    normalisation), dated, for the answers that changed: chapter 7's path loop among them."""
    from ptlab.course.sandbox.copies import PAST_ANSWERS

    kept = json.loads(PAST_ANSWERS.read_text())["answers"]
    assert all(ast.parse(v["source"]) and re.fullmatch(r"\d{4}-\d\d-\d\d", v["date"]) for v in kept)
    origins = {v["origin"] for v in kept}
    assert {"ptlab.integrators.path.trace_paths", "ptlab.materials.Diffuse.eval"} <= origins


def test_a_class_is_a_copy_when_each_graded_method_it_writes_is_one():
    copied = next(c for c in copied_files(6) if c.name == "ptlab.materials.Diffuse")
    tree = ast.parse(rewritten(copied.source, "all at once", public_names(6) | {"Diffuse"}))
    found = copied_class(tree, "Diffuse", MATERIALS.fingerprints)
    assert {c.name for c in found} == {"eval", "pdf", "sample"}
    assert is_a_copy(found)
    # One graded method of the student's own makes the class the student's, as overriding
    # one of an inherited class does (``ptlab grade`` lets a material inherit the others).
    own = ast.parse((EXERCISES / "06_right_uniform.py").read_text())
    own_eval = next(f for f in functions_in(own) if f.name == "eval")
    diffuse = next(c for c in tree.body if isinstance(c, ast.ClassDef) and c.name == "Diffuse")
    diffuse.body = [f for f in diffuse.body if getattr(f, "name", "") != "eval"] + [own_eval]
    assert copied_class(tree, "Diffuse", MATERIALS.fingerprints) == []


@pytest.mark.parametrize("rewrite", [r for r in REWRITES if r != "as copied"])
def test_a_rewritten_copy_computes_what_the_library_does(rewrite):
    """The rewrites change how the code reads, not what it computes (so that a copy found
    is a copy that works): the library's Diffuse, rewritten, gives the library's values."""
    from ptlab.materials import Diffuse

    copied = next(c for c in copied_files(6) if c.name == "ptlab.materials.Diffuse")
    namespace: dict = {}
    exec(
        compile(rewritten(copied.source, rewrite, public_names(6) | {"Diffuse"}), "06.py", "exec"), namespace
    )
    copy, library = namespace["Diffuse"]((0.5, 0.6, 0.7), "uniform"), Diffuse((0.5, 0.6, 0.7), "uniform")
    rng = np.random.default_rng(0)
    wo, wi, n = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in rng.normal(size=(3, 64, 3)))
    u = rng.random((64, 2))
    for method, arguments in (("eval", (wo, wi, n)), ("pdf", (wo, wi, n)), ("sample", (wo, n, u))):
        assert np.allclose(getattr(copy, method)(*arguments), getattr(library, method)(*arguments)), method


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_issues_rewrite_of_chapter_7_scores_nothing_in_a_grading_run(tmp_path, capsys):
    solution = next(c for c in copied_files(7) if c.name == "solution")
    path = tmp_path / "07_path_tracing.py"
    path.write_text(rewritten(solution.source, "operators and getattr", public_names(7)))
    assert main(["exercise", "check", "7", str(path), "--json", str(tmp_path / "r.json")]) == 1
    result = json.loads((tmp_path / "r.json").read_text())
    assert result["score"] == 0, result
    out = capsys.readouterr().out
    assert "a copy of ptlab's own answer, with the names changed" in out
    assert re.search(
        r"\d+ tokens of it that the exercise file does not give: \w+ is \d+% ptlab\.integrators", out
    )
