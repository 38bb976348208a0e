"""``ptlab exercise start | check | list | docs``: the exercises from the command line.

    ptlab exercise list                    # the chapters, and which are passed here
    ptlab exercise start 1                 # copies 01_cameras.py into this folder
    ptlab exercise docs 1                  # chapter 1's page (--zh: in Chinese), its tutorial
    ptlab exercise check 1 01_cameras.py   # the score table; exit 0 only on full marks
    ptlab exercise check 1 01_cameras.py --json result.json
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
from pathlib import Path

from ptlab.errors import PtlabError


def add_exercise_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``start``, ``check``, ``list`` and ``docs`` to the ``ptlab exercise`` subparser."""
    actions = parser.add_subparsers(dest="action", required=True, parser_class=type(parser))
    start = actions.add_parser(
        "start", help="copy a chapter's exercise file to write your functions in",
        description="Copy chapter NN's exercise file (signatures, docstrings, hints) into DIR.")
    start.add_argument("chapter", metavar="NN", help="the chapter number, e.g. 1 or 01")
    start.add_argument("dir", nargs="?", default=".", help="where to put it (default here)")
    start.add_argument("--force", action="store_true", help="overwrite an existing file")

    check = actions.add_parser(
        "check", help="grade your functions for a chapter",
        description="Plug FILE's functions into the renderer in place of the library's own, "
                    "run the chapter's checks, print a score table. Exit 0 only on full "
                    "marks, 1 otherwise, 2 if FILE cannot be read.")
    check.add_argument("chapter", metavar="NN", help="the chapter number")
    check.add_argument("file", metavar="FILE", help="your exercise file")
    check.add_argument("--json", metavar="OUT", help="also write the result as JSON to OUT")
    check.add_argument("--timeout-scale", type=float, default=1.0, metavar="X",
                       help="multiply every check's time limit by X (slow machines)")

    listing = actions.add_parser(
        "list", help="list the chapters and which you have passed",
        description="List the chapters, with the score of the last check of each in DIR.")
    listing.add_argument("dir", nargs="?", default=".",
                         help="your exercise folder (default here)")

    docs = actions.add_parser(
        "docs", help="show a chapter's page, and where its pictures and tutorial are",
        description="Print chapter NN's page (Markdown), then where the page, its pictures and "
                    "its tutorial script are on this machine, and the command that runs the "
                    "tutorial. Without NN: the list of chapters.")
    docs.add_argument("chapter", metavar="NN", nargs="?", help="the chapter number, e.g. 7")
    docs.add_argument("--zh", action="store_true", help="the Chinese page (中文)")
    docs.add_argument("--path", action="store_true",
                      help="print only the page's path (to open it in a Markdown viewer)")


def run_exercise(args: argparse.Namespace) -> int:
    """The handler of ``ptlab exercise``."""
    return {"start": _start, "check": _check, "list": _list, "docs": _docs}[args.action](args)


def _start(args) -> int:
    from ptlab.exercises import chapter

    found = chapter(args.chapter)
    folder = Path(args.dir)
    if folder.exists() and not folder.is_dir():
        raise PtlabError(f"{folder}: exists and is not a folder")
    target = folder / found.template.name
    if target.exists() and not args.force:
        raise PtlabError(f"{target}: already exists (your work?); use --force to overwrite it")
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(found.template, target)
    print(f"wrote {target.resolve()}")
    print(f"Chapter {found.number}: {found.title}. Write {', '.join(found.functions)}.")
    print(f"Read the chapter with: ptlab exercise docs {found.number}   (中文: --zh)")
    print(f"Check your work with: ptlab exercise check {found.number} {target}")
    return 0


def _docs(args) -> int:
    from ptlab.exercises import chapter
    from ptlab.exercises.pages import docs_folder, page, tutorial

    found = chapter(args.chapter) if args.chapter is not None else None
    path = page(found, chinese=args.zh)
    if args.path:
        print(path)
        return 0
    lines = [path.read_text(encoding="utf-8").rstrip("\n"), f"\n-- this page: {path}"]
    if found is not None:
        lines += [f"-- its pictures: {docs_folder() / 'exercises'}",
                  f"-- its tutorial, which renders them: python {tutorial(found)} --out DIR"]
    try:
        print("\n".join(lines))
        sys.stdout.flush()
    except BrokenPipeError:     # the reader (head, a pager) stopped reading: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def _check(args) -> int:
    from ptlab.exercises import chapter
    from ptlab.exercises.grader import grade
    from ptlab.exercises.progress import remember

    found = chapter(args.chapter)
    if not 0 < args.timeout_scale <= 100:
        raise PtlabError(f"--timeout-scale {args.timeout_scale}: must be in (0, 100]")
    path = Path(args.file)
    if path.suffix != ".py":
        raise PtlabError(f"{path}: expected a Python file (.py)")
    # A line per check as it finishes, on a terminal (a course's scripts get the table only).
    echo = (lambda line: print(line, file=sys.stderr)) if sys.stderr.isatty() else None
    result = grade(found, path, timeout_scale=args.timeout_scale, echo=echo)
    print(result.table())
    if args.json:
        Path(args.json).write_text(json.dumps(result.as_dict(), indent=2) + "\n")
    remember(result)
    return 0 if result.full_marks else 1


def _list(args) -> int:
    from ptlab.exercises import all_chapters
    from ptlab.exercises.progress import read_record

    folder = Path(args.dir)
    if not folder.is_dir():
        raise PtlabError(f"{folder}: no such folder")
    record = read_record(folder)
    print(f"{'NN':2}  {'chapter':52}  {'status':18}  write")
    for found in all_chapters():
        entry = record.get(f"{found.number:02d}")
        if entry is None:
            status = "-"
        elif entry.get("full_marks"):
            status = f"passed ({entry['score']}/{entry['max_score']})"
        else:
            status = f"{entry.get('score')}/{entry.get('max_score')} points"
        print(f"{found.number:02d}  {found.title:52}  {status:18}  {', '.join(found.functions)}")
    return 0
