"""Attacks that hand in ptlab's own answer as the student's (docs/grading-security.md): under
another name, compiled from the installed source, copied with the names changed, linked to,
or run in a fresh interpreter; and code the grader cannot read in the file, the student's
own or not (carried encoded and compiled at run time). Each earns nothing, with a message
that says why."""

from __future__ import annotations

import ast
import base64
import csv
import inspect
import os
import shutil
import sys
import textwrap

import numpy as np
import pytest

from attacks.hostile import SUBMISSIONS, assert_honest_failure
from ptlab.cli import main
from ptlab.course import chapter
from ptlab.course.grader import grade

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes
EXERCISES = SUBMISSIONS.parents[1] / "exercises"
#: Right answers of every shape an honest student's may take (tests/exercises/readable).
READABLE = EXERCISES / "readable"

#: What the static reading of the file says.
OWN_ANSWER = "ptlab's own answer"
#: What the student's process says when the code calls an answer: its kit has none.
NOT_IN_KIT = "is left out of the kit your code is graded with"
#: What a graded function whose code the grader cannot read in the file gets.
UNREADABLE = "the grader cannot read the code that runs for it in your file"
TEACHER = "this needs a teacher's look"


def test_the_librarys_function_wrapped_under_the_students_name_is_found_in_the_text(attack):
    result = grade(chapter(7), attack("07_direct_light_wrapper.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert result.score == 0, result.table()
    messages = {r.name: r.message for r in result.results}
    assert f"{OWN_ANSWER} (ptlab.integrators.path.direct_light)" in messages["direct light"]


def test_the_librarys_functions_under_an_alias_earn_nothing(attack):
    # The aliases are made with getattr of names the file builds at run time: the reading of
    # the text refuses that before anything runs (and the kit has none of these answers).
    result = grade(chapter(7), attack("07_alias.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert_honest_failure(
        result,
        "your file uses getattr() with a name built at run time when it is imported (07_path_tracing.py:9)",
    )
    assert_honest_failure(result, TEACHER)


def test_the_library_compiled_at_import_under_the_students_name_earns_nothing(attack):
    # The source the file reads is the kit's, whose answers are stubs; and what the file
    # compiles at import the grader cannot read in it.
    result = grade(chapter(7), attack("07_compiled_from_source.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert_honest_failure(result, "your file uses exec when it is imported (07_path_tracing.py:8)")
    assert_honest_failure(result, TEACHER)


def test_the_students_own_code_carried_encoded_earns_nothing_and_asks_for_a_teacher(attack):
    # Chapter 7's right answer compressed, base64-encoded and compiled at import: it had
    # full marks, and nothing in the file's text showed the code (nor could the pairs of
    # alike students compare it).
    result = grade(chapter(7), attack("07_encoded_own_code.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert_honest_failure(result, f"{UNREADABLE}, so the checks that use it earn nothing; {TEACHER}")
    for check in result.results:
        assert "uses exec when it is imported (07_path_tracing.py:" in check.message, result.table()


def test_a_right_answer_that_uses_exec_for_something_else_keeps_its_marks(tmp_path):
    # exec and eval in a helper that no graded function calls, and in the __main__ block:
    # the graded functions' code is all in the text.
    right = (EXERCISES / "07_right_own_code.py").read_text()
    path = tmp_path / "07_path_tracing.py"
    path.write_text(
        right
        + "\n\ndef _calculator(expression):\n    return eval(expression, {'__builtins__': {}})\n"
        + "\n\nif __name__ == '__main__':\n    exec('print(_calculator(\\'1 + 1\\'))')\n"
    )
    result = grade(chapter(7), path, timeout_scale=0.5)
    assert result.full_marks, result.table()


def _encoded_library(names: list[str]) -> str:
    """A student's file that carries the library's functions ``names`` (dotted) as base64 and
    compiles them at import: no trace of them in its text, none in the files it reads."""
    from ptlab.course.sandbox.copies import resolve

    source = "\n\n".join(textwrap.dedent(inspect.getsource(resolve(n))) for n in names)
    blob = base64.b64encode(source.encode()).decode()
    return (
        f"import base64\nfrom ptlab.integrators.path import *  # noqa\n"
        f"from ptlab.integrators.path import SurfaceHit, kept, leave_surface, sees\n"
        f"exec(compile(base64.b64decode({blob!r}), __file__, 'exec'))\n"
    )


def test_the_library_decoded_and_compiled_at_run_time_earns_nothing(tmp_path):
    path = tmp_path / "07_path_tracing.py"
    path.write_text(
        _encoded_library(
            [
                f"ptlab.integrators.path.{name}"
                for name in ("trace_paths", "direct_light", "scatter", "russian_roulette")
            ]
        )
    )
    result = grade(chapter(7), path, timeout_scale=0.5)
    assert_honest_failure(result, "compiling a copy of ptlab's own answer")


def _renamed(source: str, names: dict[str, str]) -> str:
    """``source`` with its identifiers renamed as a copier would (``names``), docstrings and
    comments dropped."""
    tree = ast.parse(textwrap.dedent(source))
    for node in ast.walk(tree):
        for field in ("id", "arg", "attr", "name"):
            value = getattr(node, field, None)
            if isinstance(value, str) and value in names:
                setattr(node, field, names[value])
        body = getattr(node, "body", None)
        if (
            isinstance(body, list)
            and body
            and isinstance(body[0], ast.Expr)
            and isinstance(body[0].value, ast.Constant)
        ):
            node.body = body[1:] or [ast.Pass()]
    return ast.unparse(tree)


def test_the_librarys_diffuse_copied_with_the_names_changed_earns_nothing(tmp_path, capsys):
    from ptlab.materials.diffuse import Diffuse

    copy = _renamed(
        inspect.getsource(Diffuse),
        {
            "Diffuse": "Lambertian",
            "albedo": "colour",
            "wo": "outgoing",
            "wi": "incoming",
            "n": "normal",
            "u": "random",
            "cos_theta_i": "cosine",
            "above": "visible",
            "density": "p",
            "scale": "factor",
            "SAMPLINGS": "WAYS",
            "sampling": "way",
        },
    )
    path = tmp_path / "06_diffuse.py"
    path.write_text(
        "import math\nimport numpy as np\nfrom ptlab.materials.base import Material\n"
        "from ptlab.sampling import cosine_hemisphere_around, uniform_hemisphere_around\n"
        "from ptlab.textures import Texture\nfrom ptlab.vectors import dot\n"
        "WAYS = ('cosine', 'uniform')\n\n" + copy
    )
    assert "class Lambertian(Material)" in path.read_text()
    result = grade(chapter(6), path, timeout_scale=0.5)
    assert_honest_failure(result, "a copy of ptlab's own answer, with the names changed")
    assert "eval is 100% ptlab.materials.Diffuse.eval, at 06_diffuse.py:" in result.results[0].message
    assert main(["grade", f"{path}:Lambertian", "--samples", "20000"]) == 1
    assert "a copy of ptlab's own answer" in capsys.readouterr().out


def test_a_link_to_the_librarys_answer_file_is_no_submission(tmp_path, capsys):
    link = tmp_path / "07_path_tracing.py"
    link.symlink_to(chapter(7).solution)
    result = grade(chapter(7), link, timeout_scale=0.5)
    assert_honest_failure(result, "is a symbolic link")
    # A folder that leads into the package, and the package's file itself, are refused too.
    (tmp_path / "inside").symlink_to(chapter(7).solution.parent)
    for path in (tmp_path / "inside" / "07_path_tracing.py", chapter(7).solution):
        assert_honest_failure(grade(chapter(7), path, timeout_scale=0.5), "part of ptlab itself")
    # A copy of the answer file is the library's re-exports: its own code is not the student's.
    shutil.copyfile(chapter(7).solution, tmp_path / "copied.py")
    assert grade(chapter(7), tmp_path / "copied.py", timeout_scale=0.5).score == 0
    # In a class's folder, a linked student is a row with no marks.
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "mallory.py").symlink_to(chapter(7).solution)
    os.symlink(chapter(7).solution.parent, folder / "trudy")
    assert main(["exercise", "grade-all", "7", str(folder), "--csv", str(tmp_path / "g.csv")]) == 0
    rows = list(csv.DictReader((tmp_path / "g.csv").open()))
    assert [(r["student"], r["score"]) for r in rows] == [("mallory", "0"), ("trudy", "0")]
    assert all("is a symbolic link" in r["first_failure"] for r in rows)


def test_the_librarys_answers_in_a_fresh_interpreter_are_out_of_reach(attack):
    result = grade(chapter(7), attack("07_pool_oracle.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert result.score == 0, result.table()
    messages = {r.name: r.message for r in result.results}
    # direct_light runs another Python (subprocess) and compiles the source it got: the grader
    # cannot read that; and a fresh interpreter in the sandbox sees the same kit: no answers.
    assert "direct_light: it uses subprocess (07_path_tracing.py:15)" in messages["direct light"]
    assert UNREADABLE in messages["direct light"]
    assert NOT_IN_KIT in messages["Cornell box"]


# -- the red team's files: library code carried encoded, or reached by a name built at run time

#: Each had full marks before the allowlist of the text and the recording of what runs:
#: {file: the name it is graded under}.
FOOLED = {
    "03_marshalled_globals_lookup.py": "03_whitted.py",
    "03_marshalled_in_library_wrapper.py": "03_whitted.py",
    "03_marshalled_in_slots.py": "03_whitted.py",
    "03_marshalled_partial_on_numpy.py": "03_whitted.py",
    "03_hook_off_then_exec.py": "03_whitted.py",
    "06_marshalled_globals_lookup.py": "06_diffuse.py",
    "07_marshalled_globals_lookup.py": "07_path_tracing.py",
}
#: The rest of them, which were caught already (by the reading of the text, the authorship
#: hook, or a failure of their own).
CAUGHT = dict.fromkeys(
    (
        "03_marshalled_code_swapped_in.py",
        "03_marshalled_in_defaults.py",
        "03_marshalled_bound_directly.py",
        "03_marshalled_weak_proxies.py",
        "03_exec_of_library_source.py",
        "03_exec_of_renamed_source.py",
        "03_exec_through_vars_builtins.py",
    ),
    "03_whitted.py",
)
#: Of these, those the authorship hook refuses as they are imported: they compile a copy of
#: ptlab's answers (``ptlab.course.sandbox.confinement``).
REFUSED_AT_IMPORT = (
    "03_hook_off_then_exec.py",  # (whose search for the hook's state finds nothing now)
    "03_exec_of_library_source.py",
    "03_exec_of_renamed_source.py",
    "03_exec_through_vars_builtins.py",
)
#: And the one that fails by itself: a weak proxy of a function looks like an iterator, and
#: its process cannot send it.
FAILS_BY_ITSELF = "03_marshalled_weak_proxies.py"
#: Their blobs are code objects of this Python (3.11) marshalled: another cannot load them.
MARSHALLED_HERE = sys.version_info[:2] == (3, 11)


@pytest.mark.parametrize("name", FOOLED)
def test_library_code_carried_encoded_earns_nothing_for_the_checks_it_serves(attack, name):
    result = grade(chapter(int(name[:2])), attack(name, FOOLED[name]), timeout_scale=0.5)
    if name in REFUSED_AT_IMPORT:  # (the hook it looked for among all objects is out of sight)
        assert_honest_failure(result, "compiling a copy of ptlab's own answer")
        return
    assert_honest_failure(result, UNREADABLE)
    assert_honest_failure(result, TEACHER)


def _first_call(number: int, module):
    """Call the first graded function of chapter ``number``'s file, on small inputs."""
    rng = np.random.default_rng(0)
    wo = rng.normal(size=(4, 3))
    n = np.tile([0.0, 0.0, 1.0], (4, 1))
    if number == 3:
        return module.reflect(wo, n)
    if number == 6:
        return module.Lambertian().eval(wo, wo, n)
    return module.russian_roulette(np.ones((4, 3), order="F"), 0.5, rng.random(4))


@pytest.mark.parametrize("name", {**FOOLED, **CAUGHT})
def test_what_runs_for_the_red_teams_files_is_not_the_files_own_code(tmp_path, name):
    """The second layer alone, with no reading of the text (the grader reads it only when a
    check asks for a graded name): calling a graded function runs code that is not the
    file's, and the call fails; or the file is refused as it is imported."""
    from ptlab.course.sandbox import ImportFailed, ProcessGuard, StudentError, Submission
    from ptlab.course.sandbox.submission import UnreadableCode

    if "marshalled" in name and not MARSHALLED_HERE:
        pytest.skip("code objects marshalled by Python 3.11")
    number = int(name[:2])
    path = tmp_path / {**FOOLED, **CAUGHT}[name]
    shutil.copyfile(SUBMISSIONS / name, path)
    with ProcessGuard() as guard:
        if name in REFUSED_AT_IMPORT:
            with pytest.raises(ImportFailed, match="compiling a copy of ptlab's own answer"):
                Submission(path, guard, time_limit=60, rules=chapter(number).rules)
            return
        with Submission(path, guard, time_limit=60, rules=chapter(number).rules) as submission:
            if name == FAILS_BY_ITSELF:
                with pytest.raises(StudentError, match="'function' object is not iterable"):
                    _first_call(number, submission.module)
                return
            with pytest.raises(UnreadableCode) as raised:
                _first_call(number, submission.module)
            assert raised.value.why.reason == "unreadable.not_the_text"


@pytest.mark.parametrize("name", sorted(path.name for path in READABLE.glob("*.py")))
def test_honest_answers_of_every_shape_keep_full_marks(tmp_path, name):
    """Right answers written as students do (a type test of types.FunctionType, find_spec to
    tell whether numba is installed, a large table, a dataclass material, decorators, eval in
    the __main__ block): readable, and graded as such."""
    found = chapter(int(name[:2]))
    path = tmp_path / found.solution.name
    shutil.copyfile(READABLE / name, path)
    result = grade(found, path, timeout_scale=0.5)
    assert result.full_marks, result.table()
