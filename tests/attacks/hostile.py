"""Helpers of the attack tests (``tests/attacks/test_*.py``): where the hostile submissions
are, and what an honest failure looks like."""

from __future__ import annotations

import os
from pathlib import Path

from ptlab.course.sandbox.processes import process_table

#: The hostile submissions, one file per attack (each docstring says what it does).
SUBMISSIONS = Path(__file__).parent / "submissions"
#: The lines a grader that is not root prints after its verdict: one, "NOT FOR CREDIT ..."
#: (its students' code runs as its own user; docs/grading-security.md). Root prints none.
NOT_FOR_CREDIT_LINES = 0 if os.geteuid() == 0 else 1


def verdict_lines(text: str) -> list[str]:
    """``text``'s lines up to the verdict (the table's total, ``ptlab grade``'s PASSED or
    FAILED), without the not-for-credit line a grader that is not root adds after it."""
    lines = text.rstrip().splitlines()
    if NOT_FOR_CREDIT_LINES:
        assert lines[-1].lstrip().startswith("NOT FOR CREDIT"), text
        return lines[:-NOT_FOR_CREDIT_LINES]
    return lines


def alive(pids) -> list[int]:
    """Those of ``pids`` that are still running (not ended, not zombies)."""
    running = process_table(alive_only=True)
    return [pid for pid in pids if pid in running]


def students_processes() -> list[int]:
    """Every process on the machine that a student's process is or started (their command
    line is the sandbox's ``BOOTSTRAP``: ``ptlab.course.sandbox.sandbox``). The pids a submission
    prints are its pid namespace's, which name other processes out here."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if b"from ptlab.course.sandbox.child import main" in (entry / "cmdline").read_bytes():
                    found.append(int(entry.name))
            except OSError:
                continue
    return sorted(set(found) & set(process_table(alive_only=True)))


def printed_pids(output: str) -> list[int]:
    """The pids a hostile submission printed, from the grader's stderr (``    | 1234``)."""
    return [
        int(line.split("|", 1)[1])
        for line in output.splitlines()
        if "|" in line and line.split("|", 1)[1].strip().isdigit()
    ]


def assert_honest_failure(result, reason: str = "") -> None:
    """Every check of the ``Grade`` failed, with ``reason`` in its message and no traceback."""
    assert result.score == 0, result.table()
    for check in result.results:
        assert not check.passed, result.table()
        assert reason in check.message, result.table()
        assert "Traceback" not in check.message
