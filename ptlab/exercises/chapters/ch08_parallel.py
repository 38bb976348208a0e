"""Chapter 8's checks: rendering over tiles on several processes (``make_tiles``,
``render_tile``, ``render_parallel``).

* Tiles must cover every pixel exactly once, at odd image sizes and at the image's edges.
* A tile's job must give exactly the library's sums (``ptlab.rendering.jobs.run_job``: every
  random number from the setup's sampler, by pixel and sample), and the same sums again when
  the same process has rendered other tiles in between (no generator shared between jobs).
* ``render_parallel`` must really use several processes (each tile's job reports the pid of
  the process that ran it), give the same image bit for bit with 1 and 2 workers, and that
  image must be the library's (``ptlab.render_result`` with the same seed and tile size, one
  pass): all deterministic, so every comparison is exact and no check is statistical.

The scene is chapter 7's furnace (``ch07_path_tracing.furnace_scene``): built without
reading mesh files, so the checks spend their time on the parallel part.

The student's code runs in a process of its own (``ptlab.untrusted``): "this process" below
is that one. The checks that run the student's pool end any worker the student's code
leaves behind (and the grader ends every process the check started when it is done).
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from ptlab.exercises.chapter import Chapter, ChapterCheck, CheckFailed, grading_rng, grading_seed_for, require
from ptlab.exercises.finite import at_pixel, require_finite
from ptlab.untrusted import submission_of

if TYPE_CHECKING:
    from ptlab.rendering.jobs import RenderSetup
    from ptlab.scene import Scene

#: What the render checks render: the furnace at 48 x 40 (odd tiles at the right and bottom
#: edges with TILE = 16), SPP samples per pixel, the seed stream SEED of the grading seed
#: (``ptlab.exercises.chapter.grading_seed_for``: new for each grading).
RES, SPP, TILE, SEED = (48, 40), 8, 16, 8
#: The share of pixels (about twice as bright as the library's) that says pixels were added
#: twice: 10 of the 1920, where noise makes 0 to 3 (measured on 5 pairs of seeds).
DOUBLED_SHARE = 0.005


def _scene() -> Scene:
    from ptlab.exercises.chapters.ch07_path_tracing import furnace_scene

    return furnace_scene()


def _seed() -> int:
    """The render checks' seed: stream SEED of the grading seed."""
    return grading_seed_for(SEED)


def _setup(scene: Scene) -> RenderSetup:
    from ptlab.accel import resolve_backend
    from ptlab.integrators.path import PathSettings
    from ptlab.rendering.jobs import RenderSetup

    return RenderSetup(
        scene=scene,
        backend=resolve_backend("auto"),
        width=RES[0],
        height=RES[1],
        seed=_seed(),
        settings=PathSettings(),
    )


# -- tiles -------------------------------------------------------------------------------------


