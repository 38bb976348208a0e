"""Which chapters a student has passed, remembered beside their exercise files.

``ptlab exercise check`` records each result in ``.ptlab-exercises.json`` in the checked
file's folder (after every process of the student's code has ended, atomically), one entry
per chapter and file, and
``ptlab exercise start`` remembers the folders it copies exercise files into (in
``$XDG_STATE_HOME/ptlab/exercise-folders.json``, by default under ``~/.local/state``).
``ptlab exercise list`` reads the records of the current folder and its subfolders (with
``--all``, of the remembered folders too: on a shared account, other people's), and says
where it looked, showing for each chapter its best file (``best``: a 10/10 is not hidden
by a 5/10 of another file checked later); ``--forget DIR`` drops a remembered folder.

The record beside the file is a convenience, not proof: whoever may write that folder may
write it. So the grader never reads it; each check replaces its file's entry for the chapter (a
pass is not kept once the file fails); an entry keeps the SHA-256 of the file it graded; and the
grader keeps its own copy of every entry it wrote, in its user's private state
(``$XDG_STATE_HOME/ptlab/results.json``, a folder only that user may enter): ``list`` says
"passed" only for an entry the grader's copy vouches for, while the file is still the one
that passed. A student's code that writes the record (it cannot when the grader is root:
it runs as another user), or a record copied from elsewhere, shows as "not vouched for".
A course grades by running the checks itself (``ptlab exercise grade-all``).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path

from ptlab.atomic import check_writable_folder, write_atomically
from ptlab.errors import PtlabError

RECORD = ".ptlab-exercises.json"
#: The grader's own copy of the entries it wrote, in its private state.
VOUCHED = "results.json"
#: How deep below the folder ``list`` looks, and how many folders it reads at most.
SEARCH_DEPTH = 3
SEARCH_FOLDERS = 2000
#: Folders never searched: tools' and environments' (a folder holding pyvenv.cfg is a venv).
SKIPPED = {"__pycache__", "node_modules", "site-packages", "build", "dist"}


def read_record(folder: Path) -> dict[str, dict[str, dict]]:
    """{"NN": {file name: {"score", "max_score", "full_marks", "file", "sha256", "when"}}}
    ({} if none). A record of one entry per chapter (written before a chapter could hold
    several files) reads as that entry under its file's name."""
    try:
        record = json.loads((folder / RECORD).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return {}
    if not isinstance(record, dict):
        return {}
    chapters: dict[str, dict[str, dict]] = {}
    for key, files in record.items():
        if isinstance(files, dict) and "score" in files:
            files = {str(files.get("file", "")): files}
        if isinstance(files, dict):
            chapters[key] = {name: entry for name, entry in files.items() if isinstance(entry, dict)}
    return chapters


def remember(grade) -> Path | None:
    """Record a ``Grade`` in its file's folder, and vouch for it in the grader's own state;
    the path written, or None if not written."""
    folder = Path(grade.file).resolve().parent
    if folder.is_relative_to(Path(__file__).resolve().parent):
        return None  # the library's own answers are not a student's progress
    entry = dict(
        score=grade.score,
        max_score=grade.max_score,
        full_marks=grade.full_marks,
        file=Path(grade.file).name,
        sha256=grade.sha256,
        when=time.strftime("%Y-%m-%d %H:%M:%S"),
    )
    key = f"{grade.chapter:02d}"
    _vouch(folder / entry["file"], key, entry)
    record = read_record(folder)
    record.setdefault(key, {})[entry["file"]] = entry
    try:
        return _write_json(folder / RECORD, record)
    except OSError as error:  # a read-only folder: the grade itself still stands
        print(f"ptlab: note: could not record the result in {folder / RECORD}: {error}")
        return None


# -- the grader's own copy --------------------------------------------------------------


def state_folder() -> Path:
    """Where this user's ptlab state lives: ``$XDG_STATE_HOME/ptlab``, by default under
    ``~/.local/state`` (the XDG Base Directory Specification)."""
    return Path(os.environ.get("XDG_STATE_HOME") or Path.home() / ".local" / "state") / "ptlab"


def private_state() -> Path:
    """The grader's own state folder, made if need be, that only its user may enter."""
    folder = state_folder()
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    folder.chmod(0o700)
    return folder


def check_private_state() -> Path:
    """``private_state``, checked writable; a ``PtlabError`` naming the way out if not (a
    home folder this user may not write: ``XDG_STATE_HOME``)."""
    try:
        return check_writable_folder(private_state())
    except (OSError, PtlabError) as error:
        why = error.strerror if isinstance(error, OSError) else str(error)
        raise PtlabError(
            f"{state_folder()}: the grader's private state folder cannot be made or written "
            f"({why}); set XDG_STATE_HOME to a folder this user owns"
        ) from None


def _vouched() -> dict:
    try:
        found = json.loads((private_state() / VOUCHED).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return {}
    return found if isinstance(found, dict) else {}


def _vouch(file: Path, key: str, entry: dict) -> None:
    try:
        vouched = _vouched()
        vouched.setdefault(str(file), {})[key] = entry
        _write_json(private_state() / VOUCHED, vouched)
    except OSError:  # no state folder here: the record shows as not vouched for
        pass


def vouched_for(entry: dict, folder: Path, key: str) -> bool:
    """Whether the grader's own copy holds exactly ``entry`` for chapter ``key`` there."""
    return _vouched().get(str(folder / str(entry.get("file", ""))), {}).get(key) == entry


def _write_json(path: Path, value) -> Path:
    def write(temporary: str) -> None:
        Path(temporary).write_text(json.dumps(value, indent=2, sort_keys=True) + "\n")

    return write_atomically(path, write)


# -- the folders ``start`` made ---------------------------------------------------------


def state_file() -> Path:
    """Where the folders ``ptlab exercise start`` copied files into are remembered."""
    return state_folder() / "exercise-folders.json"


def started_folders() -> list[Path]:
    """The folders ``ptlab exercise start`` copied exercise files into (that still exist)."""
    try:
        names = json.loads(state_file().read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return []
    if not isinstance(names, list):
        return []
    return [Path(name) for name in names if isinstance(name, str) and Path(name).is_dir()]


def remember_folder(folder: Path) -> None:
    """Add ``folder`` to the folders ``list`` looks in (quietly skipped where unwritable)."""
    names = [str(p) for p in started_folders()]
    wanted = str(folder.resolve())
    if wanted in names:
        return
    try:
        state_file().parent.mkdir(parents=True, exist_ok=True)
        _write_json(state_file(), [*names, wanted])
    except OSError:
        pass


def forget_folder(folder: Path) -> None:
    """Stop remembering ``folder`` (``list --all`` no longer looks there)."""
    names = [str(p) for p in started_folders()]
    wanted = str(folder.resolve())
    if wanted not in names:
        raise PtlabError(f"{folder}: not a folder 'ptlab exercise start' remembers")
    _write_json(state_file(), [name for name in names if name != wanted])


# -- finding the records ---------------------------------------------------------------


def folders_below(top: Path) -> list[Path]:
    """``top`` and its subfolders down to ``SEARCH_DEPTH`` (not hidden ones, caches or
    virtual environments), at most ``SEARCH_FOLDERS`` of them."""
    found, level = [], [top]
    for _ in range(SEARCH_DEPTH + 1):
        found.extend(level)
        below: list[Path] = []
        for folder in level:
            try:
                entries = sorted(folder.iterdir())
            except OSError:
                continue
            below.extend(
                entry
                for entry in entries
                if entry.is_dir()
                and not entry.is_symlink()
                and not entry.name.startswith(".")
                and entry.name not in SKIPPED
                and not (entry / "pyvenv.cfg").exists()
            )
        level = below[: max(0, SEARCH_FOLDERS - len(found))]
    return found


def find_progress(folders: list[Path]) -> tuple[dict[str, list[tuple[dict, Path]]], list[Path]]:
    """({"NN": [(entry, folder), ...]} with every file's entry of each chapter, the record
    files read)."""
    found: dict[str, list[tuple[dict, Path]]] = {}
    read = []
    for folder in dict.fromkeys(f.resolve() for f in folders):
        if not (folder / RECORD).is_file():
            continue
        read.append(folder / RECORD)
        for key, files in read_record(folder).items():
            found.setdefault(key, []).extend((entry, folder) for entry in files.values())
    return found, read


def best(entries: list[tuple[dict, Path]], key: str) -> tuple[dict, Path]:
    """The entry of chapter ``key`` a student looks for among the files checked for it: one
    that still stands (``doubt`` finds nothing) before one that does not, then the highest
    share of the points, then the latest."""

    def rank(found: tuple[dict, Path]) -> tuple[bool, float, str]:
        entry, folder = found
        try:
            share = float(entry.get("score", 0)) / float(entry.get("max_score", 0))
        except (TypeError, ValueError, ZeroDivisionError):
            share = 0.0
        return doubt(entry, folder, key) is None, share, str(entry.get("when", ""))

    return max(entries, key=rank)


def doubt(entry: dict, folder: Path, key: str) -> str | None:
    """Why chapter ``key``'s recorded entry no longer stands (not vouched for by this
    user's grader, its file gone or changed since), or None if it stands."""
    if not vouched_for(entry, folder, key):
        return "not vouched for"
    try:
        content = (folder / str(entry.get("file", ""))).read_bytes()
    except OSError:
        return "file gone"
    return None if hashlib.sha256(content).hexdigest() == entry.get("sha256") else "file changed since"


def status(entry: dict, folder: Path, key: str) -> str:
    """How chapter ``key``'s recorded entry stands: passed (if the file is unchanged),
    points, changed, or not vouched for by this user's grader."""
    points = f"{entry.get('score')}/{entry.get('max_score')}"
    why = doubt(entry, folder, key)
    if why is not None:
        return f"{points}, {why}"
    return f"passed ({points})" if entry.get("full_marks") is True else f"{points} points"
