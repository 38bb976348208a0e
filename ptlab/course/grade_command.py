"""``ptlab grade FILE.py:Name``: check a student's material, print the verdict.

    ptlab grade my_material.py:Microfacet --args '{"roughness": 0.3}' --plots plots/

``Name`` is a class (constructed with the ``--args`` JSON object as keyword arguments) or a
ready-made material object in the file: anything with ``eval``, ``pdf`` and ``sample``
(``ptlab.grading.material.as_material``). The file is imported, and every method of the
material runs, in a process of its own (``ptlab.course.sandbox``: as ``nobody`` when the grader
is root); the statistics and the verdict are computed here. The exit code is 0 when every
check passes, 1 when one fails (or the material is ptlab's own or a copy of it, or its
process hangs or ends), 2 when the file or the name cannot be loaded, or the import takes
longer than a minute (one line on stderr, no traceback).

``ptlab.cli`` wires it in with ``add_grade_arguments(subparser)`` and the handler
``run_grade(args)``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ptlab.course.sandbox import (
    IMPORT_TIME_LIMIT,
    GradeLoadError,
    ImportFailed,
    ProcessGuard,
    RefusedSubmission,
    RemoteFunction,
    Rules,
    StudentError,
    Submission,
    SubmissionFailed,
    import_nothing_from_here,
    library_answer,
    make_undumpable,
    sandbox,
    student_user,
    take_in,
)
from ptlab.course.sandbox.copies import copied_class, describe_copies, is_a_copy
from ptlab.course.sandbox.remote_material import as_student_material
from ptlab.course.sandbox.shown import print_verdict, relay, shown, shown_line
from ptlab.course.sandbox.student_user import add_student_user_argument
from ptlab.errors import PtlabError
from ptlab.grading.material import NotAMaterialError

#: Seconds one call of the material may take (10^6 directions take well under one).
CALL_TIME_LIMIT = 120.0
#: ptlab's own materials: their copies are not the student's, and the kit that ``ptlab grade``
#: runs a material with leaves them out (``ptlab.course.sandbox.kit``).
MATERIALS = Rules(
    answers=(
        "ptlab.materials.Diffuse",
        "ptlab.materials.Microfacet",
        "ptlab.materials.Mirror",
        "ptlab.materials.Dielectric",
    ),
    # (the Lambertian that chapter 7's checks hand to the student's code is one too)
    also_left_out=("ptlab.course.given",),
)


def add_grade_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add ``grade``'s arguments to ``parser`` (the ``ptlab grade`` subparser)."""
    parser.add_argument(
        "target", metavar="FILE.py:Name", help="the Python file and the material class (or object) in it"
    )
    parser.add_argument(
        "--args",
        default="{}",
        metavar="JSON",
        help="keyword arguments for the class, as a JSON object (default {})",
    )
    parser.add_argument(
        "--plots", metavar="DIR", help="write PNG pictures of a failed chi-square test into DIR"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed of the checks (default 0)")
    parser.add_argument(
        "--samples", type=int, default=1_000_000, help="directions sampled per wo (default 10^6)"
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=900.0,
        metavar="SECONDS",
        help="stop the material's process after this long (default 900; its "
        f"import may take {IMPORT_TIME_LIMIT:.0f}, one call "
        f"{CALL_TIME_LIMIT:.0f})",
    )
    add_student_user_argument(parser)
    return parser


def run_grade(args: argparse.Namespace) -> int:
    """Grade the material ``args`` name; print the report. Raises GradeLoadError (exit 2)."""
    from ptlab.grading import check_material

    if args.samples < 1000:
        raise GradeLoadError("--samples must be at least 1000")
    if not args.time_limit > 0:
        raise GradeLoadError(f"--time-limit {args.time_limit:g}: must be a positive number of seconds")
    path, name, keywords = parse_target(args.target, args.args)
    try:
        student_user(args.student_user)
    except PtlabError as error:
        raise GradeLoadError(str(error)) from None
    make_undumpable()
    import_nothing_from_here()
    try:
        taken = take_in(path)
    except RefusedSubmission as refused:
        raise GradeLoadError(str(refused)) from None
    copied = copied_class(taken.tree, name, MATERIALS.fingerprints)
    if is_a_copy(copied):
        copy = describe_copies(copied, shown(taken.name))
        print_verdict(f"{shown(args.target)}: FAILED: {shown(name)} is {copy}, not yours")
        return 1
    with ProcessGuard() as guard:
        try:
            with Submission(
                taken,
                guard,
                time_limit=args.time_limit,
                call_time_limit=CALL_TIME_LIMIT,
                on_output=relay("  | "),
                rules=MATERIALS,
                user=args.student_user,
            ) as submission:
                origin = _library_answer(submission, name)
                if origin is not None:
                    failure = f"{name} is ptlab's own answer ({origin}), not yours"
                else:
                    material = load_material(submission, name, keywords)
                    report = check_material(material, seed=args.seed, samples=args.samples)
                    failure = None
        except ImportFailed as error:
            raise GradeLoadError(shown_line(str(error))) from None
        except (SubmissionFailed, StudentError) as error:
            failure = error.describe() if isinstance(error, StudentError) else str(error)
    # Everything the file started has ended: only now is anything written.
    if failure is not None:
        print_verdict(f"{shown(args.target)}: FAILED: {shown_line(failure)}")
        return 1
    print_verdict(str(report))
    outside = sandbox.not_for_credit()
    if outside is not None:
        print_verdict(f"NOT FOR CREDIT: {outside}")
    if args.plots and not report.passed:
        _write_plots(report, args.plots)
    return 0 if report.passed else 1


def _write_plots(report, folder: str) -> None:
    from ptlab.grading import write_plots

    written = write_plots(report, folder)
    if written:
        print(f"wrote {len(written)} chi-square plots to {Path(folder).resolve()}")


def parse_target(target: str, arguments: str = "{}") -> tuple[Path, str, dict]:
    """``FILE.py:Name`` and the ``--args`` JSON as (path, name, keyword arguments)."""
    file, separator, name = target.rpartition(":")
    if not separator or not file or not name:
        raise GradeLoadError(f"{target!r}: expected FILE.py:Name")
    path = Path(file)
    if not path.is_file():
        raise GradeLoadError(f"{file}: no such file")
    try:
        keywords = json.loads(arguments)
    except json.JSONDecodeError as error:
        raise GradeLoadError(f"--args is not valid JSON: {error}") from None
    if not isinstance(keywords, dict):
        raise GradeLoadError("--args must be a JSON object, e.g. '{\"roughness\": 0.3}'")
    return path, name, keywords


def _library_answer(submission: Submission, name: str) -> str | None:
    """The ptlab answer that ``name`` is (``library_answer``), once the file is known to
    have it: a name missing is the user's mistake (exit 2), not code the grader cannot read."""
    if not hasattr(submission.module, name):
        raise GradeLoadError(f"{submission.path}: no class or object named {name!r}")
    return library_answer(submission.module, name)


def load_material(submission: Submission, name: str, keywords: dict):
    """The material ``name`` of the student's file (built with ``keywords`` if a class),
    as a full ``Material`` whose methods run in the student's process."""
    file = submission.path
    try:
        found = getattr(submission.module, name)
    except AttributeError:
        raise GradeLoadError(f"{file}: no class or object named {name!r}") from None
    if isinstance(found, RemoteFunction) and found.is_class:
        try:
            found = found(**keywords)
        except StudentError as error:
            raise GradeLoadError(f"{name}(**{keywords}) raised {error.type_name}: {error}") from None
    elif keywords:
        raise GradeLoadError(f"{name} is not a class, so --args cannot be applied")
    try:
        return as_student_material(found)
    except NotAMaterialError as error:
        raise GradeLoadError(f"{name} is not a material: {error}") from None
