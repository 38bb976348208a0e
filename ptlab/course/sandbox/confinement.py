"""The authorship hook: a copy of ptlab's answers compiled at run time is refused.

The sandbox (``ptlab.course.sandbox.sandbox``) decides what the student's process can reach;
this hook decides nothing of that. It answers another question, authorship, for code the
grader cannot read in the file: Python raises an audit event before it compiles code
(PEP 578, ``sys.addaudithook``), and the hook refuses code that holds a copy of the
chapter's answers (``ptlab.course.sandbox.copies``), however it was assembled (decoded from
base64, downloaded before the grading, built from strings).

It is a second layer, not a defence: it lives in the process it watches, whose code can
take it apart (PEP 578 says as much), and bytecode imported from a ``.pyc`` raises no
compile event. Its state is in a closure, not in the attributes of an object that a look
at every object (``gc.get_objects()``) would hand out by its class's name; and the reading
of the file's text (``ptlab.course.sandbox.uses``) refuses ``gc``, closures' cells and every
other way there. What it guards is written in docs/grading-security.md.
"""

from __future__ import annotations

import ast
import os
import sys
import threading

from ptlab.course.sandbox.copies import Answers, copies_in, describe_copies, is_a_copy


class Refused(PermissionError):  # noqa: N818 (a rule, not an error of the code)
    """What the student's code tried is not allowed while it is graded."""


def confine(answers: Answers) -> None:
    """Add the hook, if there are answers to look for (none when grading ptlab's own file)."""
    if answers:
        sys.addaudithook(_compiled_copies(answers))


def _compiled_copies(answers: Answers):
    """The audit hook (called for every event, so it returns at once for the others)."""
    parsing: set[int] = set()  # (the threads parsing in the hook: parsing raises events too)

    def hook(event: str, arguments: tuple) -> None:
        thread = threading.get_ident()
        if event != "compile" or thread in parsing:
            return
        source, filename = arguments[0], arguments[1]
        parsing.add(thread)
        try:
            tree = source if isinstance(source, ast.AST) else ast.parse(source)
        except (SyntaxError, ValueError, TypeError, MemoryError, RecursionError):
            return  # compile() itself will say what is wrong
        finally:
            parsing.discard(thread)
        found = copies_in(tree, answers)
        if is_a_copy(found):
            raise Refused(
                f"compiling {describe_copies(found, os.path.basename(os.fsdecode(filename)))} "
                f"is not allowed while your code is graded"
            )

    return hook
