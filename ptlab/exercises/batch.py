"""``ptlab exercise grade-all``: a whole class's submissions, several graded at once.

    ptlab exercise grade-all 6 submissions/ --csv grades-06.csv --workers 2

Each entry of the folder is one student's work: a Python file (the student is its name) or
a folder (the student is the folder's name; the file in it is the chapter's, ``06_diffuse.py``,
or its only Python file; its other Python files are the student's too). A symbolic link is
no submission. Every student is graded by a grader process of their own
(``python -I -m ptlab.exercises.batch N FILE``: isolated, so nothing is imported from the
current folder; the same isolation as ``ptlab exercise check``), with a time limit on the
whole, so a submission that hangs or crashes costs that student its marks and nobody else
anything.

The CSV gets one row per student (total, the points of every check, the first failure's
message), its cells made safe for spreadsheets (one that begins with ``=``, ``+``, ``-``,
``@``, a tab or a carriage return is quoted with a leading ``'``). The rows come from the
grader's own record of what it graded (its private state, ``ptlab.exercises.progress``),
and the CSV is rewritten from it, atomically, at the start and after each student:
interrupted, the command picks up where it stopped. A student is not graded again when the
CSV still holds the row the grader wrote and the submission is the one it graded; a row
that is missing (delete it to grade that student anew), changed, or not the grader's own is
graded again.
"""

from __future__ import annotations

import csv
import hashlib
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
from ptlab.exercises.grader import OVERALL_SLACK, overall_limit, table_message
from ptlab.exercises.progress import private_state
from ptlab.untrusted import ProcessGuard, import_nothing_from_here, make_undumpable, student_user

#: The largest report a grader process may print (a grade's JSON is a few kilobytes).
MAX_REPORT = 1 << 20
#: Seconds a grader process gets beyond its own overall limit before it is ended.
EXTRA_SECONDS = 60.0
#: The first characters that make a spreadsheet read a cell as a formula.
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


@dataclass(frozen=True)
class Work:
    """One student's submission: ``file`` is None when none was found (``problem`` says why);
    ``own_folder``: the folder holding ``file`` is the student's alone."""

    student: str
    file: Path | None
    problem: str = ""
    own_folder: bool = False


def find_work(folder: Path, chapter: Chapter) -> list[Work]:
    """Every student's submission in ``folder``, by student name."""
    if not folder.is_dir():
        raise PtlabError(f"{folder}: no such folder")
    found = []
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith((".", "_")):
            continue
        if entry.is_symlink():
            found.append(
                Work(
                    entry.stem if entry.suffix == ".py" else entry.name,
                    None,
                    f"{entry.name} is a symbolic link: hand in the files themselves",
                )
            )
        elif entry.is_file() and entry.suffix == ".py":
            found.append(Work(entry.stem, entry))
        elif entry.is_dir():
            found.append(_work_in_folder(entry, chapter))
    return found


def _work_in_folder(folder: Path, chapter: Chapter) -> Work:
    expected = folder / chapter.template.name
    if expected.is_file():
        return Work(folder.name, expected, own_folder=True)
    files = sorted(p for p in folder.glob("*.py") if not p.name.startswith((".", "_")))
    if len(files) == 1:
        return Work(folder.name, files[0], own_folder=True)
    listed = ", ".join(p.name for p in files[:5]) or "no Python file"
    return Work(folder.name, None, f"no {expected.name} in the folder ({listed})")


def columns(chapter: Chapter) -> list[str]:
    return (
        ["student", "file", "score", "max_score"]
        + [c.name for c in chapter.checks]
        + ["first_failure", "seconds", "grading_seed"]
    )


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


def safe_cell(value) -> str:
    """``value`` as a CSV cell that no spreadsheet takes for a formula."""
    text = str(value)
    return "'" + text if text.startswith(FORMULA_STARTS) else text


