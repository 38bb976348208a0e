"""A typical wrong chapter-8 answer: only whole tiles, ``range(0, height - size + 1, size)``,
so when the tile size does not divide the height the last, smaller row of tiles is never
made: the bottom of the image stays black. The jobs, their random numbers and the pool are right, so
the checks of parallelism and worker counts pass; the tiles and the image do not."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.camera import generate_rays
from ptlab.integrators.path import Paths, PathSettings, trace_paths
from ptlab.rendering.jobs import RenderSetup, Tile
from ptlab.rendering.settings import parse_resolution
from ptlab.samplers import BounceUniforms

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


def render_tile(setup, tile, spp):
    if setup.token not in _accelerators:
        _accelerators.clear()
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    height, width = tile.y1 - tile.y0, tile.x1 - tile.x0
    n = height * width
    pixel = np.tile(np.arange(n), spp)
    pixel_x, pixel_y = tile.x0 + pixel % width, tile.y0 + pixel // width
    sample = setup.sampler.keys(pixel_y * setup.width + pixel_x, np.repeat(np.arange(spp), n))
    origins, dirs = generate_rays(setup.scene.camera, setup.width, setup.height, pixel_x,
                                  pixel_y, setup.sampler.get(sample, BounceUniforms.PIXEL, 2))
    paths = Paths(origins, dirs, np.ones((len(pixel), 3), np.float32, order="F"), pixel,
                  np.ones(len(pixel), dtype=bool), sample)
    film = np.zeros((n, 3))
    trace_paths(film, setup.scene, _accelerators[setup.token], paths, setup.sampler, setup.settings)
    return film.reshape(height, width, 3), os.getpid()


def render_parallel(scene, spp, res, seed=0, workers=2, tile_size=32):
    width, height = parse_resolution(res)
    setup = RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width,
                        height=height, seed=seed, settings=PathSettings())
    sums = np.zeros((height, width, 3))
    pids = set()
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("forkserver")) as pool:
        jobs = {pool.submit(render_tile, setup, tile, spp): tile
                for tile in make_tiles(width, height, tile_size)}
        for done in as_completed(jobs):
            tile = jobs[done]
            tile_sums, pid = done.result()
            sums[tile.y0:tile.y1, tile.x0:tile.x1] += tile_sums
            pids.add(pid)
    return (sums / spp).astype(np.float32), pids
