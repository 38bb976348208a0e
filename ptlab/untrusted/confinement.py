"""The authorship hook: a copy of ptlab's answers compiled at run time is refused.

The sandbox (``ptlab.untrusted.sandbox``) decides what the student's process can reach;
this hook decides nothing of that. It answers another question, authorship, for code the
grader cannot read in the file: Python raises an audit event before it compiles code
(PEP 578, ``sys.addaudithook``), and the hook refuses code that holds a copy of the
chapter's answers (``ptlab.untrusted.copies``), however it was assembled (decoded from
base64, downloaded before the grading, built from strings).

It is a second layer, not a defence: it lives in the process it watches, whose code can
take it apart (PEP 578 says as much), and bytecode imported from a ``.pyc`` raises no
compile event. What it guards is written in docs/grading-security.md.
"""

from __future__ import annotations

import ast
import os
import sys
import threading

from ptlab.untrusted.copies import Answers, copies_in, describe_copies, is_a_copy


class Refused(PermissionError):  # noqa: N818 (a rule, not an error of the code)
    """What the student's code tried is not allowed while it is graded."""


def confine(answers: Answers) -> None:
    """Add the hook, if there are answers to look for (none when grading ptlab's own file)."""
    if answers:
        sys.addaudithook(_CompiledCopies(answers))


class _CompiledCopies:
    """The audit hook (called for every event, so it returns at once for the others)."""

    def __init__(self, answers: Answers):
        self.answers = answers
        self.checking = threading.local()  # (parsing inside the hook raises events)

    def __call__(self, event: str, arguments: tuple) -> None:
        if event != "compile" or getattr(self.checking, "now", False):
            return
        source, filename = arguments[0], arguments[1]
        self.checking.now = True
        try:
            tree = source if isinstance(source, ast.AST) else ast.parse(source)
        except (SyntaxError, ValueError, TypeError, MemoryError, RecursionError):
            return  # compile() itself will say what is wrong
        finally:
            self.checking.now = False
        found = copies_in(tree, self.answers)
        if is_a_copy(found):
            raise Refused(
                f"compiling {describe_copies(found, os.path.basename(os.fsdecode(filename)))} "
                f"is not allowed while your code is graded"
            )
