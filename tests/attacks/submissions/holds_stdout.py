"""An attack: at import, start processes in sessions of their own that keep the grader's
output open (the inherited stdout, and the grader's stdout reached through the parent
process's file descriptors): whoever reads the grader's output (a course's script, a pipe)
then waits until they end. Each writes its pid to ``holds_stdout.pids`` beside this file."""

import os
import subprocess
import sys
import time
from pathlib import Path

PIDS = Path(__file__).resolve().with_suffix(".pids")
HOLD = f"import os, time; open({str(PIDS)!r}, 'a').write(str(os.getpid()) + chr(10)); time.sleep(60)"

subprocess.Popen([sys.executable, "-c", HOLD], start_new_session=True)
try:
    _parents_stdout = os.open(f"/proc/{os.getppid()}/fd/1", os.O_WRONLY)
    subprocess.Popen([sys.executable, "-c", HOLD], start_new_session=True,
                     stdout=_parents_stdout, stderr=_parents_stdout)
except OSError:
    pass
for _ in range(500):        # until they have started (so that the test knows them)
    if PIDS.exists() and len(PIDS.read_text().split()) >= 2:
        break
    time.sleep(0.01)


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
