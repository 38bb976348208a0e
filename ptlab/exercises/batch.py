"""``ptlab exercise grade-all``: a whole class's submissions, several graded at once.

    ptlab exercise grade-all 6 submissions/ --csv grades-06.csv --workers 2

Each entry of the folder is one student's work: a Python file (the student is its name) or
a folder (the student is the folder's name; the file in it is the chapter's, ``06_diffuse.py``,
or its only Python file). Every student is graded by a grader process of their own
(``python -m ptlab.exercises.batch N FILE``, the same isolation as ``ptlab exercise check``),
with a time limit on the whole, so a submission that hangs or crashes costs that student
its marks and nobody else anything. The CSV gets one row per student (total, the points of
every check, the first failure's message), rewritten atomically after each student:
interrupted, the command picks up where it stopped (students with a row are not graded
again; delete a row to grade that student anew).
"""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from ptlab.atomic import write_atomically
from ptlab.errors import PtlabError
from ptlab.exercises.chapter import Chapter
from ptlab.exercises.grader import one_line, overall_limit
from ptlab.untrusted import ProcessGuard

#: The largest report a grader process may print (a grade's JSON is a few kilobytes).
MAX_REPORT = 1 << 20
#: Seconds a grader process gets beyond its own overall limit before it is ended.
EXTRA_SECONDS = 60.0


@dataclass(frozen=True)
class Work:
    """One student's submission: ``file`` is None when none was found (``problem`` says why)."""

    student: str
    file: Path | None
    problem: str = ""


def find_work(folder: Path, chapter: Chapter) -> list[Work]:
    """Every student's submission in ``folder``, by student name."""
    if not folder.is_dir():
        raise PtlabError(f"{folder}: no such folder")
    found = []
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith((".", "_")):
            continue
        if entry.is_file() and entry.suffix == ".py":
            found.append(Work(entry.stem, entry))
        elif entry.is_dir():
            found.append(_work_in_folder(entry, chapter))
    return found


def _work_in_folder(folder: Path, chapter: Chapter) -> Work:
    expected = folder / chapter.template.name
    if expected.is_file():
        return Work(folder.name, expected)
    files = sorted(p for p in folder.glob("*.py") if not p.name.startswith((".", "_")))
    if len(files) == 1:
        return Work(folder.name, files[0])
    listed = ", ".join(p.name for p in files[:5]) or "no Python file"
    return Work(folder.name, None, f"no {expected.name} in the folder ({listed})")


def columns(chapter: Chapter) -> list[str]:
    return (["student", "file", "score", "max_score"] + [c.name for c in chapter.checks]
            + ["first_failure", "seconds"])


def read_rows(path: Path, chapter: Chapter) -> dict[str, dict]:
    """The rows of an earlier run's CSV, by student ({} if there is none)."""
    if not path.exists():
        return {}
    try:
        reader = csv.DictReader(io.StringIO(path.read_text(encoding="utf-8")))
        rows = list(reader)
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise PtlabError(f"{path}: cannot read it to resume ({error})") from None
    if reader.fieldnames != columns(chapter):
        raise PtlabError(f"{path}: its columns are not chapter {chapter.number}'s; give another --csv")
    return {row["student"]: row for row in rows}


def write_rows(path: Path, chapter: Chapter, rows: dict[str, dict]) -> None:
    def write(temporary: str) -> None:
        with open(temporary, "w", newline="", encoding="utf-8") as out:
            writer = csv.DictWriter(out, fieldnames=columns(chapter))
            writer.writeheader()
            for student in sorted(rows):
                writer.writerow(rows[student])

    write_atomically(path, write)


