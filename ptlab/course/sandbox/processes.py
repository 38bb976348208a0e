"""Keeping every process that a student's code starts where the grader can end it.

A student's code may fork, start a pool, or start a process in a session of its own
(``subprocess.Popen(..., start_new_session=True)``, ``os.setsid``) that would outlive the
grader and could rewrite its results afterwards. On Linux the grader makes itself a *child
subreaper* (``prctl(PR_SET_CHILD_SUBREAPER)``, prctl(2)): a process whose parent dies is then
re-parented to the grader instead of to init, so however it detaches itself it stays in the
grader's tree of processes, where ``ProcessGuard.end`` finds it.

Ending a tree takes two sweeps: every process in it is first stopped (SIGSTOP cannot be
caught, and a stopped process cannot fork), the tree is read again until no new process
appears, and then all of them are killed and the grader's own children among them reaped.
Elsewhere than Linux there is no subreaper: the guard ends the process group of each child
it is given, which a process that left the group escapes (see docs/grading-security.md).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import time
from collections.abc import Iterable
from pathlib import Path

PR_SET_DUMPABLE = 4
PR_SET_CHILD_SUBREAPER = 36
PR_GET_CHILD_SUBREAPER = 37
#: Stop-and-look sweeps before giving up on a tree that keeps growing (a fork bomb is
#: stopped process by process; each sweep stops every process it sees).
MAX_SWEEPS = 200
#: How long to wait for killed processes to disappear.
REAP_SECONDS = 5.0

LINUX = sys.platform.startswith("linux")


def _prctl(option: int, value: int = 0) -> int:
    libc = ctypes.CDLL(None, use_errno=True)
    if option == PR_GET_CHILD_SUBREAPER:
        current = ctypes.c_int(0)
        if libc.prctl(option, ctypes.byref(current), 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_GET_CHILD_SUBREAPER) failed")
        return current.value
    if libc.prctl(option, ctypes.c_ulong(value), 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl failed")
    return 0


def make_undumpable() -> None:
    """Make this process non-dumpable (prctl(2) ``PR_SET_DUMPABLE`` 0): no process without
    CAP_SYS_PTRACE can attach to it or read its memory and file descriptors through
    ``/proc``, not even one of its own user (a student's process when the grader is not
    root). It also writes no core file. Nothing elsewhere than Linux."""
    if LINUX:
        _prctl(PR_SET_DUMPABLE, 0)


def _scan() -> dict[int, tuple[int, bool]]:
    """{pid: (parent pid, is a zombie)} of every process this user can see (Linux ``/proc``)."""
    table = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_bytes()
        except OSError:  # gone meanwhile
            continue
        # pid (comm) state ppid ...; comm may hold spaces and parentheses: split after the last ')'.
        state, parent = stat[stat.rfind(b")") + 2 :].split()[:2]
        table[int(entry.name)] = (int(parent), state == b"Z")
    return table


def process_table(alive_only: bool = False) -> dict[int, int]:
    """{pid: parent pid} of every process this user can see; with ``alive_only``, without
    zombies (processes that ended and wait for their parent to reap them)."""
    return {pid: parent for pid, (parent, zombie) in _scan().items() if not (alive_only and zombie)}


def descendants(roots: Iterable[int], table: dict[int, int]) -> set[int]:
    """``roots`` that still exist and every process below them in ``table``."""
    children: dict[int, list[int]] = {}
    for pid, parent in table.items():
        children.setdefault(parent, []).append(pid)
    found, todo = set(), [pid for pid in roots if pid in table]
    while todo:
        pid = todo.pop()
        if pid not in found:
            found.add(pid)
            todo.extend(children.get(pid, ()))
    return found


class ProcessGuard:
    """While it is entered, every process a child of this one leaves behind stays ours.

    ``end(pid)`` ends a child process and everything below it, including processes that
    left its session and were re-parented here. Leaving the ``with`` block ends whatever is
    left and restores the previous subreaper setting.
    """

    def __init__(self) -> None:
        self._previous: int | None = None
        self._helpers: set[int] = set()
        self._servers: set[int] = set()

    def __enter__(self) -> ProcessGuard:
        if LINUX:
            self._previous = _prctl(PR_GET_CHILD_SUBREAPER)
            _prctl(PR_SET_CHILD_SUBREAPER, 1)
        self.trust_current_children()
        return self

    def __exit__(self, *exc) -> None:
        self.end()
        if LINUX and self._previous is not None:
            _prctl(PR_SET_CHILD_SUBREAPER, self._previous)

    def trust_current_children(self) -> None:
        """Count this process's children of now as its own helpers, never to be ended
        (a test runner's workers, multiprocessing's fork server and resource tracker)."""
        if LINUX:
            me = os.getpid()
            self._helpers = {pid for pid, parent in process_table().items() if parent == me}

    def add_server(self, pid: int, started: int, table: dict[int, int] | None = None) -> None:
        """Count ``pid``, the fork server that just ``started`` a process, as a helper whose
        later children are all ours to end (a student's code that asks it for a process of
        its own, through its socket, must not slip out of reach); its children of now but
        ``started`` (the workers of a pool this process keeps) stay helpers. ``table``: the
        ``process_table`` the caller just took, if it has one."""
        self._servers.add(pid)
        table = process_table() if table is None else table
        self._helpers |= {child for child, parent in table.items() if parent == pid and child != started}

    def end(self, *roots: int, keep: Iterable[int] = ()) -> None:
        """End ``roots``, every process below them, every orphan re-parented here and every
        child of a fork server; but not the processes in ``keep``."""
        if not LINUX:
            for pid in roots:
                _signal_group(pid, signal.SIGKILL)
            return
        me, keep = os.getpid(), set(keep)
        stopped: set[int] = set()
        for _ in range(MAX_SWEEPS):
            table = process_table()
            orphans = {
                pid
                for pid, parent in table.items()
                if pid not in keep and pid not in self._helpers and (parent == me or parent in self._servers)
            }
            victims = descendants(set(roots) | orphans, table) - stopped - keep - {me}
            if not victims:
                break
            for pid in victims:
                _signal(pid, signal.SIGSTOP)
            stopped |= victims
        for pid in stopped:
            _signal(pid, signal.SIGKILL)
        _reap(stopped, me)


def _signal(pid: int, signum: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.kill(pid, signum)


def _signal_group(pid: int, signum: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, signum)


def _reap(pids: set[int], me: int) -> None:
    """Wait until every killed process has ended, reaping those that are our children
    (orphans re-parented to us; the others are their own parents' to reap)."""
    waiting = set(pids)
    deadline = time.monotonic() + REAP_SECONDS
    while waiting and time.monotonic() < deadline:
        table = _scan()
        for pid in list(waiting):
            parent, zombie = table.get(pid, (None, True))
            if parent is None or (zombie and parent != me):
                waiting.discard(pid)
            elif parent == me:
                try:
                    done, _ = os.waitpid(pid, os.WNOHANG)
                except ChildProcessError:
                    done = pid
                if done:
                    waiting.discard(pid)
        if waiting:
            time.sleep(0.005)
