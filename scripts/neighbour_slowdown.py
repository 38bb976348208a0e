"""How much a submission that spins the CPU slows the student graded beside it.

``ptlab exercise grade-all N FOLDER --workers 2`` grades two students at once. This grades
a right answer of chapter 1 (``tests/exercises/01_right_own_code.py``) beside a copy of it, then beside a
submission that starts 40 spinning processes in every check, alternately, ``--rounds``
times, and prints the honest student's grading time in each case (grade-all's ``seconds``
column) and their ratio:

    python scripts/neighbour_slowdown.py --rounds 3

As root, on a machine with control groups, each student's grader and all it starts share one
CPU weight (``ptlab/course/sandbox/control_groups.py``), so the ratio should stay near 1.
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

#: A right answer of chapter 1, written as a student would.
HONEST = Path(__file__).resolve().parents[1] / "tests" / "exercises" / "01_right_own_code.py"
#: A submission whose every process starts 40 processes that spin for a minute, and whose
#: function then waits out the check's time limit: it spins through all of the other's
#: grading.
SPINNER = """
import os, time
for _ in range(40):
    if os.fork() == 0:
        end = time.monotonic() + 60
        while time.monotonic() < end:
            pass
        os._exit(0)


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    time.sleep(600)
"""


def honest_seconds(neighbour: str) -> float:
    """Seconds grade-all took to grade the honest student beside ``neighbour``'s source."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "in"
        folder.mkdir()
        (folder / "honest.py").write_text(HONEST.read_text())
        (folder / "neighbour.py").write_text(neighbour)
        out = Path(scratch) / "grades.csv"
        command = ["exercise", "grade-all", "1", str(folder), "--csv", str(out), "--workers", "2"]
        command += ["--timeout-scale", "0.3"]  # (the spinner waits out each check's limit)
        subprocess.run(
            [sys.executable, "-m", "ptlab.cli", *command],
            cwd=scratch,
            capture_output=True,
            check=False,
            env=dict(os.environ, XDG_STATE_HOME=scratch),
        )
        rows = {row["student"]: row for row in csv.DictReader(out.open())}
        return float(rows["honest"]["seconds"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3, help="rounds of both cases (3)")
    args = parser.parse_args()
    quiet, spinning, ratios = [], [], []
    honest = HONEST.read_text()
    for _ in range(args.rounds):
        quiet.append(honest_seconds(honest))
        spinning.append(honest_seconds(SPINNER))
        ratios.append(spinning[-1] / quiet[-1])
        print(f"beside an honest student {quiet[-1]:.1f} s, beside the spinner {spinning[-1]:.1f} s")
    print(
        f"slowdown {statistics.median(ratios):.2f}x (min {min(ratios):.2f}, max {max(ratios):.2f}) "
        f"over {args.rounds} rounds"
    )


if __name__ == "__main__":
    main()