def check_tiles(module) -> str:
    (make_tiles,) = require(module, "make_tiles")
    cases = [(37, 23, 8), (64, 64, 16), (5, 3, 8), (100, 1, 7), (16, 48, 16)]
    rng = grading_rng(80)  # and three sizes new for each grading
    cases += [tuple(int(n) for n in rng.integers(1, (100, 100, 20))) for _ in range(3)]
    for width, height, size in cases:
        tiles = list(make_tiles(width, height, size))
        where = f"make_tiles({width}, {height}, {size})"
        if not tiles:
            raise CheckFailed(f"{where} returned no tiles")
        covered = np.zeros((height, width), dtype=int)
        for position, tile in enumerate(tiles):
            if not all(hasattr(tile, name) for name in ("index", "x0", "y0", "x1", "y1")):
                raise CheckFailed(f"{where}: tiles must be ptlab.rendering.jobs.Tile(index, x0, y0, x1, y1)")
            if tile.index != position:
                raise CheckFailed(
                    f"{where}: tile {position} of the list has index {tile.index}; "
                    f"number the tiles 0, 1, 2, ... in list order (a tile's index "
                    f"is its place in the list)"
                )
            if not (0 <= tile.x0 < tile.x1 <= width and 0 <= tile.y0 < tile.y1 <= height):
                raise CheckFailed(
                    f"{where}: tile {tile.index} spans columns {tile.x0}..{tile.x1 - 1} "
                    f"and rows {tile.y0}..{tile.y1 - 1}, outside the {width} x "
                    f"{height} image or empty (x1 and y1 are one past the last "
                    f"pixel: clip them with min(x0 + size, width))"
                )
            if tile.x1 - tile.x0 > size or tile.y1 - tile.y0 > size:
                raise CheckFailed(f"{where}: tile {tile.index} is larger than {size} x {size}")
            covered[tile.y0 : tile.y1, tile.x0 : tile.x1] += 1
        if (covered == 0).any():
            y, x = np.argwhere(covered == 0)[0]
            raise CheckFailed(
                f"{where}: pixel (x={x}, y={y}) is in no tile (the last, smaller "
                f"tiles at the right and bottom edges?)"
            )
        if (covered > 1).any():
            y, x = np.argwhere(covered > 1)[0]
            raise CheckFailed(
                f"{where}: pixel (x={x}, y={y}) is in {covered[y, x]} tiles: it "
                f"would be rendered, and added to the image, more than once"
            )
    return f"every pixel in exactly one tile, for {len(cases)} image and tile sizes"


# -- one tile's job ---------------------------------------------------------------------------


def _tile_result(render_tile, setup, tile, spp: int) -> tuple[np.ndarray, int]:
    result = render_tile(setup, tile, spp)
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed("render_tile must return two things: (sums, os.getpid())")
    sums, pid = np.asarray(result[0]), result[1]
    height, width = tile.y1 - tile.y0, tile.x1 - tile.x0
    if sums.shape != (height, width, 3):
        raise CheckFailed(
            f"render_tile must return the tile's sums as a ({height}, {width}, 3) "
            f"array (rows, columns, colour), not {sums.shape}"
        )
    return sums, pid


def at_pixel_of(tile):
    """``finite.at_pixel`` for the sums of ``tile``: the pixel named in the whole image."""

    def where(index, shape) -> str:
        y, x, channel = index
        return at_pixel((tile.y0 + y, tile.x0 + x, channel), shape)

    return where


def check_tile_job(module) -> str:
    from ptlab.accel import make_accelerator
    from ptlab.rendering.jobs import Job, Tile, run_job

    (render_tile,) = require(module, "render_tile")
    first, second = Tile(5, 16, 16, 32, 32), Tile(8, 32, 32, 48, 40)
    library = _setup(_scene())  # the grader's own: the student's setup is another
    expected = run_job(
        library, Job(first, 0, 4), make_accelerator(library.scene.triangles, library.backend)
    ).sums
    setup = _setup(_scene())
    sums, pid = _tile_result(render_tile, setup, first, 4)
    require_finite(sums, "the tile's sums", at_pixel_of(first))
    here = submission_of(module).pid
    if pid != here:
        raise CheckFailed(
            f"render_tile must return the pid of the process that ran it "
            f"(os.getpid()); it returned {pid!r}, this process is {here}"
        )
    _tile_result(render_tile, setup, second, 4)
    again, _ = _tile_result(render_tile, setup, first, 4)
    if not np.array_equal(again, sums):
        raise CheckFailed(
            "the same tile rendered again, after another tile in the same "
            "process, gives other sums: its random numbers depend on what the "
            "process did before (one generator per process, or a global one?). "
            "Take every random number from setup.sampler, by the paths' keys "
            "sampler.keys(pixel ids, sample indices)"
        )
    # The library sums each path's radiance first, then a pixel's paths (a film row per path,
    # ``run_job``); a film row per pixel, as the template has it, adds the same numbers in
    # another order: equal to float64 rounding (1e-16), where other random numbers, a
    # path lost or counted twice differ by whole samples.
    if not np.allclose(sums, expected, rtol=1e-12, atol=0):
        if np.abs(sums).max() == 0:
            raise CheckFailed(
                "the tile's sums are empty: return the film the tile's paths "
                "were traced into, reshaped to (h, w, 3)"
            )
        raise CheckFailed(
            "the tile's sums are not the library's: a tile's job takes every "
            "random number from setup.sampler: keys = sampler.keys(pixel_y * "
            "setup.width + pixel_x, sample index) for paths in sample-major order, "
            "the camera jitter sampler.get(keys, BounceUniforms.PIXEL, 2), then "
            "trace_paths with the same sampler (as ptlab.rendering.jobs.run_job "
            "does)"
        )
    return "a tile's sums are the library's, and the same whatever the process rendered before"


