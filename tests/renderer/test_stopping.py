"""However a render is stopped, nothing outlives it, and a stopped `ptlab render` is quiet.

Each test starts a render with two workers in a session of its own, so that its processes
(the main one, the fork server, the resource tracker, the workers) share one process group;
it stops the render one way (a signal to the group, as a terminal's Ctrl-C, or to the main
process alone, as ``kill -INT PID``, an IDE's stop button or a supervisor), then asserts
that no process of the group is left.
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

#: A script that renders under a main guard: its workers come from the fork server. It
#: first says whether it found SIGINT ignored (started as a shell's background job).
SCRIPT = """
import signal
import ptlab

if __name__ == "__main__":
    print("SIGINT ignored:", signal.getsignal(signal.SIGINT) is signal.SIG_IGN, flush=True)
    ptlab.render("cornell-box", spp=4096, res=128, workers=2)
    print("finished")
"""

#: The README's first Python example as a plain script, longer: no main guard, so its
#: workers are forked from it (``ptlab.rendering.executors``), three processes in all.
README_SCRIPT = """
import signal
import ptlab
print("SIGINT ignored:", signal.getsignal(signal.SIGINT) is signal.SIG_IGN, flush=True)  # (the test's)

scene = ptlab.load_scene("cornell-box")  # a built-in name or a path to a scene file
image = ptlab.render(scene, spp=4096, res=(128, 128), seed=0, workers=2, backend="embree")
from ptlab.image import write_image

