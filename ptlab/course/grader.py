"""Running a chapter's checks on a student's file, like a course autograder.

Student code only computes; trusted code judges. Every check runs here, in the grader's
process, on a stand-in for the student's module: the student's file is read once, then
imported, and each of its functions runs, in a process of its own
(``ptlab.course.sandbox.Submission``, a fresh one per check, in a private folder, as the student
user when the grader is root), which sends back plain data only. So nothing the student's
code does (patching NumPy or the checks, writing to the grader's pipes, exiting early) can
touch a verdict.

Every check is worth some points and has a time limit: a student's function that loops
forever, crashes its process or sends nonsense costs that check's points, and the grader
goes on to the next one. A check of a secondary property (``ChapterCheck.requires``) scores
only when the checks of the core behaviour it builds on passed. A check is a plain function
of the student's module: it returns a short note of what it measured, or raises
``CheckFailed`` with a message for the student. An exception the student's code raised
becomes the check's message too (the error, and the line of the student's file it came
from), never a traceback. Every process the student's code started is ended before ``grade``
returns, and so before any result is written.
"""

from __future__ import annotations

import time
import unicodedata
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from ptlab.course.chapter import CheckFailed, active_grading_seed, grading_seed, new_grading_seed
from ptlab.course.messages import check_name, language, text
from ptlab.course.sandbox import (
    ImportFailed,
    ProcessGuard,
    RefusedSubmission,
    StudentError,
    StudentUser,
    Submission,
    SubmissionFailed,
    Taken,
    import_nothing_from_here,
    make_undumpable,
    sandbox,
    student_user,
    take_in,
)
from ptlab.course.sandbox.kit import kit_for
from ptlab.course.sandbox.shown import shown, shown_line
from ptlab.errors import PtlabError

#: Seconds the whole grading may take beyond the sum of its checks' limits (making the
#: kit, the library's own renders).
OVERALL_SLACK = 60.0
#: The longest message a check reports (the rest is cut off).
MAX_MESSAGE = 1000


def overall_limit(chapter, timeout_scale: float = 1.0) -> float:
    """Seconds the grading of one file for ``chapter`` may take in all: its checks' limits,
    scaled, and ``OVERALL_SLACK``."""
    return sum(check.timeout for check in chapter.checks) * timeout_scale + OVERALL_SLACK


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
    """Every check of one chapter on one file.

    Attributes:
        sha256: the file's content as graded (hex), so that a record of the grade can tell
            whether the file changed since.
        grading_seed: the seed every check drew its inputs from (fresh for each grading:
            ``--grading-seed`` grades again with the same inputs, for the same verdict).
        lang: the language of the messages and of the table ("en", "zh";
            ``ptlab.course.messages``).
        not_for_credit: why the results do not count (``ptlab.course.sandbox.sandbox.
            not_for_credit``: no sandbox here, or a grader that is not root), or "".
    """

    chapter: int
    title: str
    file: str
    results: list[CheckResult]
    sha256: str = ""
    grading_seed: int = 0
    lang: str = "en"
    not_for_credit: str = ""

    @property
    def for_credit(self) -> bool:
        return not self.not_for_credit

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
        return dict(
            chapter=self.chapter,
            title=self.title,
            file=self.file,
            score=self.score,
            max_score=self.max_score,
            full_marks=self.full_marks,
            sha256=self.sha256,
            grading_seed=self.grading_seed,
            lang=self.lang,
            for_credit=self.for_credit,
            **({"not_for_credit": self.not_for_credit} if self.not_for_credit else {}),
            checks=[asdict(r) for r in self.results],
        )

    def table(self) -> str:
        """The score table, one row per check, as a course autograder prints it, in the
        grading's language (its headings and the checks' names; the messages already are)."""
        with language(self.lang):
            return self._table()

    def _table(self) -> str:
        names = [check_name(self.chapter, r.name) for r in self.results]
        width = max(display_width(name) for name in [text("table.check"), text("table.total"), *names])
        title = text(f"ch{self.chapter:02d}.title")
        lines = [text("table.chapter", number=self.chapter, title=title, file=shown(self.file)), ""]
        check, points, verdict = text("table.check"), text("table.points"), text("table.verdict")
        points = padded(points, 7, right=True)
        lines.append(f"  {padded(check, width)}  {points}  {padded(verdict, 7)}  {text('table.message')}")
        for name, r in zip(names, self.results, strict=True):
            verdict = text("table.pass") if r.passed else text("table.fail")
            message = table_message(r.message)
            score = f"{r.points:>3}/{r.max_points:<3}"
            lines.append(f"  {padded(name, width)}  {score}  {padded(verdict, 7)}  {message}")
        # (on the total's line: the table keeps a line per check, and two more)
        full_marks = text("table.full_marks") if self.full_marks else ""
        lines.append(
            f"  {padded(text('table.total'), width)}  {self.score:>3}/{self.max_score:<3}  "
            + text("table.seed", full_marks=full_marks, seed=self.grading_seed)
        )
        if self.not_for_credit:
            lines.append("  " + text("table.not_for_credit", why=self.not_for_credit))
        return "\n".join(lines)


