"""No namespaces of the student's own: a seccomp filter that bubblewrap installs for it.

As root the sandbox makes no user namespace (``ptlab.course.sandbox.sandbox`` says why), so the
kernel would let the student's code make one, and be root in it: mount file systems of its
own size (past the sandbox's bounded ones), churn namespaces to slow the machine for the
student graded beside it, and reach kernel code that no exercise needs. This filter
(seccomp(2), a classic BPF program; linux/filter.h, linux/seccomp.h) refuses with EPERM
``unshare``, ``setns`` and a ``clone`` that asks for any new namespace, and answers
``clone3`` (whose flags a classic filter cannot read) with ENOSYS, on which the C library
falls back to ``clone``. Every other call is allowed: forking, threads and programs work.
bubblewrap loads it (``--seccomp FD``) just before it starts the student's Python, and it
holds for every process that one starts.

The program: refuse a call of a foreign architecture (a 32-bit call on a 64-bit kernel is
numbered differently) or of the x32 ABI (numbered from 2^30), then dispatch on the number.
"""

from __future__ import annotations

import errno
import platform
import struct

SECCOMP_RET_ALLOW = 0x7FFF0000
SECCOMP_RET_ERRNO = 0x00050000
# BPF opcodes: load a 32-bit word of struct seccomp_data; jumps; return.
LOAD_WORD = 0x20  # BPF_LD | BPF_W | BPF_ABS
JUMP_IF_EQUAL = 0x15  # BPF_JMP | BPF_JEQ | BPF_K
JUMP_IF_AT_LEAST = 0x35  # BPF_JMP | BPF_JGE | BPF_K
JUMP_IF_ANY_BIT = 0x45  # BPF_JMP | BPF_JSET | BPF_K
RETURN = 0x06  # BPF_RET | BPF_K
#: offsetof(struct seccomp_data, nr), (..., arch), the low half of args[0] (little-endian).
NUMBER, ARCH, FIRST_ARGUMENT = 0, 4, 16
X32_FIRST = 0x40000000
#: CLONE_NEWNS, NEWCGROUP, NEWUTS, NEWIPC, NEWUSER, NEWPID, NEWNET (linux/sched.h).
NEW_NAMESPACES = 0x00020000 | 0x02000000 | 0x04000000 | 0x08000000 | 0x10000000 | 0x20000000 | 0x40000000
#: Per machine: the kernel's name of it (AUDIT_ARCH_*), and unshare, setns, clone, clone3.
CALLS = {
    "x86_64": (0xC000003E, 272, 308, 56, 435),
    "aarch64": (0xC00000B7, 97, 268, 220, 435),
}


def supported() -> bool:
    """Whether this machine's calls are known here (Linux on x86_64 or aarch64)."""
    return platform.system() == "Linux" and platform.machine() in CALLS


def program() -> bytes:
    """The filter, as the array of ``struct sock_filter`` that bubblewrap reads."""
    arch, unshare, setns, clone, clone3 = CALLS[platform.machine()]
    refuse, no_such_call = SECCOMP_RET_ERRNO | errno.EPERM, SECCOMP_RET_ERRNO | errno.ENOSYS
    # (jt, jf): how many instructions to skip when the test holds, or does not (a jump
    # lands on the instruction after the skipped ones).
    instructions = [
        (LOAD_WORD, 0, 0, ARCH),
        (JUMP_IF_EQUAL, 1, 0, arch),  # 1: this machine's calls: on to 3
        (RETURN, 0, 0, refuse),  # 2
        (LOAD_WORD, 0, 0, NUMBER),  # 3
        (JUMP_IF_AT_LEAST, 7, 0, X32_FIRST),  # 4: the x32 ABI: to 12, refuse
        (JUMP_IF_EQUAL, 6, 0, unshare),  # 5: to 12
        (JUMP_IF_EQUAL, 5, 0, setns),  # 6: to 12
        (JUMP_IF_EQUAL, 5, 0, clone3),  # 7: to 13, no such call
        (JUMP_IF_EQUAL, 0, 2, clone),  # 8: on to 9, else to 11, allow
        (LOAD_WORD, 0, 0, FIRST_ARGUMENT),  # 9: clone's flags
        (JUMP_IF_ANY_BIT, 1, 0, NEW_NAMESPACES),  # 10: a new namespace: to 12
        (RETURN, 0, 0, SECCOMP_RET_ALLOW),  # 11
        (RETURN, 0, 0, refuse),  # 12
        (RETURN, 0, 0, no_such_call),  # 13
    ]
    # struct sock_filter { u16 code; u8 jt; u8 jf; u32 k; }
    return b"".join(struct.pack("=HBBI", *instruction) for instruction in instructions)
