"""However a render is stopped, nothing outlives it, and a stopped `ptlab render` is quiet.

Each test starts a render with two workers in a session of its own, so that its processes
(the main one, the fork server, the resource tracker, the workers) share one process group;
it stops the render one way, then asserts that no process of the group is left.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = [pytest.mark.subprocess, pytest.mark.slow]

#: Long enough that every stop comes mid-render: two workers, 128x128 at 4096 spp.
LONG = ["cornell-box", "--res", "128", "--spp", "4096", "--workers", "2"]

SCRIPT = """
import ptlab

if __name__ == "__main__":
    ptlab.render("cornell-box", spp=4096, res=128, workers=2)
    print("finished")
"""


def group_members(pgid: int) -> list[int]:
    """The processes whose process group is ``pgid``."""
    members = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2 :].split()  # (the name may hold spaces)
            if fields[0] != "Z" and int(fields[2]) == pgid:
                members.append(int(entry))
    return members


#: The sessions the tests started, killed at the end of each test whatever happened, so that
#: a render that hangs fails its own test and leaves nothing to the next ones.
_sessions: list[int] = []


@pytest.fixture(autouse=True)
def _kill_what_is_left():
    yield
    while _sessions:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(_sessions.pop(), signal.SIGKILL)


def start(command: list[str], cwd: Path) -> subprocess.Popen:
    """``command`` in a new session, once it has its two workers (five processes in all)."""
    process = subprocess.Popen(
        command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    _sessions.append(process.pid)
    deadline = time.monotonic() + 120
    while len(group_members(process.pid)) < 5:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "the render never started its workers"
        time.sleep(0.1)
    time.sleep(0.5)  # (the workers have jobs)
    return process


def assert_nothing_left(pgid: int, within: float = 15.0) -> None:
    deadline = time.monotonic() + within
    while group_members(pgid):
        if time.monotonic() > deadline:
            left = {pid: Path(f"/proc/{pid}/cmdline").read_bytes()[:80] for pid in group_members(pgid)}
            for pid in left:
                os.kill(pid, signal.SIGKILL)
            raise AssertionError(f"left running: {left}")
        time.sleep(0.1)


def ptlab_render(tmp_path: Path) -> list[str]:
    return [sys.executable, "-m", "ptlab.cli", "render", *LONG, "--out", "box.png"]


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_to_the_group_stops_ptlab_render_quietly_with_its_exit_code(tmp_path, signum, code):
    process = start(ptlab_render(tmp_path), tmp_path)
    os.killpg(process.pid, signum)  # as a terminal's Ctrl-C, or `kill -- -PGID`
    _, err = process.communicate(timeout=120)
    assert process.returncode == code, err
    assert "Warning" not in err
    assert "Traceback" not in err
    # Progress lines (stderr is a pipe here), then what it kept; what it wrote, if a pass had
    # finished, is renderer/test_parallel.py's to check.
    said = [line for line in err.strip().splitlines() if not re.match(r"pass \d+/\d+: ", line)]
    assert said, err
    assert all(line.startswith("ptlab: interrupted") for line in said), err
    assert_nothing_left(process.pid)


@pytest.mark.parametrize("gap", [0.05, 0.3, 1.0])
def test_a_second_ctrl_c_ends_ptlab_render_at_once(tmp_path, gap):
    # Early, it lands in the render or the pool's shutdown; later, while the partial image is
    # written, which it must not cut short (it once aborted the process inside an import), or
    # while the process exits (it ended by SIGINT, or with a traceback from an exit hook).
    process = start(ptlab_render(tmp_path), tmp_path)
    os.killpg(process.pid, signal.SIGINT)
    time.sleep(gap)
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=60)  # (it ends in seconds; this is a hang)
    assert process.returncode == 130, err
    assert "Traceback" not in err
    assert_nothing_left(process.pid)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_script_calling_render_stops_at_once_and_leaves_nothing(tmp_path, signum):
    script = tmp_path / "render_box.py"
    script.write_text(SCRIPT)
    process = start([sys.executable, str(script)], tmp_path)
    stopped = time.monotonic()
    os.killpg(process.pid, signum)
    out, err = process.communicate(timeout=120)
    assert "finished" not in out
    # Ctrl-C is a KeyboardInterrupt in a script, which ends the workers rather than waiting
    # for their jobs, and then Python ends by that signal; SIGTERM ends it at once (its default).
    assert process.returncode == -signum, err
    assert time.monotonic() - stopped < 10
    assert_nothing_left(process.pid)


@pytest.mark.parametrize("command", ["ptlab render", "a script"])
def test_workers_end_when_the_main_process_is_killed(tmp_path, command):
    script = tmp_path / "render_box.py"
    script.write_text(SCRIPT)
    argv = ptlab_render(tmp_path) if command == "ptlab render" else [sys.executable, str(script)]
    process = start(argv, tmp_path)
    process.kill()  # SIGKILL to the main process only: it cannot clean up
    process.communicate(timeout=60)
    assert_nothing_left(process.pid)


def _large_result(_: int) -> bytes:
    return bytes(16_000_000)  # (a write to the results pipe that a kill can cut in half)


def test_a_pool_whose_workers_are_killed_mid_result_shuts_down():
    """A worker killed halfway through writing its result leaves half a message in the pool's
    results pipe; the pool's thread then waited for the rest forever, and with it the
    shutdown. Six kills at random moments of 16 MB writes: before the fix about half hung
    (15 of 30 measured), so this catches the bug with probability 1 - 2^-6; the fixed close
    ends every time (it closes the pipe's last writer)."""
    import random
    import threading
    from concurrent.futures import ProcessPoolExecutor

    from ptlab.rendering.executors import worker_context
    from ptlab.rendering.scheduler import _close_pool

    chance = random.Random(36)
    for _ in range(6):
        pool = ProcessPoolExecutor(2, mp_context=worker_context())
        for k in range(8):
            pool.submit(_large_result, k)
        time.sleep(chance.uniform(0.05, 0.4))
        closing = threading.Thread(target=_close_pool, args=(pool, True), daemon=True)
        closing.start()
        closing.join(20)
        assert not closing.is_alive(), "the pool's shutdown hangs after its workers were killed"
