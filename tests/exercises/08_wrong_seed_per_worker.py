"""A typical wrong chapter-8 answer: random numbers seeded per worker, not per tile. Each
worker process makes one generator from the seed and its pid and draws every tile's numbers
from it, so a tile's noise depends on which process renders it and on what that process
rendered before: the image changes with the number of workers (and from run to run), and
it is not the library's image for the same seed. The tiles and the pool are right."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.camera import generate_rays
from ptlab.integrators.path import Paths, PathSettings, trace_paths
from ptlab.rendering.jobs import RenderSetup, Tile
from ptlab.rendering.settings import parse_resolution

EXPECTED_FAILURES = ("tile job", "any worker count", "matches the library")

_accelerators: dict = {}
_rng = None        # the bug: one generator per worker process


def make_tiles(width, height, size):
    return [Tile(index, x0, y0, min(x0 + size, width), min(y0 + size, height))
            for index, (y0, x0) in enumerate((y0, x0) for y0 in range(0, height, size)
                                             for x0 in range(0, width, size))]


def render_tile(setup, tile, spp):
    global _rng
    if _rng is None:
        _rng = np.random.default_rng([setup.seed, os.getpid()])
    if setup.token not in _accelerators:
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    height, width = tile.y1 - tile.y0, tile.x1 - tile.x0
    n = height * width
    pixel = np.tile(np.arange(n), spp)
    origins, dirs = generate_rays(setup.scene.camera, setup.width, setup.height,
                                  tile.x0 + pixel % width, tile.y0 + pixel // width,
                                  _rng.random((len(pixel), 2), dtype=np.float32))
    paths = Paths(origins, dirs, np.ones((len(pixel), 3), np.float32, order="F"), pixel,
                  np.ones(len(pixel), dtype=bool))
    film = np.zeros((n, 3))
    trace_paths(film, setup.scene, _accelerators[setup.token], paths, _rng, setup.settings)
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
