"""Where jobs run: this process, a pool of worker processes, or a Dask cluster.

* ``workers=1``: in this process, one job after the other.
* ``workers=N``: a ``ProcessPoolExecutor`` of N processes started by ``forkserver`` (a
  clean process that forks the workers, so they never inherit the parent's Embree threads).
  Each worker ignores Ctrl-C, which the main process handles (it stops the render and keeps
  what is done), and receives the render's setup once, through the pool's initializer.
* any ``concurrent.futures.Executor`` the caller passes, e.g. ``ThreadPoolExecutor`` or a
  Dask client's ``get_executor()``: jobs then carry the setup with them.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

from ptlab.errors import PtlabError
from ptlab.rendering.jobs import RenderSetup, install_setup
from ptlab.rendering.memory import keep_freed_memory


def _init_worker(setup: RenderSetup) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # the main process handles Ctrl-C
    keep_freed_memory()
    install_setup(setup)


def process_pool(workers: int, setup: RenderSetup) -> ProcessPoolExecutor:
    """N worker processes, each holding ``setup`` and its accelerator from the start."""
    try:
        context = multiprocessing.get_context("forkserver")
        # Workers fork from a server that has already imported ptlab: fast to start.
        context.set_forkserver_preload(["ptlab.rendering.jobs"])
    except ValueError:  # no forkserver on this platform (Windows)
        context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(workers, mp_context=context, initializer=_init_worker,
                               initargs=(setup,))


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
