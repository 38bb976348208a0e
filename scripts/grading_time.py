"""How long grading takes per check: this checkout against another, alternately.

First the fixed cost of a check: a student's process started, a two-line file imported,
one call, the process ended (the median of 20). Then each round grades the library's own
answer of each chapter named (``--chapters``) once with each ptlab (this checkout's, and
``--against FOLDER``'s, e.g. a ``git worktree`` of an earlier commit), in processes of
their own, in turn, and prints the seconds per check and the ratio of the two with its
spread over the rounds:

    git worktree add /tmp/ptlab-before 0aefaa3
    python scripts/grading_time.py --against /tmp/ptlab-before --chapters 1 6 7 --rounds 3

Grading a chapter's own answer runs every check to the end (no check is skipped for an
earlier failure), so both sides do the same work.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
#: What each side runs: grade a chapter's own answer file, print seconds and checks as JSON.
PROBE = """
import json, sys, time
from ptlab.course import chapter
from ptlab.course.grader import grade
number = int(sys.argv[1])
start = time.perf_counter()
result = grade(chapter(number), chapter(number).solution, library_answer=True, seed=1)
seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "checks": len(result.results), "full": result.full_marks}))
"""


#: What each side runs for the fixed cost of a check: start the student's process, import a
#: two-line file, call it once, end it; 20 times (after one to warm up), median seconds.
START_PROBE = """
import json, statistics, sys, tempfile, time
from pathlib import Path
from ptlab.course import chapter
from ptlab.course.sandbox import ProcessGuard, Submission
path = Path(tempfile.mkdtemp()) / "01_cameras.py"
path.write_text("def generate_rays(*arguments):\\n    return 1\\n")
seconds = []
with ProcessGuard() as guard:
    for _ in range(21):
        start = time.perf_counter()
        with Submission(path, guard, time_limit=30, rules=chapter(1).rules) as submission:
            submission.module.generate_rays()
        seconds.append(time.perf_counter() - start)
print(json.dumps({"seconds": statistics.median(seconds[1:]), "checks": 1, "full": True}))
"""


def started(tree: Path) -> float:
    """Median seconds to start, import, call once and end a student's process with the
    ptlab in ``tree``."""
    return _run(tree, START_PROBE)[0]


def timed(tree: Path, number: int) -> tuple[float, int]:
    """Seconds to grade chapter ``number``'s own answer with the ptlab in ``tree``, and its
    number of checks."""
    return _run(tree, PROBE, str(number))


def _run(tree: Path, probe: str, *arguments: str) -> tuple[float, int]:
    ran = subprocess.run(
        [sys.executable, "-c", probe, *arguments],
        env=dict(os.environ, PYTHONPATH=str(tree)),
        cwd=tree,
        capture_output=True,
        text=True,
        check=False,
    )
    if ran.returncode != 0:
        raise SystemExit(f"{tree}: {' '.join(arguments)} failed: {ran.stderr.strip()[-500:]}")
    found = json.loads(ran.stdout.strip().splitlines()[-1])
    if not found["full"]:
        raise SystemExit(f"{tree}: chapter {arguments[0]}'s own answer did not get full marks")
    return found["seconds"], found["checks"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--against", type=Path, required=True, metavar="FOLDER", help="another ptlab checkout"
    )
    parser.add_argument("--chapters", type=int, nargs="+", default=[1, 6, 7], help="chapters (1 6 7)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of both sides (3)")
    args = parser.parse_args()
    for _ in range(args.rounds):
        mine, theirs = started(HERE), started(args.against.resolve())
        print(f"a student's process started, imported, called, ended: {mine * 1000:.0f} ms", end="")
        print(f", other {theirs * 1000:.0f} ms")
    print(f"{'chapter':>7}  {'checks':>6}  {'this s/check':>12}  {'other s/check':>13}  ratio (min-max)")
    for number in args.chapters:
        ratios, here, there = [], [], []
        for _ in range(args.rounds):
            mine, checks = timed(HERE, number)
            theirs, _ = timed(args.against.resolve(), number)
            here.append(mine / checks)
            there.append(theirs / checks)
            ratios.append(mine / theirs)
        print(
            f"{number:>7}  {checks:>6}  {statistics.median(here):>12.2f}  "
            f"{statistics.median(there):>13.2f}  {statistics.median(ratios):.2f} "
            f"({min(ratios):.2f}-{max(ratios):.2f})"
        )


if __name__ == "__main__":
    main()
