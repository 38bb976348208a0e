"""Which chapters a student has passed, remembered in their exercise folder.

``ptlab exercise check`` records each result in ``.ptlab-exercises.json`` beside the checked
file; ``ptlab exercise list`` reads it back. The record is a convenience for the student;
a course grades by running the checks itself.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from ptlab.atomic import write_atomically

RECORD = ".ptlab-exercises.json"


def read_record(folder: Path) -> dict:
    """{"NN": {"score", "max_score", "full_marks", "file", "when"}} for a folder ({} if none)."""
    path = folder / RECORD
    try:
        record = json.loads(path.read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return {}
    return record if isinstance(record, dict) else {}


def remember(grade) -> None:
    """Add a ``Grade`` to the record in its file's folder (a chapter once passed stays passed)."""
    folder = Path(grade.file).resolve().parent
    if folder.is_relative_to(Path(__file__).resolve().parent):
        return              # the library's own answers are not a student's progress
    record = read_record(folder)
    key = f"{grade.chapter:02d}"
    previous = record.get(key, {})
    if previous.get("full_marks") and not grade.full_marks:
        return
    record[key] = dict(score=grade.score, max_score=grade.max_score,
                       full_marks=grade.full_marks, file=Path(grade.file).name,
                       when=time.strftime("%Y-%m-%d %H:%M"))

    def write(temporary: str) -> None:
        Path(temporary).write_text(json.dumps(record, indent=2, sort_keys=True) + "\n")

    try:
        write_atomically(folder / RECORD, write)
    except OSError as error:        # a read-only folder: the grade itself still stands
        print(f"ptlab: note: could not record the result in {folder / RECORD}: {error}")
