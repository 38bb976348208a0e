"""Write ``ptlab/course/sandbox/past_answers.json``: earlier releases' versions of every answer.

    python scripts/past_answers.py            # from this checkout's git history
    python scripts/past_answers.py --check    # exit 1 if the file is not what it would write

A student may copy last year's release or a fork rather than today's library, so the copy
detector (``ptlab/course/sandbox/copies.py``) compares a student's file with every version of an
answer that git history holds. For each answer of every chapter and of ``ptlab grade``
(``Chapter.answers``, ``ptlab.course.grade_command.MATERIALS``) and each function of the chapters'
answer files (``ptlab/course/solutions/``), this walks the commits that changed ptlab,
newest first, looks for the function by its qualified name in each file they changed (an
answer may have moved between modules: a function of the same name in another file than
today's counts only if it shares ``RELATED`` of its grams with a version kept already; a
method counts by its class's name), and keeps each version whose normalised grams differ
from today's and from every version kept before it, unless a copy of it would be found
through one of them (``REDUNDANT``).

It stores sources, not hashes, which would go stale when the normalisation changes: each
version's ``answer_context`` (its module's imports and small helpers, and the function),
which ``copies.answers_of`` reads again. Run it again after a release, and after changing
the normalisation (then ``--check`` says whether anything changed).
"""

from __future__ import annotations

import argparse
import ast
import inspect
import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from ptlab.course import all_chapters
from ptlab.course.grade_command import MATERIALS
from ptlab.course.sandbox.copies import (
    PAST_ANSWERS,
    Answer,
    answer_context,
    answer_sources,
    library_helpers,
    read_answer,
    resolve,
)

ROOT = Path(__file__).resolve().parents[1]
#: The share of a same-named function's grams that a kept version must hold for it to be a
#: version of that answer (and not another function that happens to share its name).
RELATED = 0.25
#: The share of a kept version's grams that a version must hold for a copy of it to be
#: found through the kept one (``THRESHOLD`` and a margin).
REDUNDANT = 0.95
#: Folders of ptlab whose functions are never answers (the exercise files, the graders).
NOT_ANSWERS = ("ptlab/course/templates/", "ptlab/course/sandbox/", "ptlab/grading/")


@dataclass
class Wanted:
    """An answer whose earlier versions are looked for.

    Attributes:
        origin: its name in ``Answers`` (``ptlab.materials.Diffuse.eval``).
        qualname: its qualified name in its module (``Diffuse.eval``).
        path: for a function of an answer file, that file (relative to the root); else
            None (a library function, looked for in every module).
        kept: the versions kept so far (today's first).
        home: for a library function, the file that defines it today.
    """

    origin: str
    qualname: str
    path: str | None
    kept: list[Answer]
    home: str | None = None

    def has(self, version: Answer) -> bool:
        """Whether a copy of ``version`` is found through a version kept already: one that
        shares ``REDUNDANT`` of its grams and weighs as much (an answer that changed a
        little keeps one version)."""
        return any(
            len(kept.grams & version.grams) >= REDUNDANT * len(kept.grams) and kept.size >= version.size
            for kept in self.kept
        )


def answer_names() -> list[str]:
    """The dotted names of every chapter's answers and of ``ptlab grade``'s."""
    return [*MATERIALS.answers, *(name for chapter in all_chapters() for name in chapter.answers)]


def wanted_answers(helpers) -> list[Wanted]:
    """Every answer whose versions are kept, with today's version."""
    found: dict[str, Wanted] = {}
    for chapter in all_chapters():
        for origin, context, qualname in answer_sources((), chapter.solution):
            path = str(chapter.solution.relative_to(ROOT))
            found[origin] = Wanted(origin, qualname, path, [read_answer(origin, context, qualname, helpers)])
    for origin, context, qualname in answer_sources(answer_names()):
        home = str(Path(inspect.getsourcefile(resolve(origin))).resolve().relative_to(ROOT))
        today = read_answer(origin, context, qualname, helpers)
        found.setdefault(origin, Wanted(origin, qualname, None, [today], home))
    return list(found.values())


def _git(*arguments: str) -> str:
    return subprocess.run(
        ["git", "-C", str(ROOT), *arguments], check=True, capture_output=True, text=True
    ).stdout


def changed_files() -> list[tuple[str, str, str]]:
    """(commit, date, path) of every Python file of ptlab that a commit changed, newest first."""
    found, commit, date = [], "", ""
    for line in _git("log", "--format=@%H %cs", "--name-only", "--", "ptlab").splitlines():
        if line.startswith("@"):
            commit, date = line[1:].split()
        elif line.endswith(".py") and not line.startswith(NOT_ANSWERS):
            found.append((commit, date, line))
    return found


def module_name(path: str) -> str:
    return path.removesuffix(".py").removesuffix("/__init__").replace("/", ".")


def past_versions(wanted: list[Wanted], helpers) -> list[dict]:
    """The versions to keep (see the module docstring), newest first."""
    by_name: dict[str, list[Wanted]] = {}
    for answer in wanted:
        by_name.setdefault(answer.qualname.split(".")[0], []).append(answer)
    kept = []
    for commit, date, path in changed_files():
        try:
            tree = ast.parse(_git("show", f"{commit}:{path}"))
        except (subprocess.CalledProcessError, SyntaxError, ValueError):
            continue  # (deleted by that commit, or not Python that parses today)
        defined = {getattr(node, "name", None) for node in tree.body}
        for answer in (a for name in defined & by_name.keys() for a in by_name[name]):
            if answer.path is not None and answer.path != path:
                continue
            context = answer_context(tree, answer.qualname, None if answer.path else module_name(path))
            if context is None:
                continue
            version = read_answer(answer.origin, context, answer.qualname, helpers)
            if not version.grams or answer.has(version):
                continue
            # (a method of its class, or a function of its file, is a version of it; a
            # function of the same name elsewhere must show that it is one)
            elsewhere = answer.path is None and path != answer.home and "." not in answer.qualname
            grams = version.grams
            if elsewhere and not any(len(grams & k.grams) >= RELATED * len(grams) for k in answer.kept):
                continue
            answer.kept.append(version)
            source = ast.unparse(context)
            kept.append(
                {
                    "origin": answer.origin,
                    "qualname": answer.qualname,
                    "commit": commit[:7],
                    "date": date,
                    "source": source,
                }
            )
    return kept


def contents() -> str:
    helpers = library_helpers(answer_names())
    versions = past_versions(wanted_answers(helpers), helpers)
    versions.sort(key=lambda v: (v["origin"], v["date"], v["commit"]), reverse=True)
    about = (
        "Earlier versions of ptlab's answers (ptlab/course/sandbox/copies.py), by scripts/past_answers.py."
    )
    return json.dumps({"about": about, "answers": versions}, indent=1, ensure_ascii=False) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if the file is not what this would write"
    )
    args = parser.parse_args()
    text = contents()
    if args.check:
        same = PAST_ANSWERS.is_file() and PAST_ANSWERS.read_text(encoding="utf-8") == text
        state = "up to date" if same else "out of date: run scripts/past_answers.py"
        print(f"{PAST_ANSWERS.relative_to(ROOT)}: {state}")
        return 0 if same else 1
    PAST_ANSWERS.write_text(text, encoding="utf-8")
    count = text.count('"origin"')
    print(f"wrote {count} earlier versions of ptlab's answers to {PAST_ANSWERS.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
