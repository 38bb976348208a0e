"""Running a chapter's checks on a student's file, like a course autograder.

Every check is worth some points and runs in a process of its own, with a time limit: a
student's function that loops forever or crashes the interpreter costs that check's
points, and the grader goes on to the next one. A check is a plain function of the
student's module: it returns a short note of what it measured, or raises ``CheckFailed``
with a message for the student. Anything else the student's code raises becomes the
check's message too (the error, and the line of the student's file it came from), never a
traceback.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from types import ModuleType

from ptlab.errors import PtlabError
from ptlab.exercises.chapter import CheckFailed


@dataclass
class CheckResult:
    """How one check went."""

    name: str
    points: int
    max_points: int
    passed: bool
    message: str
    seconds: float


@dataclass
class Grade:
    """Every check of one chapter on one file."""

    chapter: int
    title: str
    file: str
    results: list[CheckResult]

    @property
    def score(self) -> int:
        return sum(r.points for r in self.results)

    @property
    def max_score(self) -> int:
        return sum(r.max_points for r in self.results)

    @property
    def full_marks(self) -> bool:
        return self.score == self.max_score

    def as_dict(self) -> dict:
        """A JSON-ready summary, for course infrastructure."""
        return dict(chapter=self.chapter, title=self.title, file=self.file, score=self.score,
                    max_score=self.max_score, full_marks=self.full_marks,
                    checks=[asdict(r) for r in self.results])

    def table(self) -> str:
        """The score table, one row per check, as a course autograder prints it."""
        width = max(len(r.name) for r in self.results)
        lines = [f"Chapter {self.chapter}: {self.title}  ({self.file})", ""]
        lines.append(f"  {'check':{width}}  {'points':>7}  verdict  message")
        for r in self.results:
            verdict = "pass" if r.passed else "FAIL"
            lines.append(f"  {r.name:{width}}  {r.points:>3}/{r.max_points:<3}  {verdict:7}  "
                         f"{r.message}")
        lines.append(f"  {'total':{width}}  {self.score:>3}/{self.max_score:<3}  "
                     f"{'full marks' if self.full_marks else ''}")
        return "\n".join(lines)


def grade(chapter, path: str | Path, timeout_scale: float = 1.0,
          echo: Callable[[str], None] | None = None) -> Grade:
    """Run every check of ``chapter`` (a ``ptlab.exercises.Chapter``) on the file ``path``."""
    path = Path(path)
    if not path.is_file():
        raise PtlabError(f"{path}: no such file")
    results = []
    for index, check in enumerate(chapter.checks):
        result = run_check(chapter.number, index, path, check.timeout * timeout_scale)
        if echo is not None:
            echo(f"  {'pass' if result.passed else 'FAIL'}  {result.name} ({result.seconds:.1f} s)")
        results.append(result)
    return Grade(chapter.number, chapter.title, str(path), results)


def run_check(chapter_number: int, index: int, path: Path, timeout: float) -> CheckResult:
    """Run one check in a fresh process, killed after ``timeout`` seconds.

    The process comes from a forkserver: a clean copy of an interpreter that has run no
    renders (forking this process instead could inherit Embree's threads mid-lock).
    """
    from ptlab.exercises import chapter as find_chapter

    check = find_chapter(chapter_number).checks[index]
    context = multiprocessing.get_context("forkserver")
    # Imported once in the server, not again in every check's process (~0.5 s each).
    context.set_forkserver_preload(["numpy", "trimesh", "ptlab.rendering", "ptlab.exercises"])
    receive, send = context.Pipe(duplex=False)
    start = time.perf_counter()
    # Not daemonic, so that a student's code may start a pool of its own (chapter 8).
    process = context.Process(target=_check_in_child,
                              args=(chapter_number, index, str(path), send))
    process.start()
    send.close()
    passed, message = False, ""
    if receive.poll(timeout):
        try:
            passed, message = receive.recv()
        except EOFError:
            message = "the check's process died (the code crashed the interpreter)"
    else:
        message = (f"took longer than {timeout:.0f} s and was stopped (an endless loop, or "
                   f"a Python loop over every ray?)")
    _kill_process_group(process.pid)     # the check and any process the student's code started
    process.join()
    receive.close()
    return CheckResult(check.name, check.points if passed else 0, check.points, passed,
                       message, time.perf_counter() - start)


def _check_in_child(chapter_number: int, index: int, path: str, send) -> None:
    """In the check's process: load the student's file, run the check, send the verdict."""
    from ptlab.exercises import chapter as find_chapter

    os.setpgid(0, 0)    # a process group of its own, which the grader ends as a whole

    check = find_chapter(chapter_number).checks[index]
    try:
        module = load_student(Path(path))
        verdict = (True, check.run(module))
    except CheckFailed as failure:
        verdict = (False, str(failure))
    except NotImplementedError as error:
        name = f"{error} " if str(error) else ""
        verdict = (False, f"{name}is not written yet: it still raises NotImplementedError "
                          f"({where(error, path)})")
    except PtlabError as error:
        verdict = (False, str(error))
    except Exception as error:  # the student's code raised: report it, do not crash
        verdict = (False, f"{type(error).__name__}: {error} ({where(error, path)})")
    send.send(verdict)
    send.close()


def _kill_process_group(pid: int) -> None:
    """SIGKILL the process group led by ``pid`` (if it still exists)."""
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def where(error: BaseException, path: str) -> str:
    """``file.py:line`` of the deepest frame of the student's file in the traceback."""
    frames = [f for f in traceback.extract_tb(error.__traceback__)
              if Path(f.filename).resolve() == Path(path).resolve()]
    if not frames:
        return "raised outside your file"
    return f"{Path(path).name}:{frames[-1].lineno}"


def load_student(path: Path) -> ModuleType:
    """Import the student's file (a ``PtlabError`` names a syntax error or a failed import)."""
    from ptlab.grading.untrusted import import_file
    return import_file(path)


