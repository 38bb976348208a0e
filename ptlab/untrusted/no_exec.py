"""No programs from the student's process: the kernel refuses ``execve`` to it and to all it forks.

A process that may start programs may start a fresh Python, which has none of the grader's
traps and rules (``ptlab.untrusted.traps``, ``ptlab.untrusted.confinement``) and can import
ptlab's own answers, run them for the student's code (a process pool whose workers are new
interpreters does it in three lines), or read any file the student's user may read. So,
except where a chapter's subject is starting processes (chapter 8's pools of clean workers),
the student's process installs a seccomp filter (seccomp(2), ``SECCOMP_SET_MODE_FILTER``)
that fails ``execve`` and ``execveat`` with EPERM. Filters are inherited by every child and
cannot be removed, and installing one needs no privilege once ``PR_SET_NO_NEW_PRIVS`` is set.
Forking stays allowed: a forked child has the same traps and rules.

The filter is a classic BPF program of nine instructions (linux/filter.h, linux/seccomp.h):
load the system call's architecture, refuse every call of a foreign one (32-bit calls on a
64-bit kernel number their calls differently); load the call's number, refuse the x32 ABI's
calls (numbered from 2^30) and the two exec calls; allow the rest.
"""

from __future__ import annotations

import ctypes
import errno
import platform
import struct

PR_SET_NO_NEW_PRIVS = 38
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2
SECCOMP_RET_ALLOW = 0x7FFF0000
SECCOMP_RET_ERRNO = 0x00050000

# BPF opcodes: load a 32-bit word at an offset of struct seccomp_data; jumps; return.
LOAD_WORD = 0x20  # BPF_LD | BPF_W | BPF_ABS
JUMP_IF_EQUAL = 0x15  # BPF_JMP | BPF_JEQ | BPF_K
JUMP_IF_AT_LEAST = 0x35  # BPF_JMP | BPF_JGE | BPF_K
RETURN = 0x06  # BPF_RET | BPF_K
NUMBER, ARCH = 0, 4  # offsetof(struct seccomp_data, nr), offsetof(..., arch)
X32_FIRST = 0x40000000

#: The kernel's name of each machine (AUDIT_ARCH_*), and its execve and execveat numbers.
EXEC_CALLS = {"x86_64": (0xC000003E, 59, 322), "aarch64": (0xC00000B7, 221, 281)}


def supported() -> bool:
    """Whether this machine's programs can be refused (Linux on x86_64 or aarch64)."""
    return platform.system() == "Linux" and platform.machine() in EXEC_CALLS


def forbid_programs() -> None:
    """From now on this process and every process it forks cannot start a program.

    Raises OSError if the kernel refuses the filter, and RuntimeError where it is not
    ``supported``.
    """
    if not supported():
        raise RuntimeError(f"no seccomp filter for {platform.system()} on {platform.machine()}")
    arch, execve, execveat = EXEC_CALLS[platform.machine()]
    refuse = SECCOMP_RET_ERRNO | errno.EPERM
    program = [
        (LOAD_WORD, 0, 0, ARCH),
        (JUMP_IF_EQUAL, 1, 0, arch),  # this architecture: go on; else refuse
        (RETURN, 0, 0, refuse),
        (LOAD_WORD, 0, 0, NUMBER),
        (JUMP_IF_AT_LEAST, 3, 0, X32_FIRST),  # the x32 ABI's numbers: refuse
        (JUMP_IF_EQUAL, 2, 0, execve),
        (JUMP_IF_EQUAL, 1, 0, execveat),
        (RETURN, 0, 0, SECCOMP_RET_ALLOW),
        (RETURN, 0, 0, refuse),
    ]
    # struct sock_filter { u16 code; u8 jt; u8 jf; u32 k; }
    filters = ctypes.create_string_buffer(b"".join(struct.pack("=HBBI", *i) for i in program))

    # struct sock_fprog { unsigned short len; struct sock_filter *filter; }
    class SockFprog(ctypes.Structure):
        _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]

    fprog = SockFprog(len(program), ctypes.addressof(filters))
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_void_p, ctypes.c_ulong, ctypes.c_ulong]
    if (
        libc.prctl(PR_SET_NO_NEW_PRIVS, 1, None, 0, 0) != 0
        or libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.addressof(fprog), 0, 0) != 0
    ):
        raise OSError(ctypes.get_errno(), "prctl failed while forbidding programs")
