"""Looks at the machine around its process: the processes it can see and their command
lines (the grader's names its --json or --csv path), the folders above it, /tmp, /etc;
prints what it found, then fails its import."""

import os
from pathlib import Path


def tell(what, action):
    try:
        print(f"tell: {what}: {action()}", flush=True)
    except OSError as error:
        print(f"tell: {what}: refused: {type(error).__name__}", flush=True)


def _cmdlines():
    found = []
    for pid in sorted(int(p) for p in os.listdir("/proc") if p.isdigit()):
        try:
            found.append(Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode())
        except OSError:
            found.append("(unreadable)")
    return found


tell("processes", lambda: sorted(int(p) for p in os.listdir("/proc") if p.isdigit()))
tell("command lines", _cmdlines)
tell("/", lambda: sorted(os.listdir("/")))
tell("/tmp", lambda: sorted(os.listdir("/tmp")))
tell("/etc", lambda: sorted(os.listdir("/etc")))
tell("/etc/passwd", lambda: len(Path("/etc/passwd").read_text()))
tell("own status", lambda: len(Path("/proc/self/status").read_text()))
tell("own folder", lambda: sorted(os.listdir(".")))
tell("numpy's folder", lambda: len(os.listdir(os.path.dirname(__import__("numpy").__file__))))
raise SystemExit("looked around")