# -- the pool -----------------------------------------------------------------------------------


def importable(module: ModuleType) -> ModuleType:
    """The student's module again, imported under its file's name from its folder.

    The grader imports the student's file under a made-up name, which a worker process
    (started by forkserver or spawn) could not import to find ``render_tile`` by; imported
    as ``08_parallel`` with its folder on ``sys.path`` (which new processes inherit) it can.
    """
    imported = submission_of(module).import_by_file_name()
    if isinstance(imported, str):
        name = submission_of(module).path.stem
        raise CheckFailed(
            f"another module is called {name!r} too ({imported}): rename your "
            f"file, e.g. to 08_parallel.py, so that worker processes import yours"
        )
    return imported


def _render(module, workers: int, spp: int = SPP) -> tuple[np.ndarray, set]:
    (render_parallel,) = require(module, "render_parallel")
    try:
        result = render_parallel(_scene(), spp, RES, seed=_seed(), workers=workers, tile_size=TILE)
    finally:
        submission_of(module).end_started_processes()  # workers left behind
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed("render_parallel must return two things: (image, pids)")
    image, pids = np.asarray(result[0]), set(result[1])
    if image.shape != (RES[1], RES[0], 3):
        raise CheckFailed(
            f"the image must have shape (height, width, 3) = ({RES[1]}, {RES[0]}, 3), not {image.shape}"
        )
    require_finite(image, "the image", at_pixel)
    if np.abs(image).max() == 0:
        raise CheckFailed(
            "the image is black: the tiles' sums never reached it. Each worker "
            "has its own copy of anything you pass it, so writing into an "
            "image there changes nothing here: return each tile's sums and add "
            "them into the image in the main process"
        )
    return image, pids


#: A pool whose second process starts late (on a loaded machine) may leave every tile to the
#: first one, so the parallel check renders with PARALLEL_SPP samples (tiles that take long
#: enough for both to start) up to PARALLEL_ATTEMPTS times: work done in one process alone
#: never shows two pids, however often it runs.
PARALLEL_SPP, PARALLEL_ATTEMPTS = 4 * SPP, 3


def check_parallel(module) -> str:
    student = importable(module)
    for _ in range(PARALLEL_ATTEMPTS):
        _, pids = _render(student, workers=2, spp=PARALLEL_SPP)
        workers = pids - {submission_of(module).pid}
        if len(workers) >= 2:
            break
    if len(workers) < 2:
        where = (
            "in this process only (threads, or no pool at all? threads share one "
            "process, where Python runs one of them at a time)"
            if not workers
            else f"in one process only (pid {min(workers)})"
        )
        raise CheckFailed(
            f"with workers=2 every tile was rendered {where}: submit each tile's "
            f"job to a pool of 2 processes (concurrent.futures.ProcessPoolExecutor "
            f"or multiprocessing.Pool) and collect what each job returns"
        )
    return f"the tiles were rendered by {len(workers)} worker processes"


