"""A right chapter-8 answer, written as a student would (not the library's code): tiles that
cover the image once, a tile's job that takes its random numbers from the render's sampler
by pixel and sample, and a pool of processes whose tiles' sums are added into the image in
the main process. It must get full marks; the chapter's typical wrong answers are this file
with the mistake patched in (wrong_answers.toml)."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from ptlab.accel import make_accelerator, resolve_backend
from ptlab.camera import generate_rays
from ptlab.integrators.path import Paths, PathSettings, trace_paths
from ptlab.rendering.jobs import RenderSetup, Tile
from ptlab.rendering.settings import parse_resolution
from ptlab.samplers import BounceUniforms


def make_tiles(width, height, size):
    return [Tile(index, x0, y0, min(x0 + size, width), min(y0 + size, height))
            for index, (y0, x0) in enumerate((y0, x0) for y0 in range(0, height, size)
                                             for x0 in range(0, width, size))]


#: In each worker process: the accelerator of the render it works for (built once).
_accelerators: dict = {}


def render_tile(setup, tile, spp):
    if setup.token not in _accelerators:
        _accelerators.clear()
        _accelerators[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    sampler = setup.sampler
    height, width = tile.y1 - tile.y0, tile.x1 - tile.x0
    n = height * width
    pixel = np.tile(np.arange(n), spp)
    pixel_x, pixel_y = tile.x0 + pixel % width, tile.y0 + pixel // width
    sample = sampler.keys(pixel_y * setup.width + pixel_x, np.repeat(np.arange(spp), n))
    origins, dirs = generate_rays(setup.scene.camera, setup.width, setup.height, pixel_x,
                                  pixel_y, sampler.get(sample, BounceUniforms.PIXEL, 2))
    paths = Paths(origins, dirs, np.ones((len(pixel), 3), np.float32, order="F"), pixel,
                  np.ones(len(pixel), dtype=bool), sample)
    film = np.zeros((n, 3))
    trace_paths(film, setup.scene, _accelerators[setup.token], paths, sampler, setup.settings)
    return film.reshape(height, width, 3), os.getpid()


def render_parallel(scene, spp, res, seed=0, workers=2, tile_size=32):
    width, height = parse_resolution(res)
    setup = RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width,
                        height=height, seed=seed, settings=PathSettings())
    tiles = make_tiles(width, height, tile_size)
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("forkserver")) as pool:
        done = list(pool.map(render_tile, [setup] * len(tiles), tiles, [spp] * len(tiles)))
    image = np.zeros((height, width, 3))
    for tile, (tile_sums, _) in zip(tiles, done, strict=True):
        image[tile.y0:tile.y1, tile.x0:tile.x1] += tile_sums
    return (image / spp).astype(np.float32), {pid for _, pid in done}
