"""An attack: at import, fork processes into sessions of their own that keep open the
output the student's process was given, and the grader's stdout reached through the parent
process's file descriptors (/proc/<parent>/fd/1): whoever reads the grader's output (a
course's script, a pipe) would then wait until they end. Each prints its pid, which the
test reads from the student's output."""

import os
import sys
import time

try:
    _parents_stdout = os.open(f"/proc/{os.getppid()}/fd/1", os.O_WRONLY)
except OSError:
    _parents_stdout = None
for _ in range(2):
    if os.fork() == 0:
        os.setsid()
        if _parents_stdout is not None:
            os.dup2(_parents_stdout, 1)
        print(os.getpid(), flush=True)
        os.write(2, f"{os.getpid()}\n".encode())
        time.sleep(60)
        os._exit(0)
time.sleep(0.2)
sys.stdout.flush()


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    raise NotImplementedError("generate_rays")
