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

The student's code runs in a process of its own (``ptlab.course.sandbox``): "this process" below
is that one. The checks that run the student's pool end any worker the student's code
leaves behind (and the grader ends every process the check started when it is done).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ptlab.course.chapter import (
    Chapter,
    ChapterCheck,
    ChapterRender,
    CheckFailed,
    grading_rng,
    grading_seed_for,
    require,
)
from ptlab.course.finite import at_pixel, require_finite
from ptlab.course.messages import check_name, text
from ptlab.course.sandbox import RemoteModule, submission_of

if TYPE_CHECKING:
    from ptlab.rendering.jobs import RenderSetup
    from ptlab.scene import Scene

#: What the render checks render: the furnace at 48 x 40 (odd tiles at the right and bottom
#: edges with TILE = 16), SPP samples per pixel, the seed stream SEED of the grading seed
#: (``ptlab.course.chapter.grading_seed_for``: new for each grading).
RES, SPP, TILE, SEED = (48, 40), 8, 16, 8
#: The share of pixels (about twice as bright as the library's) that says pixels were added
#: twice: 10 of the 1920, where noise makes 0 to 3 (measured on 5 pairs of seeds).
DOUBLED_SHARE = 0.005
#: The largest difference from the library's float64 values, relative, that rounding to
#: float32 explains (float32 keeps a value to 6e-8 an addition; other random numbers change
#: a furnace pixel by whole samples, percents): at most this much is sums added in float32.
ROUNDING = 1e-4
#: Two tiles whose values at the same places in the tile are correlated at least this much
#: (and this much more than the library's) drew the same random numbers there: measured,
#: 0.94 to 0.99 for keys of the pixel's place in its tile, -0.05 to 0.05 for the library's
#: (16 x 8 pixels of the furnace at 4 spp, 3 seeds), where chance gives a standard deviation
#: of 0.09.
SAME_PLACE_CORRELATION = 0.5


def _scene() -> Scene:
    from ptlab.course.chapters.ch07_path_tracing import furnace_scene

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
    new_sizes = (rng.integers(1, (100, 100, 20)) for _ in range(3))
    cases += [(int(width), int(height), int(size)) for width, height, size in new_sizes]
    for width, height, size in cases:
        tiles = list(make_tiles(width, height, size))
        where = f"make_tiles({width}, {height}, {size})"
        if not tiles:
            raise CheckFailed(text("ch08.no_tiles", where=where))
        covered = np.zeros((height, width), dtype=int)
        for position, tile in enumerate(tiles):
            if not all(hasattr(tile, name) for name in ("index", "x0", "y0", "x1", "y1")):
                raise CheckFailed(text("ch08.tile_type", where=where))
            if tile.index != position:
                raise CheckFailed(text("ch08.index", where=where, position=position, index=tile.index))
            if not (0 <= tile.x0 < tile.x1 <= width and 0 <= tile.y0 < tile.y1 <= height):
                raise CheckFailed(
                    text(
                        "ch08.outside",
                        where=where,
                        index=tile.index,
                        x0=tile.x0,
                        x1=tile.x1 - 1,
                        y0=tile.y0,
                        y1=tile.y1 - 1,
                        width=width,
                        height=height,
                    )
                )
            w, h = tile.x1 - tile.x0, tile.y1 - tile.y0
            if max(w, h) == size + 1:  # (an end one past the last pixel, counted once more)
                raise CheckFailed(text("ch08.one_larger", where=where, index=tile.index, w=w, h=h, size=size))
            if w > size or h > size:
                raise CheckFailed(text("ch08.larger", where=where, index=tile.index, size=size))
            covered[tile.y0 : tile.y1, tile.x0 : tile.x1] += 1
        if (covered == 0).any():
            y, x = np.argwhere(covered == 0)[0]
            raise CheckFailed(text("ch08.in_no_tile", where=where, x=x, y=y))
        if (covered > 1).any():
            y, x = np.argwhere(covered > 1)[0]
            raise CheckFailed(text("ch08.in_tiles", where=where, x=x, y=y, count=covered[y, x]))
    return text("ch08.tiles_ok", n=len(cases))


# -- one tile's job ---------------------------------------------------------------------------