def display_width(line: str) -> int:
    """How many columns ``line`` takes on a terminal: wide (Chinese) characters take two."""
    return sum(2 if unicodedata.east_asian_width(c) in "WF" else 1 for c in line)


def padded(line: str, width: int, right: bool = False) -> str:
    """``line`` padded with spaces to ``width`` columns (``display_width``), on the right or,
    with ``right``, on the left."""
    spaces = " " * max(0, width - display_width(line))
    return spaces + line if right else line + spaces


def grade(
    chapter,
    path: str | Path,
    timeout_scale: float = 1.0,
    echo: Callable[[str], None] | None = None,
    on_output: Callable[[str], None] | None = None,
    user: str | StudentUser | None = None,
    with_folder: bool = True,
    library_answer: bool = False,
    seed: int | None = None,
    lang: str | None = None,
) -> Grade:
    """Run every check of ``chapter`` (a ``ptlab.course.Chapter``) on the file ``path``.

    Args:
        timeout_scale: multiplies every check's time limit (slow machines).
        echo: called with a line per check as it finishes.
        on_output: called with each line the student's code prints (default: dropped).
        user: the user the student's code runs as (``--student-user``, or a ``StudentUser``
            such as grade-all's ``pool_user``; None: ``nobody`` when this process is root,
            else its own user).
        with_folder: the Python files beside ``path`` are the student's too (a folder of
            their own), and are copied with it; else ``path`` alone.
        library_answer: ``path`` is the chapter's own answer file, graded as itself (the
            tests and the graders' measurements; never a student's file).
        seed: the grading seed, which every check draws its inputs and render seeds from
            (``ptlab.course.chapter.grading_rng``); None: a fresh one, so that no answer
            computed beforehand for known inputs can be replayed. A recorded seed gives the
            same inputs again.
        lang: the language of the messages ("en", "zh"; ``ptlab.course.messages``);
            None: the active one (``--lang``, else the locale's).

    Raises:
        PtlabError: no such file, or no such ``user`` (or one that cannot run ptlab).
    """
    with language(lang) as lang:
        return _grade(
            chapter, Path(path), timeout_scale, echo, on_output, user, with_folder, library_answer, seed, lang
        )


def _grade(
    chapter, path, timeout_scale, echo, on_output, user, with_folder, library_answer, seed, lang
) -> Grade:
    if not path.is_file():
        raise PtlabError(f"{path}: no such file")
    if library_answer and path.resolve() != chapter.solution.resolve():
        raise PtlabError(f"{path}: not chapter {chapter.number}'s own answer file")
    student_user(user)  # (an unknown user, or one that cannot run ptlab: before anything)
    make_undumpable()
    import_nothing_from_here()
    rules = chapter.library_rules if library_answer else chapter.rules
    _import_what_checks_use(rules)
    taken: Taken | str
    try:
        taken = take_in(path, with_folder=with_folder, library=library_answer)
        sha256 = taken.sha256
    except RefusedSubmission as refused:  # (its bytes are not read: it may be a link)
        taken, sha256 = str(refused), ""
    seed = new_grading_seed() if seed is None else seed
    overall = overall_limit(chapter, timeout_scale)
    deadline = time.monotonic() + overall
    results = []
    earlier: dict[str, CheckResult] = {}
    with ProcessGuard() as guard, grading_seed(seed):
        for check in chapter.checks:
            unmet = [earlier[name] for name in check.requires if not earlier[name].passed]
            left = deadline - time.monotonic()
            if isinstance(taken, str):
                result = CheckResult(check.name, 0, check.points, False, table_message(taken), 0.0)
            elif left <= 0:
                result = CheckResult(
                    check.name,
                    0,
                    check.points,
                    False,
                    text("grader.overall_limit", seconds=overall),
                    0.0,
                )
            elif unmet and not check.quick:  # (a render: its message is not worth the wait)
                message = text(
                    "grader.gated_says",
                    not_graded=not_graded_until(chapter.number, unmet),
                    name=check_name(chapter.number, unmet[0].name),
                    message=unmet[0].message,
                )
                result = CheckResult(check.name, 0, check.points, False, table_message(message), 0.0)
            else:
                result, hung = run_check(
                    check, taken, min(check.timeout * timeout_scale, left), guard, on_output, rules, user
                )
                if hung:  # every later check would wait as long again for nothing
                    taken = text("grader.not_run", message=result.message)
                if unmet:
                    result = gated(chapter.number, result, unmet)
            earlier[check.name] = result
            if echo is not None:
                verdict = text("table.pass") if result.passed else text("table.fail")
                name = check_name(chapter.number, result.name)
                echo(f"  {verdict}  {name} ({result.seconds:.1f} s)")
            results.append(result)
    outside = sandbox.not_for_credit()
    return Grade(chapter.number, chapter.title, str(path), results, sha256, seed, lang, str(outside or ""))