def check_worker_count(module) -> str:
    module = importable(module)
    two, _ = _render(module, workers=2)
    one, _ = _render(module, workers=1)
    if not np.array_equal(one, two):
        differ = np.any(one != two, axis=2)
        raise CheckFailed(
            f"the image with 2 workers differs from the one with 1 worker in "
            f"{differ.sum()} of {differ.size} pixels: the random numbers depend on "
            f"which process renders which tile, or in which order. Take them from "
            f"setup.sampler, by pixel and sample: never a generator (or sampler) "
            f"made per worker, and none shared between jobs"
        )
    return "the image is the same, bit for bit, with 1 and 2 workers"


def check_library(module) -> str:
    from ptlab.rendering import render_result

    expected = render_result(
        _scene(), spp=SPP, res=RES, seed=_seed(), workers=1, tile_size=TILE, spp_per_pass=SPP
    ).image
    image, _ = _render(importable(module), workers=2)
    empty = image.max(axis=2) == 0
    if empty.any():
        y, x = np.argwhere(empty)[0]
        raise CheckFailed(
            f"{empty.sum()} pixels are black, e.g. (x={x}, y={y}): some tiles "
            f"were never rendered or added (the last, smaller tiles at the right "
            f"and bottom edges?)"
        )
    if not np.array_equal(image, expected):
        ratio = float(image.mean() / expected.mean())
        differ = np.any(image != expected, axis=2)
        # A pixel rendered and added twice comes out about twice as bright, and the image
        # brighter by the share of such pixels. (At 8 spp a furnace pixel is over 1.5x
        # another render's in about 1 in 1000 pixels by chance, so a few do not count.)
        doubled = np.all(image > 1.5 * expected, axis=2)
        share = float(doubled.mean())
        if share > DOUBLED_SHARE and 0.5 * share < ratio - 1 < 1.5 * share:
            y, x = np.argwhere(doubled)[0]
            hint = (
                f"{doubled.sum()} pixels, e.g. (x={x}, y={y}), are about twice as bright as "
                f"the library's: they were rendered and added twice, by tiles that overlap "
                f"(x1 and y1 are one past a tile's last pixel; see 'tiles')"
            )
        elif abs(ratio - 1) > 0.05:
            hint = "divide the sums by spp once, at the end"
        else:
            hint = (
                "the same seed must give the library's random numbers: setup.sampler's, "
                "keyed by each path's pixel in the whole image and its sample index, and "
                "float64 sums divided by spp, then float32"
            )
        raise CheckFailed(
            f"your image differs from the library's (same seed, tile size {TILE}, "
            f"one pass) in {differ.sum()} of {differ.size} pixels and is "
            f"{ratio:.3f}x as bright: {hint}"
        )
    return f"the image is the library's, bit for bit (seed {_seed()}, {TILE} x {TILE} tiles)"


CHAPTER = Chapter(
    number=8,
    slug="parallel",
    title="Parallel rendering over tiles",
    functions=("make_tiles", "render_tile", "render_parallel"),
    # The workers may be new interpreters (forkserver, as ptlab's own are), so this chapter's
    # code may start programs (docs/grading-security.md says what that leaves open).
    answers=(
        "ptlab.rendering.jobs.make_tiles",
        "ptlab.rendering.jobs.run_job",
        "ptlab.rendering.jobs.run_job_group",
        "ptlab.rendering.jobs.run_job_group_in_worker",
        "ptlab.rendering.api.render",
        "ptlab.rendering.api.render_result",
    ),
    programs=True,
    checks=(
        ChapterCheck("tiles", 2, check_tiles, timeout=20),
        ChapterCheck("tile job", 2, check_tile_job, timeout=30),
        ChapterCheck("parallel", 2, check_parallel, timeout=60),
        ChapterCheck("any worker count", 2, check_worker_count, timeout=90),
        ChapterCheck("matches the library", 2, check_library, timeout=60),
    ),
)
