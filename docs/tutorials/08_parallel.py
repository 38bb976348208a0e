# %% [markdown]
# # Chapter 8 tutorial: rendering over tiles on several processes, reproducibly
#
# Pixels are independent, so an image can be cut into tiles and each tile rendered as a job
# by whichever process is free. Two rules make that right: what a job writes is not
# shared (each job *returns* its tile's sums, and the main process alone adds them to the
# image), and the random numbers belong to the pixel and the sample, not to the worker (the
# render's sampler makes every number a function of the seed, the pixel, the sample index
# and the dimension). With both, the image is the same bit for bit whatever the number of
# workers and the order in which the jobs finish. Chapter 8's exercise is the tiles, a
# tile's job and the pool (the chapter's page: `ptlab exercise docs 8`).
#
# This tutorial renders the Cornell box tile by tile on a pool of worker processes, each
# tile's job taking its random numbers from the render's sampler
# (`ptlab.rendering.jobs.run_job`), and shows which process rendered which tile. Then the
# chapter's typical mistake: a sampler seeded per worker process.

# %%
"""Chapter 8 tutorial: rendering over tiles on several processes, reproducibly.

As a script (in a notebook, the options come from PTLAB_TUTORIAL_ARGS):

    python docs/tutorials/08_parallel.py                 # writes parallel-tiles.png, parallel-wrong.png
    python docs/tutorials/08_parallel.py --res 64 --spp 4 --out /tmp/t
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

import ptlab
from ptlab.accel import make_accelerator, resolve_backend
from ptlab.course.tutorial import in_notebook, show_pictures, tutorial_options
from ptlab.image import write_image
from ptlab.integrators.path import PathSettings
from ptlab.rendering.jobs import Job, RenderSetup, make_tiles, run_job
from ptlab.samplers import make_sampler

# %% [markdown]
# ## A tile's job, in a worker process
#
# Each worker builds the scene's accelerator once and keeps it for the jobs that follow. A
# job renders one tile with `run_job` and returns the tile, its sums and the worker's
# process id, so that we can see who did what. With `per_worker_rng`, the job makes the
# chapter's mistake: whatever tile it is, its numbers depend on the process (its pid).

# %%
#: In each worker process: the accelerator, built once.
_accelerator: dict = {}


def render_tile(setup: RenderSetup, tile, spp: int, per_worker_rng: bool):
    """One tile's job in a worker: (tile, sums, pid)."""
    if setup.token not in _accelerator:
        _accelerator.clear()
        _accelerator[setup.token] = make_accelerator(setup.scene.triangles, setup.backend)
    if per_worker_rng:
        # The mistake: whatever tile it is, the numbers depend on this process (its pid).
        setup = dataclasses.replace(setup, seed=os.getpid(), sampler=make_sampler("sobol", os.getpid()))
    return tile, run_job(setup, Job(tile, 0, spp), _accelerator[setup.token]).sums, os.getpid()


# %% [markdown]
# ## The pool
#
# The jobs go to a pool of processes, one per 32 x 32 tile, and the main process adds each
# tile's sums to the image in whatever order the tiles finish. A script's worker processes
# are started by a fork server, a clean process that forks them: a process forked from one
# that has rendered would inherit Embree's threads' locks, held forever. Such a worker
# imports this file to find `render_tile`, so the tutorial's own work below runs only in the
# main process, under `if __name__ == "__main__":`. A notebook's functions live in its
# kernel, which no fresh process can import: there the workers are forked from the kernel,
# and inherit them (Linux and macOS).


# %%
def render_parallel(scene, spp: int, res: int, workers: int, per_worker_rng: bool = False):
    """(image, {tile index: pid}) rendered on a pool of ``workers`` processes, 32 x 32 tiles."""
    setup = RenderSetup(
        scene=scene, backend=resolve_backend("auto"), width=res, height=res, seed=1, settings=PathSettings()
    )
    sums = np.zeros((res, res, 3))
    pids = {}
    start_method = "fork" if in_notebook() else "forkserver"
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(start_method)) as pool:
        futures = [
            pool.submit(render_tile, setup, tile, spp, per_worker_rng) for tile in make_tiles(res, res, 32)
        ]
        for future in as_completed(futures):  # in whatever order the tiles finish
            tile, tile_sums, pid = future.result()
            sums[tile.y0 : tile.y1, tile.x0 : tile.x1] += tile_sums  # only the main process writes
            pids[tile.index] = pid
    return (sums / spp).astype(np.float32), pids