def _import_what_checks_use(rules) -> None:
    """Import now what the checks would import lazily: the renderer, the mesh and statistics
    libraries (trimesh and SciPy take a second or more), and the answers' fingerprints.
    Nothing is imported once a student's process runs, which could plant modules where an
    import would look (the current folder, were it on ``sys.path``)."""
    import scipy.special
    import scipy.stats  # noqa: F401
    import trimesh  # noqa: F401

    import ptlab.rendering  # noqa: F401

    rules.fingerprints  # noqa: B018 (computed and kept)
    kit_for(rules.left_out)  # (made once, before any check's time runs)


def run_check(
    check,
    submission: str | Path | Taken,
    timeout: float,
    guard: ProcessGuard,
    on_output: Callable[[str], None] | None = None,
    rules=None,
    user: str | StudentUser | None = None,
) -> tuple[CheckResult, bool]:
    """Run one check on a fresh process of the student's submission, stopped after
    ``timeout`` s. Returns the result, and whether importing the file took too long. The
    check draws its inputs from the grading seed under way (``grade``'s), or from a fresh
    one of its own if none is."""
    start = time.perf_counter()
    passed, hung = False, False
    seed = active_grading_seed()
    try:
        with (
            grading_seed(new_grading_seed() if seed is None else seed),
            Submission(
                submission, guard, time_limit=timeout, on_output=on_output, rules=rules, user=user
            ) as running,
        ):
            message, passed = str(check.run(running.module)), True
    except CheckFailed as failure:
        message = str(failure)
    except StudentError as error:
        message = described(error)
    except ImportFailed as failure:
        message, hung = str(failure), failure.kind == "import timeout"
    except SubmissionFailed as failure:
        message = str(failure)
        if failure.kind == "timeout":
            message = text("grader.timeout", seconds=timeout, during=failure.during)
    except PtlabError as error:
        message = str(error)
    except Exception as error:  # the checks' code failed on what the student's code returned
        message = text("grader.outside", error_type=type(error).__name__, error=error)
    return CheckResult(
        check.name,
        check.points if passed else 0,
        check.points,
        passed,
        table_message(message),
        time.perf_counter() - start,
    ), hung


def described(error: StudentError) -> str:
    """One line for the student of an exception their code raised: the error, its message and
    where it came from (``StudentError.describe``, in the active language; the error's
    class is named after the student's, a subclass of ``StudentError``). A verdict of the
    harness's (an argument changed, a library answer called) keeps its own words."""
    if type(error).describe is not StudentError.describe or error.type_name == "LibraryAnswerCalled":
        return error.describe()
    place = error.where or text("grader.outside_place")
    if error.not_implemented:
        return text("grader.not_written", name=f"{error} " if str(error) else "", place=place)
    return text("grader.student_error", error_type=error.type_name, error=error, place=place)


def not_graded_until(chapter: int, unmet: list[CheckResult]) -> str:
    """Why a check scores nothing: the checks of the core behaviour it builds on failed."""
    names = text("grader.and").join(text("quoted", name=check_name(chapter, r.name)) for r in unmet)
    return text("grader.not_graded_until_one" if len(unmet) == 1 else "grader.not_graded_until", names=names)


def gated(chapter: int, result: CheckResult, unmet: list[CheckResult]) -> CheckResult:
    """``result`` of a check whose requirements ``unmet`` failed: no points, and a message
    that says why and what the check found by itself (a property a trivial answer may
    share, so it earns nothing alone)."""
    message = text(
        "grader.gated_passes" if result.passed else "grader.gated_fails",
        not_graded=not_graded_until(chapter, unmet),
        message=result.message,
    )
    return replace(result, points=0, passed=False, message=table_message(message))


def table_message(text: str) -> str:
    """``text`` as one printable line of at most ``MAX_MESSAGE`` characters (a message may
    quote what the student's code said, or a file name, which must not forge lines of the
    table): runs of white space, newlines included, become one space; every other
    character a terminal could act on is shown as its escape (``ptlab.course.sandbox.shown``).
    A longer one loses its middle (``cut_middle``), not its end, where the command to run
    next is said."""
    return cut_middle(shown_line(text, len(text) * 10 + 3), MAX_MESSAGE)


#: What stands where ``cut_middle`` cut a message.
CUT = " ... "
#: Where a message's last sentence or clause starts: after the last of these.
SENTENCE_ENDS = (". ", "; ", "。", "；")


def cut_middle(line: str, limit: int) -> str:
    """``line`` if at most ``limit`` characters long, else its start and its last sentence
    (at most half of ``limit``) with ``CUT`` between them, ``limit`` characters in all: a
    message ends with what to run next (a ``ptlab exercise inspect`` command, the harness's
    ``ptlab grade``), which a cut at the end would lose."""
    if len(line) <= limit:
        return line
    start = max(line.rfind(end) + len(end) if end in line else 0 for end in SENTENCE_ENDS)
    tail = line[max(start, len(line) - limit // 2) :]
    return line[: limit - len(CUT) - len(tail)] + CUT + tail
