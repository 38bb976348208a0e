"""``ptlab exercise grade-all``: a whole class's submissions, several graded at once.

    ptlab exercise grade-all 6 submissions/ --csv grades-06.csv --workers 2

Each entry of the folder is one student's work: a Python file (the student is its name) or
a folder (the student is the folder's name; the file in it is the chapter's, ``06_diffuse.py``,
or its only Python file; its other Python files are the student's too). A symbolic link is
no submission. Every student is graded by a grader process of their own
(``python -I -m ptlab.course.batch N FILE``: isolated, so nothing is imported from the
current folder; the same isolation as ``ptlab exercise check``), with a time limit on the
whole, so a submission that hangs or crashes costs that student its marks and nobody else
anything.

Only regular files are read: a FIFO, a device or a socket in the folder (which would hang
the reader) is reported in its student's row and skipped. Names that a spreadsheet or a
file system would take for the same student (``alice.py`` and ``alice/``; ``Alice`` and
``alice``; names that differ in Unicode normalisation or a trailing dot) are none of them
graded: each gets a row of its own that says so, so no submission is dropped unnoticed.

The CSV gets one row per student (total, the points of every check, the first failure's
message), its cells made safe for spreadsheets (``safe_cell``: control characters and
newlines shown as escapes, and one that begins, after any spaces, with ``=``, ``+``,
``-`` or ``@`` is quoted with a leading ``'``). The rows come from the
grader's own record of what it graded (its private state, ``ptlab.course.progress``),
and the CSV is rewritten from it, atomically, at the start and after each student:
interrupted, the command picks up where it stopped. A student is not graded again when the
CSV still holds the row the grader wrote and the submission is the one it graded; a row
that is missing (delete it to grade that student anew), changed, or not the grader's own is
graded again.

After the grades, the pairs of students whose files are alike (``ptlab.course.alike``:
the share of the smaller submission's normalised code found in the other, as MOSS reports
them) are listed for a teacher to look at, the most similar first: printed, and written to
a CSV of their own (``write_alike``; ``grade-all --alike``, by default beside the grades:
``grades-07-alike.csv``). Every submission with a file is compared, graded now or earlier.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import queue
import stat
import subprocess
import sys
import threading
import time
import unicodedata
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from ptlab.atomic import write_atomically
from ptlab.course.alike import MAX_COMPARED_BYTES, Alike, alike_pairs, fingerprints
from ptlab.course.chapter import Chapter
from ptlab.course.grader import OVERALL_SLACK, overall_limit, table_message
from ptlab.course.messages import LANGUAGES, active_language
from ptlab.course.progress import private_state
from ptlab.course.sandbox import (
    ProcessGuard,
    import_nothing_from_here,
    make_undumpable,
    sandbox,
    student_user,
)
from ptlab.course.sandbox.control_groups import ControlGroups
from ptlab.course.sandbox.intake import MAX_BYTES, RefusedSubmission, read_files
from ptlab.course.sandbox.shown import shown
from ptlab.course.sandbox.student_user import is_root, pool_user
from ptlab.errors import PtlabError

#: The largest report a grader process may print (a grade's JSON is a few kilobytes).
MAX_REPORT = 1 << 20
#: Seconds a grader process gets beyond its own overall limit before it is ended.
EXTRA_SECONDS = 60.0
#: The first characters (after any spaces) that make a spreadsheet read a cell as a
#: formula, the full-width forms included.
FORMULA_STARTS = ("=", "+", "-", "@", "\uff1d", "\uff0b", "\uff0d", "\uff20")
#: The columns of the CSV of alike pairs (``write_alike``).
ALIKE_COLUMNS = ("student_a", "file_a", "student_b", "file_b", "similarity", "shared", "size_a", "size_b")


@dataclass(frozen=True)
class Work:
    """One student's submission: ``file`` is None when none was found (``problem`` says why);
    ``own_folder``: the folder holding ``file`` is the student's alone.

    Attributes:
        student: the student's cell in the CSV (``safe_cell`` of the name), unique in the class.
        entry: the folder's entry it came from, shown (``alice.py``, ``alice/``).
    """

    student: str
    file: Path | None
    problem: str = ""
    own_folder: bool = False
    entry: str = ""


def find_work(folder: Path, chapter: Chapter) -> list[Work]:
    """Every student's submission in ``folder``, one per entry, each with a student cell of
    its own (``_unambiguous``)."""
    if not folder.is_dir():
        raise PtlabError(f"{folder}: no such folder")
    found = []
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith((".", "_")):
            continue
        kind = _kind(entry)
        student = safe_cell(entry.stem if entry.suffix == ".py" and kind != "folder" else entry.name)
        label = shown(entry.name) + ("/" if kind == "folder" else "")
        if kind == "link":
            problem = f"{label} is a symbolic link: hand in the files themselves"
            found.append(Work(student, None, problem, entry=label))
        elif kind == "folder":
            found.append(_work_in_folder(entry, chapter, student, label))
        elif entry.suffix == ".py":
            problem = "" if kind == "file" else f"{label} is not a regular file ({kind}): not read"
            found.append(Work(student, entry if kind == "file" else None, problem, entry=label))
    return _unambiguous(found)


def _kind(path: Path) -> str:
    """What ``path`` is, without following a link or opening it: "file" (regular),
    "folder", "link", or what else it is ("a FIFO", "a socket", "a device")."""
    try:
        mode = path.lstat().st_mode
    except OSError:
        return "gone"
    if stat.S_ISLNK(mode):
        return "link"
    if stat.S_ISDIR(mode):
        return "folder"
    if stat.S_ISREG(mode):
        return "file"
    return "a FIFO" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) else "a device"


def _work_in_folder(folder: Path, chapter: Chapter, student: str, label: str) -> Work:
    expected = folder / chapter.template.name
    kind = _kind(expected)
    if kind == "file":
        return Work(student, expected, own_folder=True, entry=label)
    if kind != "gone":
        problem = f"{label}{expected.name} is not a regular file ({kind}): not read"
        return Work(student, None, problem, entry=label)
    files = sorted(p for p in folder.glob("*.py") if not p.name.startswith((".", "_")) and _kind(p) == "file")
    if len(files) == 1:
        return Work(student, files[0], own_folder=True, entry=label)
    listed = ", ".join(shown(p.name) for p in files[:5]) or "no Python file"
    return Work(student, None, f"no {expected.name} in the folder ({listed})", entry=label)


def _identity(student: str) -> str:
    """What a spreadsheet reader or a file system may take for the same name: case,
    Unicode normalisation and trailing dots and spaces aside."""
    return unicodedata.normalize("NFKC", student).casefold().rstrip(". ")


def _unambiguous(found: list[Work]) -> list[Work]:
    """``found`` with every student cell told apart: entries whose names are the same
    student (``alice.py`` and ``alice/``, ``Bob`` and ``bob``) are none of them graded,
    and each gets a row of its own, named by its entry, that says why."""
    groups: dict[str, list[Work]] = {}
    for work in found:
        groups.setdefault(_identity(work.student), []).append(work)
    named: list[Work] = []
    for same in groups.values():
        if len(same) == 1:
            named += same
            continue
        entries = ", ".join(w.entry for w in same)
        for work in same:
            problem = f"ambiguous: {entries} are all student {work.student}; rename all but one"
            named.append(Work(safe_cell(work.entry), None, problem, entry=work.entry))
    # An entry's name may still meet another student's (a folder named "alice.py"): number it.
    taken: set[str] = set()
    unique = []
    for work in named:
        student, n = work.student, 1
        while _identity(student) in taken:
            n += 1
            student = f"{work.student} ({n})"
        taken.add(_identity(student))
        if student != work.student:
            problem = f"ambiguous: {work.entry} is named like another student; rename it"
            work = Work(student, None, problem, entry=work.entry)
        unique.append(work)
    return unique


def columns(chapter: Chapter) -> list[str]:
    return (
        ["student", "file", "score", "max_score"]
        + [c.name for c in chapter.checks]
        + ["first_failure", "seconds", "grading_seed", "for_credit"]
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
    """``value`` as a CSV cell that no spreadsheet takes for a formula and that holds one
    line: control characters shown as escapes (``ptlab.course.sandbox.shown``), and a leading
    ``'`` where it begins, after any spaces, as a formula does. A safe cell is its own
    ``safe_cell``."""
    text = shown(value)
    return "'" + text if text.lstrip().startswith(FORMULA_STARTS) else text


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
        files = {w.student: w.file for w in work}
        return {
            student: row
            for student, row in in_csv.items()
            if self.rows.get(student) == row
            and student in files
            and self.sha256.get(student) == _sha256(files[student])
        }

    def keep(self, rows: dict[str, dict], work: list[Work]) -> None:
        """Record ``rows`` (and nothing else) as written."""
        files = {w.student: w.file for w in work}
        self.rows = dict(rows)
        self.sha256 = {student: _sha256(files.get(student)) for student in rows}
        self.path.parent.mkdir(mode=0o700, exist_ok=True)
        text = json.dumps({"chapter": self.chapter.number, "rows": self.rows, "sha256": self.sha256})

        def write(temporary: str) -> None:
            Path(temporary).write_text(text)

        write_atomically(self.path, write)


def _sha256(file: Path | None) -> str:
    """The SHA-256 of a submission's file ("" for none, a link, anything but a regular file
    or one larger than a submission may be: graded again). Opened without blocking and
    checked before it is read: a FIFO put there since would hang the reader."""
    if file is None:
        return ""
    try:
        descriptor = os.open(file, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return ""
    try:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            return ""
        with os.fdopen(descriptor, "rb", closefd=False) as data:
            content = data.read(MAX_BYTES + 1)
        return hashlib.sha256(content).hexdigest() if len(content) <= MAX_BYTES else ""
    except OSError:
        return ""
    finally:
        os.close(descriptor)


def grade_all(
    chapter: Chapter,
    folder: Path,
    csv_path: Path,
    workers: int = 1,
    timeout_scale: float = 1.0,
    progress: bool = False,
    user: str | None = None,
    seed: int | None = None,
    lang: str | None = None,
) -> dict[str, dict]:
    """Grade every submission in ``folder`` the grader's record does not vouch for (see the
    module docstring); all rows by student. ``user``: whom the students' code runs as
    (``--student-user``); ``seed``: the grading seed of every student (None: a fresh one
    each, in the row's ``grading_seed``); ``lang``: the language of the messages (None: the
    active one, ``ptlab.course.messages``)."""
    student_user(user)  # (an unknown user, or one that cannot run ptlab: before anything)
    make_undumpable()
    import_nothing_from_here()
    work = find_work(folder, chapter)
    record = Record(csv_path, chapter)
    rows = record.vouched(read_rows(csv_path, chapter), work)
    write_rows(csv_path, chapter, rows)  # what the grader cannot vouch for goes at once
    record.keep(rows, work)
    todo = [w for w in work if w.student not in rows]
    outside = sandbox.not_for_credit()
    if todo and outside is not None:
        print(f"NOT FOR CREDIT: {outside}", file=sys.stderr)
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
    runner = _Runner(chapter, timeout_scale, limit, user, workers, seed, lang or active_language())
    try:
        with ProcessGuard() as guard, ThreadPoolExecutor(max(1, workers)) as pool:
            runner.guard = guard
            futures = {pool.submit(runner.grade, w): w for w in todo}
            for future in as_completed(futures):
                row = {k: safe_cell(v) for k, v in future.result().items()}
                rows[row["student"]] = row
                write_rows(csv_path, chapter, rows)
                record.keep(rows, work)
                bar.update()
    finally:
        if runner.groups is not None:
            runner.groups.remove()
    bar.close()
    return rows


class _Runner:
    """Grades one student at a time per thread, each in a grader process of its own.

    When the students' code runs as another user (the grader is root), each student graded
    at the same time gets a uid of their own (slots 1 to K of ``ptlab.course.sandbox.
    student_user.pool_user``): the kernel counts processes per uid, so a fork bomb that
    fills its limit leaves the other student's limit whole (and that of any other grader
    running students as the user itself), and neither may read the other's folder. Where
    the grader may make control groups (root), each slot's grader process and all it
    starts are a group with a CPU weight and quota, a memory limit and a process limit of
    their own (``ptlab.course.sandbox.control_groups``): spinning processes of one student take
    no more than their slot's share of the processors.
    """

    def __init__(
        self,
        chapter: Chapter,
        timeout_scale: float,
        limit: float,
        user: str | None = None,
        workers: int = 1,
        seed: int | None = None,
        lang: str = "en",
    ):
        self.chapter, self.timeout_scale, self.limit = chapter, timeout_scale, limit
        self.user, self.seed, self.lang = user, seed, lang
        self.slots: queue.SimpleQueue[int] | None = None
        self.groups: ControlGroups | None = None
        base = student_user(user)
        self.pooled = base is not None and workers > 1
        if workers > 1:
            self.slots = queue.SimpleQueue()
            for slot in range(1, workers + 1):  # (not the user itself, whom other graders may run)
                if self.pooled and base is not None:
                    pool_user(base, slot)  # (a pool that cannot be made: before anything)
                self.slots.put(slot)
            self.groups = ControlGroups.make(workers) if is_root() else None
            if self.groups is None:
                print(
                    "students graded at once share the CPU and the memory: this grader "
                    "cannot make control groups (only root can)",
                    file=sys.stderr,
                )
        self.guard: ProcessGuard | None = None
        self._lock = threading.Lock()
        self._running: set[int] = set()

    def grade(self, work: Work) -> dict:
        row: dict[str, object] = dict.fromkeys(columns(self.chapter), "")
        row.update(
            student=work.student,
            file=_file_name(work),
            score=0,
            max_score=sum(c.points for c in self.chapter.checks),
        )
        if work.file is None:
            row.update(first_failure=work.problem, seconds=0)
            return row
        start = time.monotonic()
        slot = None if self.slots is None else self.slots.get()
        try:
            report, problem = self._run(work, slot)
        finally:
            if slot is not None and self.slots is not None:
                self.slots.put(slot)
        row["seconds"] = f"{time.monotonic() - start:.1f}"
        if report is None:
            row["first_failure"] = problem
            return row
        results = {c["name"]: c for c in report["checks"]}
        row["score"], row["grading_seed"] = report["score"], report["grading_seed"]
        row["for_credit"] = "yes" if report.get("for_credit") is True else "no"
        for check in self.chapter.checks:
            row[check.name] = results[check.name]["points"]
        failed = [c for c in report["checks"] if not c["passed"]]
        row["first_failure"] = f"{failed[0]['name']}: {failed[0]['message']}" if failed else ""
        return row

    def _run(self, work: Work, slot: int | None = None) -> tuple[dict | None, str]:
        guard = self.guard
        if guard is None:
            raise RuntimeError("grade_all gives the runner its ProcessGuard before it grades")
        command = [
            sys.executable,
            "-I",
            "-m",
            "ptlab.course.batch",
            str(self.chapter.number),
            str(work.file),
            "--timeout-scale",
            repr(self.timeout_scale),
            "--lang",
            self.lang,
        ]
        if self.user is not None:
            command += ["--student-user", self.user]
        if slot is not None and self.pooled:
            command += ["--slot", str(slot)]
        if self.seed is not None:
            command += ["--grading-seed", str(self.seed)]
        if work.own_folder:
            command.append("--own-folder")
        with self._lock:
            process = subprocess.Popen(
                command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL
            )
            self._running.add(process.pid)
            if self.groups is not None and slot is not None:
                self.groups.join(slot, process.pid)
        try:
            output, _ = process.communicate(timeout=self.limit)
        except subprocess.TimeoutExpired:
            output = None
        finally:
            with self._lock:
                self._running.discard(process.pid)
                # The grader and whatever it left (re-parented here if it was killed).
                guard.end(process.pid, keep=self._running)
            process.wait()
        if output is None:
            return None, f"grading did not finish in {self.limit:.0f} s"
        if process.returncode != 0 or len(output) > MAX_REPORT:
            return None, f"the grader ended with code {process.returncode} and no report"
        return _report(output, self.chapter)


@dataclass(frozen=True)
class ClassAlike:
    """The pairs of alike students of a class, and who could not be compared.

    Attributes:
        pairs: ``Alike`` pairs of ``Work``s (``ptlab.course.alike.alike_pairs``).
        not_compared: the submissions (``submitted_file``) whose files could not be read
            for comparing: larger than ``MAX_COMPARED_BYTES`` or not Python.
    """

    pairs: list[tuple[Alike, Work, Work]]
    not_compared: list[str]


def default_alike_path(csv_path: Path) -> Path:
    """Where the alike pairs go when ``--alike`` is not given: beside the grades
    (``grades-07.csv``: ``grades-07-alike.csv``)."""
    return csv_path.with_name(f"{csv_path.stem}-alike.csv")


def alike_in_class(chapter: Chapter, folder: Path) -> ClassAlike:
    """The pairs of students of ``folder`` whose submissions for ``chapter`` are alike (the
    Python files of a student's folder are compared together, as they are graded)."""
    work = {w.student: w for w in find_work(folder, chapter) if w.file is not None}
    prints, not_compared = {}, []
    for student, found in work.items():
        file = found.file
        try:
            prints[student] = (
                fingerprints(read_files(file, with_folder=found.own_folder)) if file is not None else None
            )
        except RefusedSubmission:  # (gone since it was graded, or no longer a regular file)
            prints[student] = None
        if prints[student] is None:
            not_compared.append(submitted_file(found))
    pairs = alike_pairs({student: found for student, found in prints.items() if found is not None})
    return ClassAlike([(pair, work[pair.first], work[pair.second]) for pair in pairs], not_compared)


def submitted_file(work: Work) -> str:
    """A submission's file as the teacher finds it in the folder: ``alice.py``,
    ``bob/07_path_tracing.py`` (shown: control characters as escapes)."""
    if work.file is None or not work.own_folder:
        return work.entry
    return work.entry + shown(work.file.name)


def alike_lines(found: ClassAlike) -> list[str]:
    """What grade-all prints of the alike pairs, after the grades."""
    lines = [
        f"alike: {submitted_file(first)} and {submitted_file(second)}: {pair.similarity:.2f} "
        f"({pair.shared} of {min(pair.sizes)} fingerprints; look at them)"
        for pair, first, second in found.pairs
    ]
    if found.not_compared:
        lines.append(
            f"not compared (larger than {MAX_COMPARED_BYTES >> 10} KiB, or not Python): "
            + ", ".join(found.not_compared)
        )
    return lines


def write_alike(path: Path, found: ClassAlike) -> None:
    """The alike pairs as a CSV (``ALIKE_COLUMNS``), one row per pair, the most similar
    first; its cells made safe for spreadsheets (``safe_cell``)."""

    def write(temporary: str) -> None:
        with open(temporary, "w", newline="", encoding="utf-8") as out:
            writer = csv.writer(out)
            writer.writerow(ALIKE_COLUMNS)
            for pair, first, second in found.pairs:
                row: list[object] = [first.student, _file_name(first), second.student, _file_name(second)]
                row += [f"{pair.similarity:.3f}", pair.shared, *pair.sizes]
                writer.writerow([safe_cell(cell) for cell in row])

    write_atomically(path, write)


def _file_name(work: Work) -> str:
    """The name of a submission's file ("" for none)."""
    return "" if work.file is None else work.file.name


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

    from ptlab.course import chapter
    from ptlab.course.grader import grade
    from ptlab.course.inspect_command import graded_file

    parser = argparse.ArgumentParser(
        prog="python -m ptlab.course.batch", description="Grade one file; print the result as JSON."
    )
    parser.add_argument("chapter")
    parser.add_argument("file")
    parser.add_argument("--timeout-scale", type=float, default=1.0)
    parser.add_argument("--student-user")
    parser.add_argument("--slot", type=int, default=0, help="the uid of the pool's slot (see _Runner)")
    parser.add_argument("--grading-seed", type=int)
    parser.add_argument("--lang", choices=LANGUAGES)
    parser.add_argument(
        "--own-folder", action="store_true", help="the Python files beside FILE are the student's too"
    )
    args = parser.parse_args(argv)
    user = student_user(args.student_user)
    with graded_file(args.file):  # (as the teacher's folder names it)
        result = grade(
            chapter(args.chapter),
            Path(args.file),
            timeout_scale=args.timeout_scale,
            user=args.student_user if user is None else pool_user(user, args.slot),
            with_folder=args.own_folder,
            seed=args.grading_seed,
            lang=args.lang,
        )
    print(json.dumps(result.as_dict()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
