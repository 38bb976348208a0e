"""Running a render's jobs: in this process, on a process pool, or on any executor.

Jobs go out in groups (``job_groups``: large at first, small at the end, so that every worker
finishes at about the same time), each run as one stream of batches (``run_job_group``).
Groups are handed out a few at a time (at most ``2 x workers`` in flight), so memory stays
bounded whatever the number of samples. A process pool whose worker dies (killed by the
system, say) is replaced, and the jobs it had not finished run again: every job is
deterministic, so the image is the same as if nothing had happened.
"""

from __future__ import annotations

import multiprocessing
import signal
import threading
import warnings
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from typing import Any

from ptlab.accel import make_accelerator
from ptlab.errors import PtlabError
from ptlab.rendering.executors import process_pool
from ptlab.rendering.jobs import (
    Job,
    JobResult,
    RenderSetup,
    job_groups,
    run_job_group,
    run_job_group_in_worker,
)

#: How many times a pool may be replaced after its workers died before giving up.
MAX_POOL_RESTARTS = 3

#: How often (seconds) a waiting main process checks whether it was asked to stop.
POLL_SECONDS = 0.1


def run_jobs(
    jobs: list[Job],
    setup: RenderSetup,
    workers: int,
    executor: Executor | None,
    stop: Callable[[], bool],
    more: Callable[[], list[Job]] | None = None,
) -> Iterator[JobResult]:
    """Yield each job's result as it finishes (in any order) until done or ``stop()``.

    ``more``, if given, is called each time every job so far has finished and its result has
    been taken (a render to a noise target decides its next pass from the whole film): it
    returns the next jobs, or none to end. The workers stay up in between.
    """

    def phases() -> Iterator[list[list[Job]]]:
        next_jobs = jobs or (more() if more is not None else [])
        while next_jobs and not stop():
            yield job_groups(next_jobs, workers)
            next_jobs = more() if more is not None and not stop() else []

    if executor is not None:
        for groups in phases():
            yield from _run_on_executor(
                groups,
                lambda group: executor.submit(run_job_group_in_worker, setup, group),
                window=2 * workers,
                stop=stop,
            )
    elif workers == 1:
        accel = make_accelerator(setup.scene.triangles, setup.backend, setup.pieces.bvh)
        for groups in phases():
            for group in groups:
                if stop():
                    return
                yield from run_job_group(setup, group, accel)
    else:
        yield from _run_on_process_pool(phases(), setup, workers, stop)


def _run_on_executor(
    groups: list[list[Job]],
    submit: Callable[[list[Job]], Future],
    window: int,
    stop: Callable[[], bool],
    cancel_unfinished: bool = True,
) -> Iterator[JobResult]:
    """Each result of ``groups``' jobs, with at most ``window`` groups in flight, until done
    or ``stop()``; the groups left in flight are then cancelled if ``cancel_unfinished``."""
    pending = deque(groups)
    in_flight: dict[Future, list[Job]] = {}
    try:
        while pending or in_flight:
            if stop():
                return
            with signals_held():  # (the futures' bookkeeping; the caller's code runs outside)
                while pending and len(in_flight) < window:
                    group = pending.popleft()
                    in_flight[submit(group)] = group
                done, _ = wait(in_flight, timeout=POLL_SECONDS, return_when=FIRST_COMPLETED)
                for future in done:
                    del in_flight[future]
                results = [result for future in done for result in future.result()]
            yield from results
    finally:
        if cancel_unfinished:
            with signals_held():
                for future in in_flight:
                    future.cancel()


def _submitter(pool: Executor, token: str) -> Callable[[list[Job]], Future]:
    """A function that submits a group of jobs to ``pool`` (made per pool, so it never sees a
    later one)."""

    def submit(group: list[Job]) -> Future:
        return pool.submit(run_job_group_in_worker, token, group)

    return submit


