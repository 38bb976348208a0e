"""Attacks that hand in ptlab's own answer as the student's (docs/grading-security.md): under
another name, compiled from the installed source, copied with the names changed, linked to,
or run in a fresh interpreter. Each earns nothing, with a message that says why."""

from __future__ import annotations

import ast
import base64
import csv
import inspect
import os
import shutil
import textwrap

import pytest

from attacks.hostile import assert_honest_failure
from ptlab.cli import main
from ptlab.exercises import chapter
from ptlab.exercises.grader import grade

pytestmark = [pytest.mark.slow, pytest.mark.subprocess]  # graders, in processes

#: What the static reading of the file says.
OWN_ANSWER = "ptlab's own answer"
#: What the student's process says when the code calls an answer: its kit has none.
NOT_IN_KIT = "is left out of the kit your code is graded with"


def test_the_librarys_function_wrapped_under_the_students_name_is_found_in_the_text(attack):
    result = grade(chapter(7), attack("07_direct_light_wrapper.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert result.score == 0, result.table()
    messages = {r.name: r.message for r in result.results}
    assert f"{OWN_ANSWER} (ptlab.integrators.path.direct_light)" in messages["direct light"]


def test_the_librarys_functions_under_an_alias_are_not_in_the_kit(attack):
    result = grade(chapter(7), attack("07_alias.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert result.score == 0, result.table()
    messages = {r.name: r.message for r in result.results}
    assert f"ptlab.integrators.path.direct_light {NOT_IN_KIT}" in messages["direct light"]
    assert f"ptlab.integrators.path.trace_paths {NOT_IN_KIT}" in messages["Cornell box"]
    assert f"ptlab.integrators.path.scatter {NOT_IN_KIT}" in messages["indirect bounce"]


def test_the_library_compiled_at_import_under_the_students_name_earns_nothing(attack):
    # The source the file reads is the kit's, whose answers are stubs.
    result = grade(chapter(7), attack("07_compiled_from_source.py", "07_path_tracing.py"), timeout_scale=0.5)
    assert_honest_failure(result, NOT_IN_KIT)


def _encoded_library(names: list[str]) -> str:
    """A student's file that carries the library's functions ``names`` (dotted) as base64 and
    compiles them at import: no trace of them in its text, none in the files it reads."""
    from ptlab.untrusted.copies import resolve

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
    # A fresh interpreter in the sandbox sees the same kit: no answers there either.
    assert NOT_IN_KIT in messages["direct light"]
    assert NOT_IN_KIT in messages["Cornell box"]
