"""Where jobs run: this process, a pool of worker processes, or a Dask cluster.

* ``workers=1``: in this process, one job after the other.
* ``workers=N``: a ``ProcessPoolExecutor`` of N processes started by ``forkserver`` (a
  clean process that forks the workers, so they never inherit the parent's Embree threads).
  A process started that way runs the main script again, as ``__mp_main__``, to find what
  the script defines; a script whose own work is not under ``if __name__ == "__main__":``
  would then render again in every worker. For such a script the workers are forked from
  this process instead (``script_without_main_guard``), where fork exists and Embree has
  not started its threads here; otherwise the render stops with one line saying what to add.
  Each worker ignores Ctrl-C, which the main process handles (it stops the render and keeps
  what is done), and receives the render's setup once, through the pool's initializer.
  ``ptlab render`` starts that server first thing (``start_worker_server``), so that it
  imports ptlab while the command does (docs/performance.md).
* any ``concurrent.futures.Executor`` the caller passes, e.g. ``ThreadPoolExecutor`` or a
  Dask client's ``get_executor()``: jobs then carry the setup with them.
"""

from __future__ import annotations

import ast
import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing.connection import wait
from multiprocessing.context import BaseContext
from types import FrameType
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


def script_without_main_guard() -> str | None:
    """The path of the main script if its top-level code, outside an
    ``if __name__ == "__main__":`` block, is what is starting workers now; else None (a
    notebook, the interpreter, ``python -c``, a guarded script, ``ptlab`` itself)."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if main is None or path is None:
        return None
    frame: FrameType | None = sys._getframe()
    while frame is not None and not (frame.f_globals is vars(main) and frame.f_code.co_name == "<module>"):
        frame = frame.f_back
    if frame is None:  # the script's top level is not on the stack: it has finished
        return None
    try:
        with open(path, "rb") as file:
            tree = ast.parse(file.read())
    except (OSError, SyntaxError, ValueError):
        return None
    line = frame.f_lineno
    guards = (node for node in ast.walk(tree) if isinstance(node, ast.If) and _tests_main_name(node.test))
    if any(guard.lineno <= line <= (guard.end_lineno or guard.lineno) for guard in guards):
        return None
    return path


def _tests_main_name(test: ast.expr) -> bool:
    """Whether an ``if`` compares ``__name__`` with ``"__main__"`` (in either order)."""
    names = {node.id for node in ast.walk(test) if isinstance(node, ast.Name)}
    texts = {node.value for node in ast.walk(test) if isinstance(node, ast.Constant)}
    return "__name__" in names and "__main__" in texts


def pool_context() -> BaseContext:
    """``worker_context``, unless a script without a main guard is rendering: then workers
    forked from this process, which do not run the script again (module docstring)."""
    script = script_without_main_guard()
    if script is None:
        return worker_context()
    # Forking is safe while Embree has not started its threads here (NumPy's BLAS threads
    # are: OpenBLAS prepares for fork). (Looked up, not imported: see the imports above.)
    embree = sys.modules.get("ptlab.accel.embree")
    if "fork" in multiprocessing.get_all_start_methods() and not getattr(embree, "threads_started", False):
        return multiprocessing.get_context("fork")
    raise PtlabError(
        f"{os.path.basename(script)}: put the script's own work under "
        f'`if __name__ == "__main__":` to render with several workers (or pass workers=1)'
    )


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

    # The main process handles Ctrl-C and SIGTERM, which reach a worker too when they are sent
    # to the whole process group (a terminal's Ctrl-C, `kill -- -PGID`): it stops or kills
    # the workers itself, and a worker ends when the main process does, however it ended.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    _end_with_the_main_process()
    keep_freed_memory()
    install_setup(setup)


def _end_with_the_main_process() -> None:
    """A thread that ends this worker as soon as the process that started the pool has ended
    (even by SIGKILL), so that no worker outlives its render. A worker's parent, for
    ``multiprocessing``, is that process, also when the fork server forked it."""
    parent = multiprocessing.parent_process()
    if parent is None:
        return

    def watch() -> None:
        wait([parent.sentinel])
        os._exit(1)

    threading.Thread(target=watch, name="ptlab: end with the main process", daemon=True).start()


def process_pool(workers: int, setup: RenderSetup) -> ProcessPoolExecutor:
    """N worker processes, each holding ``setup`` and its accelerator from the start."""
    return ProcessPoolExecutor(
        workers, mp_context=pool_context(), initializer=_init_worker, initargs=(setup,)
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
