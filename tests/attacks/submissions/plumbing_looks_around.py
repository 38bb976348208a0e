"""Looks at the machine around its process: the grader's command line (which names the
--json or --csv path), the process table, other folders; prints what it managed, then
fails its import."""

import os
from pathlib import Path


def attempt(what, action):
    try:
        action()
        print(f"tell: {what}: allowed", flush=True)
    except OSError as error:
        print(f"tell: {what}: refused: {error}", flush=True)


attempt("grader cmdline", lambda: Path(f"/proc/{os.getppid()}/cmdline").read_bytes())
attempt("list /proc", lambda: os.listdir("/proc"))
attempt("list /", lambda: os.listdir("/"))
attempt("scandir /tmp", lambda: list(os.scandir("/tmp")))
attempt("iterdir /etc", lambda: list(Path("/etc").iterdir()))
attempt("read /etc/passwd", lambda: Path("/etc/passwd").read_text())
attempt("own status", lambda: Path("/proc/self/status").read_text())
attempt("own folder", lambda: os.listdir("."))
attempt("numpy's folder", lambda: os.listdir(os.path.dirname(__import__("numpy").__file__)))
raise SystemExit("looked around")