def _tile_result(render_tile, setup, tile, spp: int) -> tuple[np.ndarray, int]:
    result = render_tile(setup, tile, spp)
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed(text("ch08.tile_result"))
    sums, pid = np.asarray(result[0]), result[1]
    height, width = tile.y1 - tile.y0, tile.x1 - tile.x0
    if sums.shape != (height, width, 3):
        raise CheckFailed(text("ch08.sums_shape", height=height, width=width, shape=sums.shape))
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
    accel = make_accelerator(library.scene.triangles, library.backend)
    expected, expected_second = (run_job(library, Job(tile, 0, 4), accel).sums for tile in (first, second))
    setup = _setup(_scene())
    sums, pid = _tile_result(render_tile, setup, first, 4)
    require_finite(sums, text("ch08.sums"), at_pixel_of(first))
    here = submission_of(module).own_pid
    if pid != here:
        raise CheckFailed(text("ch08.pid", pid=repr(pid), here=here))
    sums_second, _ = _tile_result(render_tile, setup, second, 4)
    again, _ = _tile_result(render_tile, setup, first, 4)
    if not np.array_equal(again, sums):
        raise CheckFailed(text("ch08.again"))
    # The library sums each path's radiance first, then a pixel's paths (a film row per path,
    # ``run_job``); a film row per pixel, as the template has it, adds the same numbers in
    # another order: equal to float64 rounding (1e-16), where other random numbers, a
    # path lost or counted twice differ by whole samples.
    if not np.allclose(sums, expected, rtol=1e-12, atol=0):
        if np.abs(sums).max() == 0:
            raise CheckFailed(text("ch08.empty"))
        height = second.y1 - second.y0  # (the part of the first tile at the second's places)
        hint = rounded_in_float32(sums, expected, first) or same_numbers_in_tiles(
            (sums[:height], sums_second), (expected[:height], expected_second), first, second
        )
        raise CheckFailed(text("ch08.tile_not_library", hint=hint) if hint else text("ch08.not_library"))
    return text("ch08.tile_ok")


def rounded_in_float32(yours: np.ndarray, expected: np.ndarray, tile) -> str | None:
    """The message "ch08.hint.float32" if ``yours`` differs from the float64 ``expected``
    (both (h, w, 3) values of ``tile``'s pixels) by rounding alone (at most ``ROUNDING`` of a
    value, relative), naming the pixel that differs most (its place in the whole image);
    else None."""
    relative = np.abs(yours - expected) / np.maximum(np.abs(expected), np.finfo(np.float64).tiny)
    if not relative.max() <= ROUNDING:
        return None
    y, x, channel = np.unravel_index(np.argmax(relative), relative.shape)
    return text(
        "ch08.hint.float32",
        error=relative.max(),
        x=tile.x0 + x,
        y=tile.y0 + y,
        yours=yours[y, x, channel],
        expected=expected[y, x, channel],
    )


def same_numbers_in_tiles(yours: tuple, library: tuple, tile, other) -> str | None:
    """The message "ch08.hint.tile_keys" if the student's values of ``tile`` and ``other`` go
    together at the same places in the tile (``SAME_PLACE_CORRELATION``) where the library's
    do not: the two tiles drew the same random numbers there, by keys of the pixel's place in
    its tile.
    ``yours``, ``library``: the two tiles' (h, w, 3) values at the same (h, w) places (their
    top left parts). The pixels named are the pair whose library values differ most while
    the student's agree."""
    a, b = (values.sum(axis=2) for values in yours)
    library_a, library_b = (values.sum(axis=2) for values in library)
    with np.errstate(all="ignore"):  # (a tile of one value has no correlation: NaN, no hint)
        correlation = float(np.corrcoef(a.ravel(), b.ravel())[0, 1])
        library_correlation = float(np.corrcoef(library_a.ravel(), library_b.ravel())[0, 1])
    if not (
        correlation >= SAME_PLACE_CORRELATION and correlation - library_correlation >= SAME_PLACE_CORRELATION
    ):
        return None
    y, x = np.unravel_index(np.argmax(np.abs(library_a - library_b) - np.abs(a - b)), a.shape)
    return text(
        "ch08.hint.tile_keys",
        xa=tile.x0 + x,
        ya=tile.y0 + y,
        xb=other.x0 + x,
        yb=other.y0 + y,
        a=a[y, x],
        b=b[y, x],
        library_a=library_a[y, x],
        library_b=library_b[y, x],
        correlation=correlation,
        library_correlation=library_correlation,
    )


# -- the pool -----------------------------------------------------------------------------------


def importable(module: RemoteModule) -> RemoteModule:
    """The student's module again, imported under its file's name from its folder.

    The grader imports the student's file under a made-up name, which a worker process
    (started by forkserver or spawn) could not import to find ``render_tile`` by; imported
    as ``08_parallel`` with its folder on ``sys.path`` (which new processes inherit) it can.
    """
    imported = submission_of(module).import_by_file_name()
    if isinstance(imported, str):
        name = submission_of(module).path.stem
        raise CheckFailed(text("ch08.name_taken", name=repr(name), imported=imported))
    return imported


def _render_parallel(module, scene: Scene, spp: int, res: tuple, seed: int, workers: int) -> tuple:
    """The student's ``render_parallel(scene, ...)``: (image, the pids that rendered it)."""
    (render_parallel,) = require(module, "render_parallel")
    try:
        result = render_parallel(scene, spp, res, seed=seed, workers=workers, tile_size=TILE)
    finally:
        submission_of(module).end_started_processes()  # workers left behind
    if not (isinstance(result, tuple) and len(result) == 2):
        raise CheckFailed(text("ch08.parallel_result"))
    return np.asarray(result[0]), set(result[1])


