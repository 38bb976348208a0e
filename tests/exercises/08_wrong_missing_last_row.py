"""A typical wrong chapter-8 answer: only whole tiles, ``range(0, height - size + 1, size)``,
so when the tile size does not divide the height the last, smaller row of tiles is never
made: the bottom of the image stays black. The jobs, their random numbers and the pool are right, so
the checks of parallelism and worker counts pass; the tiles and the image do not."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.integrators.path import PathSettings
from ptlab.rendering.jobs import Job, RenderSetup, Tile, run_job
from ptlab.rendering.settings import parse_resolution

EXPECTED_FAILURES = ("tiles", "matches the library")
#: The black rows are reported by the check of the image, not by the check of parallelism
#: (which passes: the pool is right).
EXPECTED_HINTS = {"matches the library": ("pixels are black", "e.g. (x=0, y=32)")}


def make_tiles(width, height, size):
    # (the bug: only whole tiles, so the rows of a last, smaller tile row are left out)
    return [Tile(index, x0, y0, min(x0 + size, width), y0 + size)
            for index, (y0, x0) in enumerate((y0, x0) for y0 in range(0, height - size + 1, size)
                                             for x0 in range(0, width, size))]


#: In each worker process: the accelerator of the render it works for (built once).
_accelerators: dict = {}


def render_tile(setup: RenderSetup, tile, spp: int) -> tuple[np.ndarray, int]:
    """One tile's job, in whichever process runs it: (sums (h, w, 3) float64, this pid)."""
    if setup.token not in _accelerators:
        _accelerators.clear()
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    result = run_job(setup, Job(tile, 0, spp), _accelerators[setup.token])
    return result.sums, os.getpid()


def render_parallel(scene, spp: int, res, seed: int = 0, workers: int = 2,
                    tile_size: int = 32) -> tuple[np.ndarray, set[int]]:
    """The image ((H, W, 3) float32) and the pids of the processes that rendered its tiles."""
    width, height = parse_resolution(res)
    setup = RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width,
                        height=height, seed=seed, settings=PathSettings())
    sums = np.zeros((height, width, 3))
    pids = set()
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        jobs = {pool.submit(render_tile, setup, tile, spp): tile
                for tile in make_tiles(width, height, tile_size)}
        for done in as_completed(jobs):
            tile = jobs[done]
            tile_sums, pid = done.result()
            sums[tile.y0:tile.y1, tile.x0:tile.x1] += tile_sums
            pids.add(pid)
    return (sums / spp).astype(np.float32), pids
