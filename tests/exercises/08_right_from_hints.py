"""A right chapter-8 answer written from the exercise file's hints alone, step by step, as a
student who follows them would write it: the same tiles, job and pool as the library's
answer, because the hints spell them out. It must get full marks, and is no copy: what the
exercise file dictates is no evidence of copying (ptlab/course/sandbox/copies.py)."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.camera import generate_rays
from ptlab.integrators.path import PathSettings, trace_paths
from ptlab.integrators.wavefront import Paths
from ptlab.rendering.jobs import RenderSetup, Tile
from ptlab.rendering.settings import parse_resolution
from ptlab.samplers import BounceUniforms

#: Given, nothing to write: in each worker process, the ray-query structure of the render it
#: works for, built once per process rather than once per tile.
_accelerators: dict = {}


def accelerator_for(setup):
    """The accelerator for ``setup.scene``, built the first time this process needs it."""
    if setup.token not in _accelerators:
        _accelerators.clear()
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    return _accelerators[setup.token]


def make_tiles(width, height, size):
    tiles = []
    for y0 in range(0, height, size):
        for x0 in range(0, width, size):
            tiles.append(Tile(len(tiles), x0, y0, min(x0 + size, width), min(y0 + size, height)))
    return tiles


def render_tile(setup, tile, spp):
    accel = accelerator_for(setup)
    sampler = setup.sampler
    h, w = tile.y1 - tile.y0, tile.x1 - tile.x0
    n = h * w
    pixel = np.tile(np.arange(n), spp)
    pixel_x = tile.x0 + pixel % w
    pixel_y = tile.y0 + pixel // w
    index = np.repeat(np.arange(spp), n)
    sample = sampler.keys(pixel_y * setup.width + pixel_x, index)
    jitter = sampler.get(sample, BounceUniforms.PIXEL, 2)
    origins, dirs = generate_rays(setup.scene.camera, setup.width, setup.height, pixel_x, pixel_y, jitter)
    throughput = np.ones((len(pixel), 3), np.float32, order="F")
    sees_emission = np.ones(len(pixel), dtype=bool)
    paths = Paths(origins, dirs, throughput, pixel, sees_emission, sample)
    film = np.zeros((n, 3))
    trace_paths(film, setup.scene, accel, paths, sampler, setup.settings)
    return film.reshape(h, w, 3), os.getpid()


def render_parallel(scene, spp, res, seed=0, workers=2, tile_size=32):
    width, height = parse_resolution(res)
    setup = RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width,
                        height=height, seed=seed, settings=PathSettings())
    image = np.zeros((height, width, 3))
    pids = set()
    context = multiprocessing.get_context("forkserver")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        futures = {pool.submit(render_tile, setup, tile, spp): tile
                   for tile in make_tiles(width, height, tile_size)}
        for future in as_completed(futures):
            tile = futures[future]
            sums, pid = future.result()
            image[tile.y0:tile.y1, tile.x0:tile.x1] += sums
            pids.add(pid)
    return (image / spp).astype(np.float32), pids