def _render(module, workers: int, spp: int = SPP) -> tuple[np.ndarray, set]:
    image, pids = _render_parallel(module, _scene(), spp, RES, _seed(), workers)
    if image.shape != (RES[1], RES[0], 3):
        raise CheckFailed(text("ch08.image_shape", height=RES[1], width=RES[0], shape=image.shape))
    require_finite(image, text("ch08.image"), at_pixel)
    if np.abs(image).max() == 0:
        raise CheckFailed(text("ch08.black"))
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
        workers = pids - {submission_of(module).own_pid}
        if len(workers) >= 2:
            break
    if len(workers) < 2:
        where = text("ch08.this_process") if not workers else text("ch08.one_process", pid=min(workers))
        raise CheckFailed(text("ch08.not_parallel", where=where))
    return text("ch08.parallel_ok", n=len(workers))


def check_worker_count(module) -> str:
    module = importable(module)
    two, _ = _render(module, workers=2)
    one, _ = _render(module, workers=1)
    if not np.array_equal(one, two):
        differ = np.any(one != two, axis=2)
        raise CheckFailed(text("ch08.workers", wrong=differ.sum(), n=differ.size))
    return text("ch08.workers_ok")


def check_library(module) -> str:
    from ptlab.rendering import render_result

    films = []  # (the film's float64 sums, to compare with before they are rounded to float32)
    expected = render_result(
        _scene(),
        spp=SPP,
        res=RES,
        seed=_seed(),
        workers=1,
        tile_size=TILE,
        spp_per_pass=SPP,
        on_pass=lambda film: films.append(film.sums / SPP),
    ).image
    image, _ = _render(importable(module), workers=2)
    empty = image.max(axis=2) == 0
    if empty.any():
        y, x = np.argwhere(empty)[0]
        raise CheckFailed(text("ch08.black_pixels", count=empty.sum(), x=x, y=y))
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
            hint = text("ch08.hint.doubled", count=doubled.sum(), x=x, y=y, check=check_name(8, "tiles"))
        elif abs(ratio - 1) > 0.05:
            hint = text("ch08.hint.spp")
        else:
            hint = _numbers_hint(image, expected, films[-1])
        raise CheckFailed(
            text("ch08.library", tile=TILE, wrong=differ.sum(), n=differ.size, ratio=ratio, hint=hint)
        )
    return text("ch08.library_ok", seed=_seed(), tile=TILE)


def _numbers_hint(image: np.ndarray, expected: np.ndarray, exact: np.ndarray) -> str:
    """What an image as bright as the library's but not the same says: float32's rounding
    (against the library's float64 values ``exact``), the first two tiles alike at the same
    places (``same_numbers_in_tiles``), or else other random numbers."""
    from ptlab.rendering.jobs import Tile

    two = (Tile(0, 0, 0, TILE, TILE), Tile(1, TILE, 0, 2 * TILE, TILE))  # (the first two)
    return (
        rounded_in_float32(image, exact, Tile(0, 0, 0, *RES))
        or same_numbers_in_tiles(
            tuple(image[t.y0 : t.y1, t.x0 : t.x1] for t in two),
            tuple(expected[t.y0 : t.y1, t.x0 : t.x1] for t in two),
            *two,
        )
        or text("ch08.hint.sampler")
    )


def render_yours(module, scene: Scene, options: dict) -> np.ndarray:
    """``scene`` rendered by the student's ``render_parallel`` on two workers (``ptlab
    exercise render``; its own progress, if any: the library's bar is not in it)."""
    image, _ = _render_parallel(importable(module), scene, options["spp"], options["res"], options["seed"], 2)
    return image


CHAPTER = Chapter(
    number=8,
    slug="parallel",
    title="Parallel rendering over tiles",
    functions=("make_tiles", "render_tile", "render_parallel"),
    answers=(
        "ptlab.rendering.jobs.make_tiles",
        "ptlab.rendering.jobs.run_job",
        "ptlab.rendering.jobs.run_job_group",
        "ptlab.rendering.jobs.run_job_group_in_worker",
        "ptlab.rendering.api.render",
        "ptlab.rendering.api.render_result",
    ),
    # Its workers may be new interpreters, started in the same sandbox with the same kit:
    # the library's pools, schedulers and camera samples are not in it.
    also_left_out=(
        "ptlab.rendering.api",
        "ptlab.rendering.scheduler",
        "ptlab.rendering.executors",
        "ptlab.rendering.jobs.pass_sizes",
        "ptlab.rendering.jobs.CameraSamples",
        "ptlab.rendering.jobs.job_groups",
        "ptlab.rendering.jobs.install_setup",
        "ptlab.inspector",
        "ptlab.measure",
    ),
    checks=(
        ChapterCheck("tiles", 2, check_tiles, timeout=20),
        ChapterCheck("tile job", 2, check_tile_job, timeout=30),
        ChapterCheck("parallel", 2, check_parallel, timeout=60),
        ChapterCheck("any worker count", 2, check_worker_count, timeout=90),
        ChapterCheck("matches the library", 2, check_library, timeout=60),
    ),
    render=ChapterRender(render_yours),
)