def write_rows(path: Path, chapter: Chapter, rows: dict[str, dict]) -> None:
    def write(temporary: str) -> None:
        with open(temporary, "w", newline="", encoding="utf-8") as out:
            writer = csv.DictWriter(out, fieldnames=columns(chapter))
            writer.writeheader()
            for student in sorted(rows):
                writer.writerow(rows[student])

    write_atomically(path, write)


class Record:
    """The grader's own record of a grade-all run: every row it wrote, with the SHA-256 of
    the submission it graded, in its private state (which the students' user cannot read
    or write), one file per CSV. Rows are keyed by their ``student`` cell as written."""

    def __init__(self, csv_path: Path, chapter: Chapter):
        name = hashlib.sha256(str(csv_path.resolve()).encode()).hexdigest()[:32]
        self.path = private_state() / "grade-all" / f"{name}.json"
        self.chapter = chapter
        self.rows: dict[str, dict] = {}
        self.sha256: dict[str, str] = {}
        try:
            saved = json.loads(self.path.read_text())
            if saved.get("chapter") == chapter.number:
                self.rows, self.sha256 = saved["rows"], saved["sha256"]
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            pass

    def vouched(self, in_csv: dict[str, dict], work: list[Work]) -> dict[str, dict]:
        """The rows of ``in_csv`` this record holds as they are, for submissions unchanged."""
        files = {safe_cell(w.student): w.file for w in work}
        return {
            student: row
            for student, row in in_csv.items()
            if self.rows.get(student) == row
            and student in files
            and self.sha256.get(student) == _sha256(files[student])
        }

    def keep(self, rows: dict[str, dict], work: list[Work]) -> None:
        """Record ``rows`` (and nothing else) as written."""
        files = {safe_cell(w.student): w.file for w in work}
        self.rows = dict(rows)
        self.sha256 = {student: _sha256(files.get(student)) for student in rows}
        self.path.parent.mkdir(mode=0o700, exist_ok=True)
        text = json.dumps({"chapter": self.chapter.number, "rows": self.rows, "sha256": self.sha256})
        write_atomically(self.path, lambda temporary: Path(temporary).write_text(text))


def _sha256(file: Path | None) -> str:
    """The SHA-256 of a submission's file ("" for none, or a link: graded again)."""
    if file is None or file.is_symlink():
        return ""
    try:
        with file.open("rb") as data:
            return hashlib.file_digest(data, "sha256").hexdigest()
    except OSError:
        return ""


def grade_all(
    chapter: Chapter,
    folder: Path,
    csv_path: Path,
    workers: int = 1,
    timeout_scale: float = 1.0,
    progress: bool = False,
    user: str | None = None,
    seed: int | None = None,
) -> dict[str, dict]:
    """Grade every submission in ``folder`` the grader's record does not vouch for (see the
    module docstring); all rows by student. ``user``: whom the students' code runs as
    (``--student-user``); ``seed``: the grading seed of every student (None: a fresh one
    each, in the row's ``grading_seed``)."""
    student_user(user)  # (an unknown user, or one that cannot run ptlab: before anything)
    make_undumpable()
    import_nothing_from_here()
    work = find_work(folder, chapter)
    record = Record(csv_path, chapter)
    rows = record.vouched(read_rows(csv_path, chapter), work)
    write_rows(csv_path, chapter, rows)  # what the grader cannot vouch for goes at once
    record.keep(rows, work)
    todo = [w for w in work if safe_cell(w.student) not in rows]
    limit = overall_limit(chapter, timeout_scale) + EXTRA_SECONDS
    if todo:
        print(
            f"chapter {chapter.number}: {len(todo)} students to grade; each takes at most "
            f"{limit / 60:.1f} minutes (its checks' time limits, "
            f"{limit - OVERALL_SLACK - EXTRA_SECONDS:.0f} s, and "
            f"{OVERALL_SLACK + EXTRA_SECONDS:.0f} s to start and end)",
            file=sys.stderr,
        )
    bar = tqdm(total=len(todo), unit="student", disable=not progress, file=sys.stderr)
    runner = _Runner(chapter, timeout_scale, limit, user, seed)
    with ProcessGuard() as guard, ThreadPoolExecutor(max(1, workers)) as pool:
        runner.guard = guard
        futures = {pool.submit(runner.grade, w): w for w in todo}
        for future in as_completed(futures):
            row = {k: safe_cell(v) for k, v in future.result().items()}
            rows[row["student"]] = row
            write_rows(csv_path, chapter, rows)
            record.keep(rows, work)
            bar.update()
    bar.close()
    return rows