def _run_on_process_pool(
    phases: Iterator[list[list[Job]]], setup: RenderSetup, workers: int, stop: Callable[[], bool]
) -> Iterator[JobResult]:
    """The groups of each phase in turn on one pool of ``workers`` processes, replaced (and
    the phase's unfinished groups run again) if a worker dies."""
    remaining = next(phases, [])
    if not remaining:
        return
    for restart in range(MAX_POOL_RESTARTS + 1):
        finished: set[Job] = set()
        pool = process_pool(workers, setup)
        all_done = False
        try:
            while remaining:
                for result in _run_on_executor(
                    remaining,
                    _submitter(pool, setup.token),
                    window=2 * workers,
                    stop=stop,
                    # The pool's own thread cancels them as it shuts down. One cancelled
                    # here, which that thread then fails as its workers are killed, is an
                    # InvalidStateError and a traceback in it (CPython gh-107219, fixed in
                    # 3.12): a stop before the workers took their first jobs did that.
                    cancel_unfinished=False,
                ):
                    finished.add(result.job)
                    yield result
                if len(finished) < sum(len(group) for group in remaining):
                    return  # (stopped)
                finished, remaining = set(), next(phases, [])
            all_done = True
            return
        except BrokenProcessPool:
            if stop():  # (asked to stop anyway: no new workers)
                return
            # (A group is one call: a group with a job unfinished runs again, whole.)
            remaining = [group for group in remaining if not all(job in finished for job in group)]
            if restart == MAX_POOL_RESTARTS:
                raise PtlabError(
                    f"worker processes died {MAX_POOL_RESTARTS + 1} times (out of memory?); giving up"
                ) from None
            warnings.warn(
                f"a worker process died; starting new workers for the "
                f"{sum(len(group) for group in remaining)} unfinished jobs",
                RuntimeWarning,
                stacklevel=2,
            )
        finally:
            # Stopped, Ctrl-C, an error, or the caller stopped iterating: the jobs still
            # running would be thrown away, so their workers are ended rather than awaited.
            _close_pool(pool, kill=not all_done)


def _close_pool(pool: ProcessPoolExecutor, kill: bool) -> None:
    """Shut ``pool`` down, first ending its workers if ``kill``, with signals held: a pool
    left half shut down would make the interpreter's exit wait for its thread forever."""
    with signals_held():
        if kill:
            _kill_workers(pool)
        pool.shutdown(wait=True, cancel_futures=True)


def _kill_workers(pool: ProcessPoolExecutor) -> None:
    """End the pool's workers at once, rather than after their jobs (they ignore Ctrl-C,
    which is the main process's to handle). ``_processes`` is the pool's own record of them.

    A worker killed while it writes a result leaves half a message in the results pipe, and
    the pool's thread, reading it, would wait for the rest forever (and the shutdown with
    it). Once the workers are gone, this process's end of the pipe is its last writer:
    closing it turns that wait into an end of file, which the pool's thread takes for a
    broken pool, as it is."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        process.kill()
    for process in processes:
        process.join(timeout=5)
    results = getattr(pool, "_result_queue", None)
    if results is not None and not any(process.is_alive() for process in processes):
        results._writer.close()


@contextmanager
def interruptible() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt in the block, as Ctrl-C does, even in a process that
    was started with it ignored: then Python leaves it ignored, and ``kill -INT PID`` would
    not stop a render (while ``ptlab render``, which handles SIGINT itself, stops).

    A shell without job control starts its background commands so (a script's
    ``python render.py &``: POSIX.1-2017, Shell Command Language, 2.11). A process of a
    ``multiprocessing`` pool keeps it ignored: a pool's initializer ignores it on purpose,
    so that Ctrl-C is its main process's to handle (as ptlab's own workers do)."""
    override = (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        and multiprocessing.parent_process() is None
    )
    if not override:
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


#: The signals whose Python handlers ``signals_held`` holds back.
HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM back while the block runs, then deliver them.

    Their Python handlers raise (KeyboardInterrupt, or ``ptlab render``'s second Ctrl-C)
    between any two bytecodes: inside ``concurrent.futures.wait`` that can leave a future's
    lock taken, and the pool's thread, which needs it to record the future's end, then waits
    forever, and with it the pool's shutdown and the interpreter's exit."""
    if threading.current_thread() is not threading.main_thread():
        yield  # (only the main thread runs signal handlers)
        return
    held: list[int] = []
    previous: dict[signal.Signals, Any] = {}
    try:
        for signum in HELD_SIGNALS:
            if callable(signal.getsignal(signum)):  # (SIG_DFL and SIG_IGN never raise)
                previous[signum] = signal.signal(signum, lambda number, frame: held.append(number))
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for number in dict.fromkeys(held):
            signal.raise_signal(number)
