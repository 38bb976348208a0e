"""Chapter 8, the library's own answer: tiles from ``ptlab.rendering.jobs.make_tiles``, a
tile's job by ``ptlab.rendering.jobs.run_job`` (whose random numbers are the setup's
sampler's, by pixel and sample), and a process pool that adds the tiles' sums into the image
in the main process."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.integrators.path import PathSettings
from ptlab.rendering.jobs import Job, RenderSetup, make_tiles, run_job
from ptlab.rendering.settings import parse_resolution

__all__ = ["make_tiles", "render_parallel", "render_tile"]

#: In each worker process: the accelerator of the render it works for (built once).
_accelerators: dict = {}


def render_tile(setup: RenderSetup, tile, spp: int) -> tuple[np.ndarray, int]:
    """One tile's job, in whichever process runs it: (sums (h, w, 3) float64, this pid)."""
    if setup.token not in _accelerators:
        _accelerators.clear()
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    result = run_job(setup, Job(tile, 0, spp), _accelerators[setup.token])
    return result.sums, os.getpid()


def render_parallel(
    scene, spp: int, res, seed: int = 0, workers: int = 2, tile_size: int = 32
) -> tuple[np.ndarray, set[int]]:
    """The image ((H, W, 3) float32) and the pids of the processes that rendered its tiles."""
    width, height = parse_resolution(res)
    setup = RenderSetup(
        scene=scene,
        backend=resolve_backend("auto"),
        width=width,
        height=height,
        seed=seed,
        settings=PathSettings(),
    )
    sums = np.zeros((height, width, 3))
    pids = set()
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        jobs = {
            pool.submit(render_tile, setup, tile, spp): tile for tile in make_tiles(width, height, tile_size)
        }
        for done in as_completed(jobs):
            tile = jobs[done]
            tile_sums, pid = done.result()
            sums[tile.y0 : tile.y1, tile.x0 : tile.x1] += tile_sums
            pids.add(pid)
    return (sums / spp).astype(np.float32), pids
