"""``ptlab exercise start | check | render | list | docs | grade-all``: the exercises from the
command line.

ptlab exercise list                    # the chapters, and which are passed (and where)
ptlab exercise start 1                 # copies 01_cameras.py into this folder
ptlab exercise docs 1                  # chapter 1's page (--zh: in Chinese), its tutorial
ptlab exercise check 1 01_cameras.py   # the score table; exit 0 only on full marks
ptlab exercise check 1 01_cameras.py --json result.json
ptlab exercise render 3 03_whitted.py  # games101-hw5 through your code, the library's, the difference
ptlab exercise grade-all 1 submissions/ --csv grades.csv --workers 2   # a whole class
ptlab exercise inspect 7 07_path_tracing.py --pixel 12,20   # where your code first differs
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
from collections.abc import Callable
from pathlib import Path

from ptlab.atomic import check_writable_file, check_writable_folder, path_kind, write_atomically
from ptlab.course.messages import LANGUAGES
from ptlab.course.sandbox.shown import print_verdict, relay, shown
from ptlab.course.sandbox.student_user import add_student_user_argument, student_user
from ptlab.errors import PtlabError


def add_exercise_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``start``, ``check``, ``render``, ``list``, ``docs`` and ``grade-all`` to the
    ``ptlab exercise`` subparser."""
    actions = parser.add_subparsers(dest="action", required=True, parser_class=type(parser))
    # What check and grade-all share (a parent of their parsers).
    graded = argparse.ArgumentParser(add_help=False)
    graded.add_argument("chapter", metavar="NN", help="the chapter number")
    graded.add_argument(
        "--timeout-scale",
        type=float,
        default=1.0,
        metavar="X",
        help="multiply every check's time limit by X (slow machines)",
    )
    graded.add_argument(
        "--grading-seed",
        type=_seed,
        metavar="N",
        help="the seed the checks draw their inputs from (default: a fresh one each time, "
        "recorded in the table, the JSON and the CSV; give a recorded one to reproduce "
        "that verdict exactly)",
    )
    graded.add_argument(
        "--lang",
        choices=LANGUAGES,
        help="the language of the score table and its messages: en (English) or zh (中文) "
        "(default: the locale's: zh where the first of LC_ALL, LC_MESSAGES and LANG that is "
        "set starts with 'zh')",
    )
    add_student_user_argument(graded)

    start = actions.add_parser(
        "start",
        help="copy a chapter's exercise file to write your functions in",
        description="Copy chapter NN's exercise file (signatures, docstrings, hints) into DIR.",
    )
    start.add_argument("chapter", metavar="NN", help="the chapter number, e.g. 1 or 01")
    start.add_argument("dir", nargs="?", default=".", help="where to put it (default here)")
    start.add_argument("--force", action="store_true", help="overwrite an existing file")

    check = actions.add_parser(
        "check",
        parents=[graded],
        help="grade your functions for a chapter",
        description="Plug FILE's functions into the renderer in place of the library's own, "
        "run the chapter's checks, print a score table. FILE runs in a process of "
        "its own; what it prints is shown after '|'. Exit 0 only on full marks, 1 "
        "otherwise, 2 if FILE cannot be read.",
    )
    check.add_argument("file", metavar="FILE", help="your exercise file")
    check.add_argument(
        "--json",
        metavar="OUT",
        help="also write the result as JSON to OUT (removed at the start, written when every check is done)",
    )

    _add_render_arguments(actions)

    listing = actions.add_parser(
        "list",
        help="list the chapters and which you have passed",
        description="List the chapters with the best result of each (of the files checked for "
        "it, the one that still stands with the most points), from the records that "
        "'check' keeps beside the files it checked: in DIR (default: this folder) and its "
        "subfolders; with --all, also in the folders 'start' copied files into on this "
        "account (on a shared machine, other people's too).",
    )
    listing.add_argument("dir", nargs="?", help="where to look (default: here)")
    listing.add_argument(
        "--all", action="store_true", help="also look in every folder 'start' copied files into"
    )
    listing.add_argument(
        "--forget", metavar="DIR", help="stop remembering DIR, a folder 'start' copied files into"
    )

    docs = actions.add_parser(
        "docs",
        help="show a chapter's page, and where its pictures and tutorial are",
        description="Print chapter NN's page (Markdown), then where the page, its pictures and "
        "its tutorial script are on this machine, and the command that runs the "
        "tutorial. Without NN: the list of chapters.",
    )
    docs.add_argument("chapter", metavar="NN", nargs="?", help="the chapter number, e.g. 7")
    docs.add_argument("--zh", action="store_true", help="the Chinese page (中文)")
    docs.add_argument(
        "--path", action="store_true", help="print only the page's path (to open it in a Markdown viewer)"
    )

    _add_inspect(actions)

    batch = actions.add_parser(
        "grade-all",
        parents=[graded],
        help="grade a whole class's submissions (for teachers)",
        description="Grade every submission in DIR for chapter NN: each Python file, or each "
        "folder (holding the chapter's file, or one Python file), is one student. "
        "Each is graded in isolation, several at once; the CSV gets one row per "
        "student and is rewritten after each, so an interrupted run resumes "
        "(students already in the CSV are not graded again). Then the pairs of students "
        "whose files are alike (their normalised code, as MOSS compares it) are printed "
        "for a teacher to look at, and written to a CSV of their own.",
    )
    batch.add_argument("dir", metavar="DIR", help="the folder of submissions")
    batch.add_argument("--csv", metavar="OUT", help="the grades (default grades-NN.csv here)")
    batch.add_argument(
        "--alike",
        metavar="OUT",
        help="the pairs of students whose files are alike, most similar first (default: "
        "beside the grades, grades-NN-alike.csv)",
    )
    batch.add_argument(
        "--workers",
        type=int,
        default=max(1, (os.cpu_count() or 2) // 2),
        metavar="K",
        help="students graded at once (default: half the cores)",
    )


def _add_render_arguments(actions) -> None:
    """``ptlab exercise render``'s parser."""
    from ptlab.course import all_chapters
    from ptlab.course.side_by_side import DEFAULT_SPP, DEFAULT_WIDTH, TIME_LIMIT

    scenes = ", ".join(f"{c.number}: {c.render.scene}" for c in all_chapters() if c.render is not None)
    render = actions.add_parser(
        "render",
        help="render a scene with your functions, beside the library's render of it",
        description="Render a scene twice with the same seed: with the library's code, then "
        "with FILE's functions in its place (FILE runs in a process of its own, as 'check' "
        "runs it; what it prints is shown after '|'). Write DIR/NN-SCENE-yours.png, "
        "-library.png and -difference.png (red where yours is brighter, blue where darker) "
        "and print the share of pixels that differ. A right answer that draws the "
        "library's random numbers gives the library's picture; one that draws its own "
        f"differs by noise. The scenes by default: {scenes}. Exit 0 when the pictures are "
        "written, 1 if FILE's code failed, 2 on a bad option.",
    )
    render.add_argument("chapter", metavar="NN", help="the chapter number")
    render.add_argument("file", metavar="FILE", help="your exercise file")
    render.add_argument(
        "--scene", help="a built-in scene (ptlab scenes) or a scene file (default: the chapter's)"
    )
    render.add_argument(
        "--res",
        metavar="WxH",
        help=f"resolution, N or WxH (default {DEFAULT_WIDTH} wide at the scene's aspect ratio)",
    )
    render.add_argument("--spp", type=int, metavar="K", help=f"samples per pixel (default {DEFAULT_SPP})")
    render.add_argument(
        "--seed", type=_seed, default=0, metavar="N", help="the seed of both renders (default 0)"
    )
    render.add_argument(
        "--out", metavar="DIR", default=".", help="where to write the pictures (default here)"
    )
    render.add_argument(
        "--time-limit",
        type=float,
        default=TIME_LIMIT,
        metavar="S",
        help=f"seconds your code may take for its render (default {TIME_LIMIT:.0f})",
    )
    render.add_argument("--quiet", action="store_true", help="no progress bars")
    render.add_argument(
        "--lang", choices=LANGUAGES, help="the language of the messages (default: the locale's)"
    )
    add_student_user_argument(render)


def _add_inspect(actions) -> None:
    """``ptlab exercise inspect NN FILE --pixel X,Y`` (``ptlab.course.inspection``)."""
    inspect = actions.add_parser(
        "inspect",
        help="compare your functions with the library's at one pixel, vertex by vertex",
        description="Trace one pixel of the chapter's render check with the library's functions "
        "and with yours (run in a process of their own, as 'check' runs them), on the same "
        "samples, and print the first vertex where they differ, with both values. Chapters 3, "
        "7, 9 and 10; in 9 also the terms of your BRDF (D, G1, G2, F) beside the library's and "
        "whether what your sample draws follows your pdf, in 10 the densities your mis_weight "
        "was called with. Exit 0 if they agree, 1 if not, 2 if FILE cannot be read.",
    )
    inspect.add_argument("chapter", metavar="NN", help="the chapter number")
    inspect.add_argument("file", metavar="FILE", help="your exercise file")
    inspect.add_argument(
        "--pixel",
        required=True,
        metavar="X,Y",
        help="the pixel of the render check's image: X from the left, Y from the top",
    )
    inspect.add_argument("--seed", type=int, default=0, help="the render's seed (default 0)")
    inspect.add_argument(
        "--sampling",
        choices=("ggx", "hemisphere"),
        default="ggx",
        help="chapter 9: the GGXMetal sampling to compare (default ggx)",
    )
    inspect.add_argument("--json", metavar="OUT", help="also write the result as JSON to OUT")
    inspect.add_argument("--lang", choices=LANGUAGES, help="the language of the message: en or zh")
    add_student_user_argument(inspect)


def run_exercise(args: argparse.Namespace) -> int:
    """The handler of ``ptlab exercise``."""
    return {
        "start": _start,
        "check": _check,
        "render": _render,
        "list": _list,
        "docs": _docs,
        "grade-all": _grade_all,
        "inspect": _inspect,
    }[args.action](args)


def _inspect(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.inspection import INSPECTED, difference_dict, inspect_file, message
    from ptlab.course.messages import language, text
    from ptlab.inspector import parse_pixel
    from ptlab.rendering.settings import parse_resolution

    found = chapter(args.chapter)
    if found.number not in INSPECTED:
        chapters = ", ".join(str(n) for n in INSPECTED)
        raise PtlabError(f"chapter {found.number}: inspect compares the functions of chapters {chapters}")
    pixel = parse_pixel(args.pixel)
    options = INSPECTED[found.number].options
    width, height = parse_resolution(options["res"])
    if not (0 <= pixel[0] < width and 0 <= pixel[1] < height):
        raise PtlabError(f"--pixel {args.pixel}: chapter {found.number}'s render is {width}x{height}")
    path = Path(args.file)
    if path.suffix != ".py":
        raise PtlabError(f"{path}: expected a Python file (.py)")
    if args.json:
        _remove_old_result(Path(args.json))
    with language(args.lang):
        difference, failed = inspect_file(
            found.number, path, pixel, args.seed, args.sampling, user=args.student_user
        )
        line = (
            text("inspect.not_run", message=failed) if failed else message(difference, pixel, options["spp"])
        )
    print_verdict(line)
    if args.json:
        result = dict(
            chapter=found.number,
            file=str(path),
            pixel=list(pixel),
            seed=args.seed,
            first_difference=difference_dict(difference),
            error=failed,
        )
        content = json.dumps(result, indent=2) + "\n"

        def write(temporary: str) -> None:
            Path(temporary).write_text(content)

        write_atomically(args.json, write)
    return 0 if difference is None and failed is None else 1


def _start(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.progress import remember_folder

    found = chapter(args.chapter)
    folder = check_writable_folder(args.dir)
    target = folder / found.template.name
    if path_kind(target) == "folder":
        raise PtlabError(f"{target}: is a folder")
    if path_kind(target) is not None and not args.force:
        raise PtlabError(f"{target}: already exists (your work?); use --force to overwrite it")
    folder.mkdir(parents=True, exist_ok=True)

    def write(temporary: str) -> None:
        shutil.copyfile(found.template, temporary)

    write_atomically(target, write)
    remember_folder(folder)
    print(f"wrote {target.resolve()}")
    print(f"Chapter {found.number}: {found.title}. Write {', '.join(found.functions)}.")
    print(f"Read the chapter with: ptlab exercise docs {found.number}   (中文: --zh)")
    print(f"Check your work with: ptlab exercise check {found.number} {target}")
    return 0


def _docs(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.pages import docs_folder, page, tutorial

    found = chapter(args.chapter) if args.chapter is not None else None
    path = page(found, chinese=args.zh)
    if args.path:
        print(path)
        return 0
    lines = [path.read_text(encoding="utf-8").rstrip("\n"), f"\n-- this page: {path}"]
    if found is not None:
        lines += [
            f"-- its pictures: {docs_folder() / 'exercises'}",
            f"-- its tutorial, which renders them: python {tutorial(found)} --out DIR",
        ]
    print("\n".join(lines))  # a reader that stops early (head): see ptlab.cli.main
    return 0


def _timeout_scale(args) -> float:
    if not 0 < args.timeout_scale <= 100:
        raise PtlabError(f"--timeout-scale {args.timeout_scale}: must be in (0, 100]")
    return args.timeout_scale


def _seed(text: str) -> int:
    """``--grading-seed``'s value: an integer in [0, 2^63)."""
    try:
        seed = int(text)
    except ValueError:
        seed = -1
    if not 0 <= seed < 2**63:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer from 0 to 2^63 - 1")
    return seed


def _check(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.grader import grade
    from ptlab.course.inspect_command import graded_file
    from ptlab.course.progress import remember

    found = chapter(args.chapter)
    scale = _timeout_scale(args)
    path = Path(args.file)
    if path.suffix != ".py":
        raise PtlabError(f"{path}: expected a Python file (.py)")
    student_user(args.student_user)  # (a bad user: exit 2 before anything is removed)
    if args.json:
        _remove_old_result(Path(args.json))
    # A line per check as it finishes, on a terminal (a course's scripts get the table only).
    echo = (lambda line: print(line, file=sys.stderr)) if sys.stderr.isatty() else None
    with graded_file(path):  # (a failed render check suggests a command that names it)
        result = grade(
            found,
            path,
            timeout_scale=scale,
            echo=echo,
            on_output=relay("    | "),
            user=args.student_user,
            seed=args.grading_seed,
            lang=args.lang,
        )
    # grade() has ended every process of the student's code: nothing can change what follows.
    print_verdict(result.table())  # (a reader gone away changes nothing below, nor the exit code)
    if args.json:
        text = json.dumps(result.as_dict(), indent=2) + "\n"

        def write(temporary: str) -> None:
            Path(temporary).write_text(text)

        write_atomically(args.json, write)
    remember(result)
    return 0 if result.full_marks else 1


def _render(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.chapter import CheckFailed
    from ptlab.course.grader import table_message
    from ptlab.course.messages import language, text
    from ptlab.course.side_by_side import render_side_by_side

    found = chapter(args.chapter)
    out = _output(check_writable_folder, "--out", args.out)
    if not 0 < args.time_limit <= 86400:
        raise PtlabError(f"--time-limit {args.time_limit}: must be in (0, 86400] seconds")
    with language(args.lang):
        try:
            pictures = render_side_by_side(
                found,
                Path(args.file),
                args.scene,
                args.res,
                args.spp,
                args.seed,
                progress=not args.quiet,
                user=args.student_user,
                on_output=relay("    | "),
                say=None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True)),
                time_limit=args.time_limit,
            )
        except CheckFailed as failure:  # (one line, whatever the student's code said)
            print(f"{shown(Path(args.file))}: {table_message(str(failure))}", file=sys.stderr)
            return 1
        out.mkdir(parents=True, exist_ok=True)
        paths = pictures.write(out, f"{found.number:02d}-{pictures.scene}")
        print(pictures.summary())
        yours, library, difference = map(shown, paths)
        print(text("show.wrote", yours=yours, library=library, difference=difference))
    return 0


def _output(check: Callable[[str | Path], Path], option: str, path: str | Path) -> Path:
    """``check(path)`` (``check_writable_file`` or ``check_writable_folder``: before the
    work, which may take hours), its error naming ``option``."""
    try:
        return check(path)
    except PtlabError as error:
        raise PtlabError(f"{option} {error}") from None


def _remove_old_result(path: Path) -> None:
    """Check that the ``--json`` path can be written, and remove whatever is there before
    grading starts: a grader stopped midway then leaves no result at all, never an older
    one (or one written there by anybody else) that would pass for this grading's."""
    _output(check_writable_file, "--json", path)
    try:
        path.unlink(missing_ok=True)
    except OSError as error:
        raise PtlabError(f"--json {path}: cannot replace it: {error.strerror}") from None


def _list(args) -> int:
    from ptlab.course import all_chapters
    from ptlab.course.progress import (
        best,
        find_progress,
        folders_below,
        forget_folder,
        started_folders,
        status,
    )

    if args.forget is not None:
        forget_folder(Path(args.forget))
        print(f"forgot {shown(Path(args.forget))}: 'list --all' no longer looks there")
        return 0
    top = Path(args.dir) if args.dir is not None else Path.cwd()
    if not top.is_dir():
        raise PtlabError(f"{top}: no such folder")
    places = [f"{'this folder' if args.dir is None else shown(top)} and its subfolders"]
    folders = folders_below(top)
    if args.all:
        started = started_folders()
        places += [shown(f) for f in started]
        folders += started
    progress, records = find_progress(folders)
    print(
        f"looked in {'; '.join(places)}: "
        + (
            f"{len(records)} record{'s' if len(records) != 1 else ''} found"
            if records
            else "no results recorded ('ptlab exercise check' records them beside the file it checks"
            + ("" if args.all else "; --all also looks in the folders 'start' made")
            + ")"
        )
    )
    print(f"{'NN':2}  {'chapter':52}  {'status':26}  {'file':30}  write")
    for found in all_chapters():
        key = f"{found.number:02d}"
        entries = progress.get(key, [])
        state, where = "-", ""
        if entries:  # (of several files checked for the chapter, the best: see progress.best)
            entry, folder = best(entries, key)
            state = status(entry, folder, key)
            where = _shown(folder / str(entry.get("file", "")))
            where += f" (best of {len(entries)})" if len(entries) > 1 else ""
        print(f"{found.number:02d}  {found.title:52}  {state:26}  {where:30}  {', '.join(found.functions)}")
    return 0


def _shown(path: Path) -> str:
    """``path`` relative to here where it is below here, else as it is (shown: a student
    names the file)."""
    try:
        return shown(path.relative_to(Path.cwd().resolve()))
    except ValueError:
        return shown(path)


def _grade_all(args) -> int:
    from ptlab.course import chapter
    from ptlab.course.batch import alike_in_class, alike_lines, default_alike_path, grade_all, write_alike
    from ptlab.course.progress import check_private_state

    found = chapter(args.chapter)
    scale = _timeout_scale(args)
    if args.workers < 1:
        raise PtlabError(f"--workers {args.workers}: must be at least 1")
    csv_path = Path(args.csv or f"grades-{found.number:02d}.csv")
    alike_path = Path(args.alike) if args.alike else default_alike_path(csv_path)
    for option, path in (("--csv", csv_path), ("--alike", alike_path)):
        _output(check_writable_file, option, path)
    check_private_state()  # (where the grader records what it wrote: before anything is graded)
    if alike_path.absolute() == csv_path.absolute():
        raise PtlabError(f"--alike {alike_path}: the same file as --csv")
    rows = grade_all(
        found,
        Path(args.dir),
        csv_path,
        workers=args.workers,
        timeout_scale=scale,
        progress=sys.stderr.isatty(),
        user=args.student_user,
        seed=args.grading_seed,
        lang=args.lang,
    )
    full = sum(1 for row in rows.values() if str(row["score"]) == str(row["max_score"]))
    print(f"{len(rows)} students in {csv_path}: {full} with full marks")
    alike = alike_in_class(found, Path(args.dir))
    write_alike(alike_path, alike)
    for line in alike_lines(alike):
        print(line)
    count = len(alike.pairs)
    print(f"{count} pair{'' if count == 1 else 's'} of alike students in {alike_path}")
    return 0