def tiles_picture(image: np.ndarray, pids: dict, res: int) -> np.ndarray:
    """The image with the tile grid drawn, each tile tinted by the process that rendered it."""
    tints = np.array([[1.0, 0.55, 0.35], [0.35, 0.6, 1.0], [0.5, 1.0, 0.5], [1.0, 1.0, 0.4]])
    order = {pid: k for k, pid in enumerate(sorted(set(pids.values())))}
    picture = np.clip(image, 0, 1) * 0.6 + 0.25
    for tile in make_tiles(res, res, 32):
        rows, columns = slice(tile.y0, tile.y1), slice(tile.x0, tile.x1)
        picture[rows, columns] *= tints[order[pids[tile.index]] % len(tints)]
        picture[tile.y0, columns] = picture[rows, tile.x0] = 1.0
    return picture


# %% [markdown]
# ## One worker or two: the same image
#
# The same render on a pool of 1 and of 2 processes. With the render's sampler the two
# images are equal bit for bit, and equal to `ptlab.render`'s with the same seed and tiles.

# %%
if __name__ == "__main__":  # (the main process only: a worker imports this file)
    args, out = tutorial_options(__doc__, res=128, spp=16)
    scene = ptlab.load_scene("cornell-box")
    tiles = make_tiles(args.res, args.res, 32)
    print(
        f"{args.res} x {args.res} pixels in {len(tiles)} tiles of at most 32 x 32, "
        f"{args.spp} samples per pixel"
    )

    images = {}
    for workers in (1, 2):
        start = time.perf_counter()
        images[workers], pids = render_parallel(scene, args.spp, args.res, workers)
        counts = {pid: list(pids.values()).count(pid) for pid in sorted(set(pids.values()))}
        print(
            f"  {workers} worker(s): {time.perf_counter() - start:.1f} s, tiles per process "
            f"{list(counts.values())}"
        )
    print(
        f"the render's sampler: 1 and 2 workers give the same image bit for bit: "
        f"{np.array_equal(images[1], images[2])}"
    )
    library = ptlab.render_result(
        scene, spp=args.spp, res=args.res, seed=1, workers=1, tile_size=32, spp_per_pass=args.spp
    ).image
    print(
        f"                    and it is ptlab.render's image (seed 1, 32 x 32 tiles): "
        f"{np.array_equal(images[2], library)}"
    )
    write_image(out / "parallel-tiles.png", tiles_picture(images[2], pids, args.res))

# %% [markdown]
# ## The mistake: a sampler per worker
#
# Seeded per worker process, a tile's noise depends on which process happened to take it:
# the image changes with the number of workers, and from run to run. The second picture is
# `|1 worker - 2 workers|` with that mistake (black with the render's sampler).

# %%
if __name__ == "__main__":
    wrong = {
        workers: render_parallel(scene, args.spp, args.res, workers, per_worker_rng=True)[0]
        for workers in (1, 2)
    }
    differ = np.any(wrong[1] != wrong[2], axis=2)
    print(f"a sampler per worker: 1 and 2 workers differ in {differ.mean():.0%} of the pixels")
    difference = np.abs(wrong[1] - wrong[2]).mean(axis=2)
    write_image(out / "parallel-wrong.png", np.repeat(np.clip(difference, 0, 1)[..., None], 3, axis=2))
    print(
        f"wrote {out / 'parallel-tiles.png'} (tiles tinted by process) and "
        f"{out / 'parallel-wrong.png'} (|1 worker - 2 workers| with a sampler per worker)"
    )
    show_pictures(out)