def grade_all(chapter: Chapter, folder: Path, csv_path: Path, workers: int = 1,
              timeout_scale: float = 1.0, progress: bool = False) -> dict[str, dict]:
    """Grade every submission in ``folder`` not yet in ``csv_path``; all rows by student."""
    rows = read_rows(csv_path, chapter)
    todo = [work for work in find_work(folder, chapter) if work.student not in rows]
    limit = overall_limit(chapter, timeout_scale) + EXTRA_SECONDS
    bar = tqdm(total=len(todo), unit="student", disable=not progress, file=sys.stderr)
    runner = _Runner(chapter, timeout_scale, limit)
    with ProcessGuard() as guard, ThreadPoolExecutor(max(1, workers)) as pool:
        runner.guard = guard
        futures = {pool.submit(runner.grade, work): work for work in todo}
        for future in as_completed(futures):
            rows[futures[future].student] = future.result()
            write_rows(csv_path, chapter, rows)
            bar.update()
    bar.close()
    return rows


class _Runner:
    """Grades one student at a time per thread, each in a grader process of its own."""

    def __init__(self, chapter: Chapter, timeout_scale: float, limit: float):
        self.chapter, self.timeout_scale, self.limit = chapter, timeout_scale, limit
        self.guard: ProcessGuard | None = None
        self._lock = threading.Lock()
        self._running: set[int] = set()

    def grade(self, work: Work) -> dict:
        row = dict.fromkeys(columns(self.chapter), "")
        row.update(student=work.student, file="" if work.file is None else work.file.name,
                   score=0, max_score=sum(c.points for c in self.chapter.checks))
        if work.file is None:
            row.update(first_failure=work.problem, seconds=0)
            return row
        start = time.monotonic()
        report, problem = self._run(work.file)
        row["seconds"] = f"{time.monotonic() - start:.1f}"
        if report is None:
            row["first_failure"] = problem
            return row
        results = {c["name"]: c for c in report["checks"]}
        row["score"] = report["score"]
        for check in self.chapter.checks:
            row[check.name] = results[check.name]["points"]
        failed = [c for c in report["checks"] if not c["passed"]]
        row["first_failure"] = f"{failed[0]['name']}: {failed[0]['message']}" if failed else ""
        return row

    def _run(self, file: Path) -> tuple[dict | None, str]:
        command = [sys.executable, "-m", "ptlab.exercises.batch", str(self.chapter.number),
                   str(file), "--timeout-scale", repr(self.timeout_scale)]
        with self._lock:
            process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                       stderr=subprocess.DEVNULL)
            self._running.add(process.pid)
        try:
            output, _ = process.communicate(timeout=self.limit)
        except subprocess.TimeoutExpired:
            output = None
        finally:
            with self._lock:
                self._running.discard(process.pid)
                # The grader and whatever it left (re-parented here if it was killed).
                self.guard.end(process.pid, keep=self._running)
            process.wait()
        if output is None:
            return None, f"grading did not finish in {self.limit:.0f} s"
        if process.returncode != 0 or len(output) > MAX_REPORT:
            return None, f"the grader ended with code {process.returncode} and no report"
        return _report(output, self.chapter)


def _report(output: bytes, chapter: Chapter) -> tuple[dict | None, str]:
    """The grader's JSON report, checked against the chapter's checks."""
    try:
        report = json.loads(output)
        names = [c["name"] for c in report["checks"]]
        valid = (names == [c.name for c in chapter.checks] and type(report["score"]) is int
                 and all(type(c["points"]) is int and type(c["passed"]) is bool
                         and type(c["message"]) is str for c in report["checks"]))
    except (ValueError, KeyError, TypeError):
        valid = False
    if not valid:
        return None, "the grader's report was unreadable"
    for check in report["checks"]:
        check["message"] = one_line(check["message"])
    return report, ""


def main(argv: list[str] | None = None) -> int:
    """One student, for ``grade_all``: grade ``FILE`` for chapter ``N``, print the JSON."""
    import argparse

    from ptlab.exercises import chapter
    from ptlab.exercises.grader import grade

    parser = argparse.ArgumentParser(prog="python -m ptlab.exercises.batch",
                                     description="Grade one file; print the result as JSON.")
    parser.add_argument("chapter")
    parser.add_argument("file")
    parser.add_argument("--timeout-scale", type=float, default=1.0)
    args = parser.parse_args(argv)
    result = grade(chapter(args.chapter), Path(args.file), timeout_scale=args.timeout_scale)
    print(json.dumps(result.as_dict()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
