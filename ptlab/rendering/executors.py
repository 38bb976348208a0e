"""Where jobs run: this process, a pool of worker processes, or a Dask cluster.

* ``workers=1``: in this process, one job after the other.
* ``workers=N``: a ``ProcessPoolExecutor`` of N processes started by ``forkserver`` (a
  clean process that forks the workers, so they never inherit the parent's Embree threads).
  Each worker ignores Ctrl-C, which the main process handles (it stops the render and keeps
  what is done), and receives the render's setup once, through the pool's initializer.
  ``ptlab render`` starts that server first thing (``start_worker_server``), so that it
  imports ptlab while the command does (docs/performance.md).
* any ``concurrent.futures.Executor`` the caller passes, e.g. ``ThreadPoolExecutor`` or a
  Dask client's ``get_executor()``: jobs then carry the setup with them.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing.context import BaseContext
from typing import TYPE_CHECKING

from ptlab.errors import PtlabError
from ptlab.rendering.memory import keep_freed_memory

# This module imports neither NumPy nor the rest of ptlab (only the workers do, and then
# inside ``_init_worker``), so that ``start_worker_server`` can run before they are imported.
if TYPE_CHECKING:
    from ptlab.rendering.jobs import RenderSetup

#: What the fork server imports before it forks any worker.
WORKER_PRELOAD = ["ptlab.rendering.jobs"]


def default_workers() -> int:
    """The number of cores this process may run on (the default number of workers)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def worker_context() -> BaseContext:
    """How worker processes start: forked from a server that has already imported ptlab
    (fast to start, and clean: nothing of the parent's, such as Embree's threads), or
    spawned where there is no fork server (Windows)."""
    try:
        context = multiprocessing.get_context("forkserver")
    except ValueError:
        return multiprocessing.get_context("spawn")
    context.set_forkserver_preload(WORKER_PRELOAD)
    return context


def start_worker_server() -> None:
    """Start the workers' fork server now, if there is one, rather than when the first
    pool needs it; a pool started later uses this server."""
    if worker_context().get_start_method() == "forkserver":
        from multiprocessing import forkserver

        forkserver.ensure_running()


def _init_worker(setup: RenderSetup) -> None:
    from ptlab.rendering.jobs import install_setup

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the main process handles Ctrl-C
    keep_freed_memory()
    install_setup(setup)


def process_pool(workers: int, setup: RenderSetup) -> ProcessPoolExecutor:
    """N worker processes, each holding ``setup`` and its accelerator from the start."""
    return ProcessPoolExecutor(
        workers, mp_context=worker_context(), initializer=_init_worker, initargs=(setup,)
    )


@contextmanager
def dask_executor(address: str) -> Iterator[Executor]:
    """A ``concurrent.futures`` executor on the Dask cluster whose scheduler is at ``address``."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise PtlabError("--scheduler needs Dask: pip install 'ptlab[dask]'") from None
    try:
        client = Client(address, timeout=10)
    except (OSError, TimeoutError, ValueError) as error:
        raise PtlabError(f"cannot reach the Dask scheduler at {address}: {error}") from None
    try:
        yield client.get_executor()
    finally:
        client.close()