class _Runner:
    """Grades one student at a time per thread, each in a grader process of its own."""

    def __init__(
        self,
        chapter: Chapter,
        timeout_scale: float,
        limit: float,
        user: str | None = None,
        seed: int | None = None,
    ):
        self.chapter, self.timeout_scale, self.limit = chapter, timeout_scale, limit
        self.user, self.seed = user, seed
        self.guard: ProcessGuard | None = None
        self._lock = threading.Lock()
        self._running: set[int] = set()

    def grade(self, work: Work) -> dict:
        row = dict.fromkeys(columns(self.chapter), "")
        row.update(
            student=work.student,
            file="" if work.file is None else work.file.name,
            score=0,
            max_score=sum(c.points for c in self.chapter.checks),
        )
        if work.file is None:
            row.update(first_failure=work.problem, seconds=0)
            return row
        start = time.monotonic()
        report, problem = self._run(work)
        row["seconds"] = f"{time.monotonic() - start:.1f}"
        if report is None:
            row["first_failure"] = problem
            return row
        results = {c["name"]: c for c in report["checks"]}
        row["score"], row["grading_seed"] = report["score"], report["grading_seed"]
        for check in self.chapter.checks:
            row[check.name] = results[check.name]["points"]
        failed = [c for c in report["checks"] if not c["passed"]]
        row["first_failure"] = f"{failed[0]['name']}: {failed[0]['message']}" if failed else ""
        return row

    def _run(self, work: Work) -> tuple[dict | None, str]:
        command = [
            sys.executable,
            "-I",
            "-m",
            "ptlab.exercises.batch",
            str(self.chapter.number),
            str(work.file),
            "--timeout-scale",
            repr(self.timeout_scale),
        ]
        if self.user is not None:
            command += ["--student-user", self.user]
        if self.seed is not None:
            command += ["--grading-seed", str(self.seed)]
        if work.own_folder:
            command.append("--own-folder")
        with self._lock:
            process = subprocess.Popen(
                command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL
            )
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
        valid = (
            names == [c.name for c in chapter.checks]
            and type(report["score"]) is int
            and type(report["grading_seed"]) is int
            and all(
                type(c["points"]) is int and type(c["passed"]) is bool and type(c["message"]) is str
                for c in report["checks"]
            )
        )
    except (ValueError, KeyError, TypeError):
        valid = False
    if not valid:
        return None, "the grader's report was unreadable"
    for check in report["checks"]:
        check["message"] = table_message(check["message"])
    return report, ""


def main(argv: list[str] | None = None) -> int:
    """One student, for ``grade_all``: grade ``FILE`` for chapter ``N``, print the JSON."""
    import argparse

    from ptlab.exercises import chapter
    from ptlab.exercises.grader import grade

    parser = argparse.ArgumentParser(
        prog="python -m ptlab.exercises.batch", description="Grade one file; print the result as JSON."
    )
    parser.add_argument("chapter")
    parser.add_argument("file")
    parser.add_argument("--timeout-scale", type=float, default=1.0)
    parser.add_argument("--student-user")
    parser.add_argument("--grading-seed", type=int)
    parser.add_argument(
        "--own-folder", action="store_true", help="the Python files beside FILE are the student's too"
    )
    args = parser.parse_args(argv)
    result = grade(
        chapter(args.chapter),
        Path(args.file),
        timeout_scale=args.timeout_scale,
        user=args.student_user,
        with_folder=args.own_folder,
        seed=args.grading_seed,
    )
    print(json.dumps(result.as_dict()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
