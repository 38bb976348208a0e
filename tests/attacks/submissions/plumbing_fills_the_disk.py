"""Fills every place it may write with files of 1 MiB until the writes fail, and says how
far it got: the old graders' private folder was on the grader's disk, with no bound but
the size of one file, and folders of 10 000 files were left behind when they ended."""

import os

for place in (".", "/tmp", "/var/tmp", "/dev/shm"):
    written = 0
    try:
        for k in range(100_000):
            with open(os.path.join(place, f"fill{k}"), "wb") as file:
                file.write(b"\0" * (1 << 20))
            written += 1
    except OSError as error:
        print(f"filled {place}: {written} MiB, then errno {error.errno}", flush=True)
raise SystemExit("filled")
