"""Chapter 8: parallel rendering over tiles.

The chapter's page: ``ptlab exercise docs 8`` (中文: ``--zh``).

Cut the image into tiles, render each tile as an independent job on a pool of worker
processes, and add the tiles' results into the image, so that the image is the same, bit for
bit, whatever the number of workers. Write ``make_tiles``, ``render_tile`` and
``render_parallel``; check your work with

    ptlab exercise check 8 08_parallel.py

Read ``ptlab/rendering/jobs.py`` (``Tile``, ``run_job``), ``ptlab/rendering/scheduler.py``
and ``ptlab/rendering/film.py`` first: they are the library's version of this chapter.

Two rules make a parallel render right:

* **No shared state between jobs.** A worker process has its own copy of everything it is
  given; it cannot write into the main process's image. Each job *returns* its tile's sums,
  and the main process adds them into the image.
* **Random numbers belong to pixels and samples, not to workers.** The render's sampler,
  ``setup.sampler`` (``ptlab.samplers``), gives every random number as a function of (seed,
  pixel, sample index, dimension) alone, so a pixel gets the same numbers whichever process
  renders its tile. A generator made once per worker (or seeded with the worker's number or
  pid) hands each tile different numbers depending on which worker ran it and what it ran
  before: the image changes with the number of workers.

Tiles and the pool are the only Python loops here; inside a job everything is whole arrays.
"""

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
    """The image cut into ``size`` x ``size`` tiles, left to right, then top to bottom.

    Args:
        width, height: the image size in pixels (any positive integers, not only multiples
            of ``size``).
        size: the tile edge in pixels.

    Returns:
        a list of ``ptlab.rendering.jobs.Tile(index, x0, y0, x1, y1)``: the tile covers columns x0 .. x1 - 1
        and rows y0 .. y1 - 1 (x1 and y1 are one past its last pixel). ``index`` is the tile's
        position in the list (0, 1, 2, ...). The tiles at the right and bottom edges are
        smaller when ``size`` does not divide the image. Every pixel is in exactly one tile.

    Hint: two ``range(0, n, size)`` loops, and ``min`` at the edges.
    """
    raise NotImplementedError("make_tiles")


def render_tile(setup, tile, spp):
    """One tile's job: trace ``spp`` camera paths through each of its pixels.

    This runs in a worker process. It must depend on nothing but its arguments, so that any
    process gives the same result.

    Args:
        setup: a ``ptlab.rendering.jobs.RenderSetup``: ``scene``, ``width``, ``height``, ``seed``,
            ``sampler``, ``settings`` (the path tracer's) and ``backend``.
        tile: a ``Tile``.
        spp: samples per pixel.

    Returns:
        (sums, pid): sums is a (tile height, tile width, 3) float64 array, each pixel's
        radiance summed over its spp paths; pid is ``os.getpid()``, the process that ran
        the job (the checks use it to see that the work was shared out).

    The steps (``ptlab.rendering.jobs.run_job`` does the same for ``Job(tile, 0, spp)``, with a
    film row per path that it then sums per pixel: the same sums, to float64 rounding):

    1. ``accel = accelerator_for(setup)``; ``sampler = setup.sampler``.
    2. The paths, sample-major: with n = h * w pixels in the tile, path k goes through the
       tile's pixel k % n: ``pixel = np.tile(np.arange(n), spp)``, at image column
       ``tile.x0 + pixel % w`` and row ``tile.y0 + pixel // w``; it is sample number
       ``index = np.repeat(np.arange(spp), n)`` of its pixel.
    3. ``sample = sampler.keys(pixel_y * setup.width + pixel_x, index)``: each path's key to
       its random numbers (by its pixel in the whole image, not in the tile). The camera
       jitter is ``sampler.get(sample, BounceUniforms.PIXEL, 2)``: ``origins, dirs =
       generate_rays(setup.scene.camera, setup.width, setup.height, pixel_x, pixel_y, jitter)``.
    4. ``Paths(origins, dirs, throughput, pixel, sees_emission, sample)`` with throughput
       ``np.ones((len(pixel), 3), np.float32, order="F")`` and sees_emission all True; a film
       ``np.zeros((n, 3))``; then ``trace_paths(film, setup.scene, accel, paths, sampler,
       setup.settings)`` adds every path's radiance into the film row of its pixel.
    5. Return ``film.reshape(h, w, 3)`` and ``os.getpid()``.
    """
    raise NotImplementedError("render_tile")


def render_parallel(scene, spp, res, seed=0, workers=2, tile_size=32):
    """Render ``scene`` with ``workers`` processes, one job per tile.

    Args:
        scene: a ``ptlab.scene.Scene``.
        spp: samples per pixel.
        res: ``N`` or ``(width, height)`` (``parse_resolution(res)`` gives width, height).
        seed: the render's seed: the same seed must give the same image for any ``workers``.
        workers: the number of worker processes.
        tile_size: the tile edge in pixels.

    Returns:
        (image, pids): image is (height, width, 3) float32, each pixel's sums divided by
        spp; pids is the set of the pids that the tiles' jobs returned.

    Hints:
        * ``setup = RenderSetup(scene=scene, backend=resolve_backend("auto"), width=width,
          height=height, seed=seed, settings=PathSettings())``.
        * ``ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("forkserver"))``
          as a ``with`` block (so its processes end with it); ``pool.submit(render_tile, setup,
          tile, spp)`` for every tile; ``as_completed`` gives the futures as they finish, in
          any order. ("forkserver" starts clean workers, as ptlab does: forking a process that
          has already rendered can copy Embree's threads mid-lock.)
        * Add each tile's sums into a float64 ``np.zeros((height, width, 3))`` at
          ``[tile.y0:tile.y1, tile.x0:tile.x1]``, in the main process; divide by spp at the
          end and convert to float32.
    """
    raise NotImplementedError("render_parallel")