write_image("cornell.exr", image)  # or .png (8-bit sRGB)
print("finished")
"""

#: How many processes each command's render has once its two workers run: the main one,
#: the workers, and, unless they are forked from the main process, the fork server and the
#: resource tracker.
PROCESSES = {"a script": 5, "the README's script": 3, "ptlab render": 5}

#: ``sh -c`` that ignores SIGINT, then becomes the command: how a shell without job control
#: starts a background command (a script's ``python render.py &``; POSIX.1-2017, Shell
#: Command Language, 2.11), which inherits SIGINT ignored.
AS_A_BACKGROUND_JOB = ["/bin/sh", "-c", 'trap "" INT; exec "$@"', "sh"]


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


def start(command: list[str], cwd: Path, processes: int = 5) -> subprocess.Popen:
    """``command`` in a new session, once it has its two workers (``processes`` in all)."""
    process = subprocess.Popen(
        command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    _sessions.append(process.pid)
    deadline = time.monotonic() + 120
    while len(group_members(process.pid)) < processes:
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


def script_command(tmp_path: Path, command: str) -> list[str]:
    """The command line of ``command`` (a key of ``PROCESSES``), its script written to ``tmp_path``."""
    if command == "ptlab render":
        return [sys.executable, "-m", "ptlab", "render", *LONG, "--out", "box.png"]
    script = tmp_path / "render_box.py"
    script.write_text(SCRIPT if command == "a script" else README_SCRIPT)
    return [sys.executable, str(script)]


@pytest.mark.parametrize("to", ["the group", "the process"])
@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_ptlab_render_quietly_with_its_exit_code(tmp_path, signum, code, to):
    process = start(ptlab_render(tmp_path), tmp_path)
    # As a terminal's Ctrl-C or `kill -- -PGID`; or `kill PID`, to the main process alone.
    (os.killpg if to == "the group" else os.kill)(process.pid, signum)
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
@pytest.mark.parametrize("command", ["a script", "the README's script"])
def test_a_script_calling_render_stops_at_once_and_leaves_nothing(tmp_path, signum, command):
    process = start(script_command(tmp_path, command), tmp_path, PROCESSES[command])
    stopped = time.monotonic()
    os.killpg(process.pid, signum)
    out, err = process.communicate(timeout=120)
    assert "finished" not in out
    # Ctrl-C is a KeyboardInterrupt in a script, which ends the workers rather than waiting
    # for their jobs, and then Python ends by that signal; SIGTERM ends it at once (its default).
    assert process.returncode == -signum, err
    assert time.monotonic() - stopped < 10
    assert_nothing_left(process.pid)


@pytest.mark.parametrize(
    ("started", "times"),
    [("by a program", 1), ("as a shell's background job", 1), ("as a shell's background job", 2)],
)
@pytest.mark.parametrize("command", ["a script", "the README's script", "ptlab render"])
def test_sigint_to_the_main_process_alone_stops_the_render_and_leaves_nothing(
    tmp_path, command, started, times
):
    """``kill -INT PID``, once or twice, stops a render as Ctrl-C does, also in a process
    started with SIGINT ignored, where a script once rendered on with both workers (Python
    leaves such a SIGINT ignored; ``ptlab.render`` takes it back while it renders)."""
    argv = script_command(tmp_path, command)
    if started != "by a program":
        argv = AS_A_BACKGROUND_JOB + argv
    process = start(argv, tmp_path, PROCESSES[command])
    stopped = time.monotonic()
    for _ in range(times):
        os.kill(process.pid, signal.SIGINT)
        time.sleep(0.3)
    out, err = process.communicate(timeout=60)  # (it ends in seconds; this is a hang)
    assert time.monotonic() - stopped < 10, err  # (about a second, on a loaded machine too)
    if command == "ptlab render":
        assert process.returncode == 130, err
        assert "Traceback" not in err
    else:
        # The way the script began (the precondition of this test) ...
        assert out.startswith(f"SIGINT ignored: {started != 'by a program'}"), out
        # ... and a KeyboardInterrupt, which ends the workers, then Python ends by SIGINT.
        assert "finished" not in out
        assert process.returncode == -signal.SIGINT, err
        assert "KeyboardInterrupt" in err
    assert_nothing_left(process.pid, within=5)


def test_a_render_takes_an_ignored_sigint_back_only_while_it_runs():
    from ptlab.rendering.scheduler import interruptible

    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with pytest.raises(KeyboardInterrupt), interruptible():
            signal.raise_signal(signal.SIGINT)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        signal.raise_signal(signal.SIGINT)  # (ignored again: nothing happens)
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.parametrize("command", ["ptlab render", "a script"])
def test_workers_end_when_the_main_process_is_killed(tmp_path, command):
    process = start(script_command(tmp_path, command), tmp_path)
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


def test_a_stop_before_the_workers_take_their_first_jobs_leaves_no_traceback(monkeypatch):
    """The render stops at its third look at ``stop``, 0.1 s after it handed out its first
    groups, while the workers still start: one group waits in the pool, not yet theirs.
    Cancelled by the render, then failed by the pool's thread as the workers were killed, it
    was an InvalidStateError there, with a traceback (CPython 3.11; `ptlab render`'s first
    Ctrl-C at that moment). Before the fix every run of this test had it (3 of 3)."""
    import threading
    import warnings

    from ptlab.rendering.api import render_result

    thread_errors: list[str] = []
    monkeypatch.setattr(threading, "excepthook", lambda hook: thread_errors.append(repr(hook.exc_value)))
    looks = 0

    def stop() -> bool:
        nonlocal looks
        looks += 1
        return looks > 2

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (stopped before any pass)
        result = render_result("cornell-box", res=128, spp=256, workers=2, stop=stop)
    assert not result.complete
    assert thread_errors == []  # (the pool's thread has ended: the render waits for it)


def test_jupyters_interrupt_stops_a_render_and_the_kernel_renders_again(tmp_path):
    """Jupyter's "interrupt kernel" sends SIGINT to the kernel's process group: the cell
    ends with a KeyboardInterrupt within seconds, no worker is left, and the next cell renders."""
    pytest.importorskip("ipykernel")
    from jupyter_client.manager import start_new_kernel

    manager, client = start_new_kernel(kernel_name="python3", cwd=str(tmp_path))
    try:
        kernel = manager.provisioner.process.pid
        _sessions.append(kernel)  # (its own session: killed at the end whatever happened)
        # (stop_on_error: else the kernel drops the cells sent just after the error)
        code = "import ptlab\nptlab.render('cornell-box', spp=4096, res=128, workers=2)"
        message = client.execute(code, stop_on_error=False)
        deadline = time.monotonic() + 120
        while len(workers_of(kernel)) < 2:
            assert time.monotonic() < deadline, "the render never started its workers"
            time.sleep(0.1)
        time.sleep(0.5)  # (the workers have jobs)
        manager.interrupt_kernel()
        reply = client.get_shell_msg(timeout=30)
        assert reply["parent_header"]["msg_id"] == message
        assert reply["content"]["status"] == "error"
        assert reply["content"]["ename"] == "KeyboardInterrupt"
        deadline = time.monotonic() + 5
        while workers_of(kernel):
            assert time.monotonic() < deadline, f"workers left: {workers_of(kernel)}"
            time.sleep(0.1)
        again = client.execute_interactive(
            "print(ptlab.render('cornell-box', spp=32, res=32, workers=2).shape)", timeout=120
        )
        assert again["content"]["status"] == "ok"
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)


def workers_of(kernel: int) -> list[int]:
    """The processes of ``kernel``'s group that it did not start itself: its render's workers,
    which the fork server (its child) forked."""
    return [pid for pid in group_members(kernel) if pid != kernel and parent_of(pid) != kernel]


def parent_of(pid: int) -> int | None:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return int(stat[stat.rindex(")") + 2 :].split()[1])
