"""A share of the machine for each student graded at once: a control group per slot.

``grade-all --workers K`` grades K students at the same time, each in a grader process of
its own that starts the student's processes. Without more, the kernel shares the CPU
between *processes*: a submission that starts 40 spinning processes takes 40 shares to the
other student's two, and that student's checks, whose limits are wall-clock, slow down
about 4x. Linux's control groups (cgroups(7)) share between *groups* instead: each slot's
grader, and everything it starts, is one group with the same CPU weight as the others and
at most its share of the processors (a quota: a weight alone let 300 processes that wake
every 50 microseconds slow the other student 20-fold), a memory limit of its own (a share
of the machine's) and a limit on its number of processes, however many processes the
student's code makes and whatever user they run as.

Both hierarchies are handled: cgroup v1 (a folder per controller, ``cpu``, ``memory``,
``pids``, under ``/sys/fs/cgroup``) and v2 (one unified tree). Only root may make groups;
where none can be made, ``ControlGroups.make`` returns None and the graders say so.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

CGROUP_ROOT = Path("/sys/fs/cgroup")
#: Processes and threads a slot may have at once (its grader, the student's processes and
#: their threads).
SLOT_TASKS = 2048
#: The period of the CPU quota, in microseconds (the kernel's default).
QUOTA_PERIOD = 100_000
#: The share of the machine's memory that the slots divide between them.
MEMORY_SHARE = 0.8


class ControlGroups:
    """A control group per slot, below one group of this process's own."""

    def __init__(self, folders: dict[int, list[Path]], tops: list[Path]):
        self.folders, self.tops = folders, tops

    @classmethod
    def make(cls, slots: int) -> ControlGroups | None:
        """Groups for slots 1 to ``slots``, each with an equal CPU weight, a quota of the
        machine's processors divided by ``slots`` (at least one), a memory limit of
        ``MEMORY_SHARE`` of the machine's divided by ``slots``, and ``SLOT_TASKS`` tasks;
        None where this process cannot make them (not root, no cgroup file system)."""
        memory = int(_memory_bytes() * MEMORY_SHARE / max(1, slots))
        quota = QUOTA_PERIOD * max(1, (os.cpu_count() or 1) // max(1, slots))
        name = f"ptlab-grading-{os.getpid()}"
        unified = (CGROUP_ROOT / "cgroup.controllers").is_file()
        settings = (
            {
                "": {
                    "cpu.weight": "100",
                    "cpu.max": f"{quota} {QUOTA_PERIOD}",
                    "memory.max": str(memory),
                    "pids.max": str(SLOT_TASKS),
                }
            }
            if unified
            else {
                "cpu": {
                    "cpu.shares": "1024",
                    "cpu.cfs_period_us": str(QUOTA_PERIOD),
                    "cpu.cfs_quota_us": str(quota),
                },
                "memory": {"memory.limit_in_bytes": str(memory)},
                "pids": {"pids.max": str(SLOT_TASKS)},
            }
        )
        tops: list[Path] = []
        folders: dict[int, list[Path]] = {slot: [] for slot in range(1, slots + 1)}
        try:
            for controller, values in settings.items():
                top = CGROUP_ROOT / controller / name if controller else CGROUP_ROOT / name
                top.mkdir()
                tops.append(top)
                if unified:
                    (top / "cgroup.subtree_control").write_text("+cpu +memory +pids")
                for slot in folders:
                    folder = top / f"slot-{slot}"
                    folder.mkdir()
                    for file, value in values.items():
                        (folder / file).write_text(value)
                    folders[slot].append(folder)
        except OSError:
            ControlGroups(folders, tops).remove()
            return None
        return cls(folders, tops)

    def join(self, slot: int, pid: int) -> None:
        """Put process ``pid`` (and so everything it starts from now on) in ``slot``'s group."""
        for folder in self.folders[slot]:
            (folder / "cgroup.procs").write_text(str(pid))

    def remove(self) -> None:
        """Remove the groups (each must be empty: the graders' processes have ended)."""
        for slot_folders in self.folders.values():
            for folder in slot_folders:
                with contextlib.suppress(OSError):
                    folder.rmdir()
        for top in self.tops:
            with contextlib.suppress(OSError):
                top.rmdir()


def _memory_bytes() -> int:
    """The machine's memory, in bytes."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError):
        return 8 << 30
