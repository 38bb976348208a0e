"""Keeping freed memory in the process, so NumPy's big temporaries cost no page faults.

Every bounce allocates and frees dozens of arrays of a few megabytes. By default glibc
serves those with ``mmap`` and gives them back to the kernel on ``free``, so the next
bounce faults every page in again. Raising the mmap threshold (to glibc's 32 MiB maximum
on 64-bit) and the trim threshold keeps that memory in the heap for reuse: a fifth to a
third less render time (docs/performance.md). Peak memory is unchanged; only returning it
to the system is delayed.
"""

from __future__ import annotations

import ctypes
import ctypes.util

# mallopt parameters from glibc's <malloc.h>.
M_TRIM_THRESHOLD = -1
M_TOP_PAD = -2
M_MMAP_THRESHOLD = -3

_tuned = False


def keep_freed_memory() -> bool:
    """Tune glibc's allocator as described above, once per process.

    Returns True if it was applied (glibc found), False elsewhere (macOS, musl, Windows).
    """
    global _tuned
    if _tuned:
        return True
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt(M_MMAP_THRESHOLD, 32 << 20)
    mallopt(M_TRIM_THRESHOLD, 1 << 30)
    mallopt(M_TOP_PAD, 64 << 20)
    _tuned = True
    return True
