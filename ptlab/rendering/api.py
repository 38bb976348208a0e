"""The ``ptlab.render`` API (re-exported by ``ptlab.rendering`` and ``ptlab``).

``render_result`` below cuts the image into tiles and the samples into passes, runs the jobs
where they were asked to run, and adds their results into the film. Along the way it reports
progress, saves a checkpoint after every pass, and stops early, keeping what is done, when
asked to. ``render`` is the same, returning only the image. Its jobs are of the size
``sizes`` sets (``TILE_SIZE``, ``SPP_PER_PASS``).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.rendering.checkpoint import load_checkpoint, save_checkpoint, scene_digest
from ptlab.rendering.film import Film
from ptlab.rendering.jobs import Job, RenderSetup, make_tiles, pass_sizes
from ptlab.rendering.memory import keep_freed_memory
from ptlab.rendering.options import DEFAULT_RES, RenderOptions, resolution, takes_options
from ptlab.rendering.scheduler import run_jobs
from ptlab.rendering.settings import check_integer, check_workers
from ptlab.rendering.sizes import SPP_PER_PASS
from ptlab.samplers import make_sampler
from ptlab.scene import Scene
from ptlab.scene_file import load_scene

__all__ = [
    "DEFAULT_RES",
    "RenderOptions",
    "RenderResult",
    "pass_schedule",
    "render",
    "render_result",
    "resolution",
]


@dataclass
class RenderResult:
    """A rendered image and how it was made.

    Attributes:
        image: (H, W, 3) float32 linear RGB, the mean of the samples.
        spp: samples per pixel that every pixel has (less than asked if stopped early).
        spp_max: samples per pixel of the tiles that have the most (= spp when complete).
        complete: False if the render was stopped before all its samples were taken.
        seconds: wall time of this call (without loading the scene).
        samples: camera samples (paths) traced by this call.
        rays: closest-hit plus shadow rays traced, over the whole render.
        query_seconds: time spent inside ray queries, summed over workers.
        sampler_seconds: time spent inside the sampler, summed over workers.
        nonfinite: samples that were NaN or infinite and were left out of the image, over
            the whole render (``ptlab.integrators.wavefront.add_to_film``): 0 unless a
            material or an integrator has a bug.
        first_nonfinite: (x, y, depth) of the first of them (by pass, then tile): the pixel
            to look at, and the bounce; None if there is none.
        settings: what made the image, for its file's header: the options
            (``RenderOptions.record``) with the scene's name, the spp every pixel has, the
            depth at which Russian roulette started and the workers.
    """

    image: np.ndarray
    spp: int
    spp_max: int
    complete: bool
    seconds: float
    samples: int
    rays: int
    query_seconds: float
    sampler_seconds: float
    nonfinite: int = 0
    first_nonfinite: tuple[int, int, int] | None = None
    settings: dict = field(default_factory=dict)

    @property
    def samples_per_second(self) -> float:
        """Camera samples (paths) per second of this call."""
        return self.samples / max(self.seconds, 1e-9)

    def __repr__(self) -> str:
        height, width = self.image.shape[:2]
        state = "complete" if self.complete else "stopped early"
        return (
            f"RenderResult({self.settings.get('scene', 'scene')!r}, {width}x{height}, "
            f"{self.spp} spp, {state}, {self.seconds:.2f} s)"
        )

    def nonfinite_message(self) -> str:
        """What to say of the samples left out as NaN or infinite ("" when there is none)."""
        if not self.nonfinite:
            return ""
        where = ""
        if self.first_nonfinite is not None:
            x, y, depth = self.first_nonfinite
            where = f"; the first at pixel ({x}, {y}), depth {depth}"
        return f"{self.nonfinite} samples were NaN or infinite and were left out of the image{where}"

    def _repr_png_(self) -> bytes:
        """The image as an sRGB PNG: how Jupyter shows a result (as Mitsuba's ``Bitmap``)."""
        from ptlab.rendering.display import png_bytes

        return png_bytes(self.image)


@takes_options
def render_result(
    scene: Scene | str,
    *args,
    options: RenderOptions | None = None,
    executor: Executor | None = None,
    checkpoint: str | Path | None = None,
    resume: str | Path | None = None,
    progress: Callable[[Film], None] | bool | None = None,
    on_pass: Callable[[Film], None] | None = None,
    stop: Callable[[], bool] | None = None,
    command: dict | None = None,
    **keywords: Any,
) -> RenderResult:
    """Render and return the image with its statistics (arguments as for ``render``).

    Args (beyond ``render``'s):
        checkpoint: save the film here after every pass (and when stopped).
        resume: continue the render saved in this checkpoint.
        progress: called with the film after every job; True shows a progress bar (in a
            notebook too, ``ptlab.rendering.progress``).
        on_pass: called with the film whenever a pass over the whole image completes.
        stop: polled between jobs; when it returns True the render stops early and
            returns what it has (``complete`` is then False).
        command: kept in the checkpoint, not compared: what ``ptlab render --resume FILE``
            needs besides the options (``scene`` and ``out``).
    """
    options = RenderOptions.of(args, options, keywords)
    if isinstance(scene, str | Path):
        scene = load_scene(scene)
    options = options.for_scene(scene)
    workers = check_workers(options.workers)
    sampler = make_sampler(options.sampler, options.seed, options.spp)
    scene = scene.with_sampling(options.sampling)
    settings = options.path_settings()
    keep_freed_memory()

    width, height = options.size
    tiles = make_tiles(width, height, options.tile_size)
    passes = pass_schedule(options.spp, options.spp_per_pass)
    film = Film(width, height, tiles, passes)
    record = options.record()
    # Any number of workers may resume a render; the sampler's identity says what of it the
    # image depends on (its name, and for some the spp).
    identity = dict(record, scene=scene_digest(scene), sampler=sampler.identity)
    del identity["workers"]
    if resume is not None:
        load_checkpoint(resume, film, identity)
    samples_at_start = film.samples

    start = time.perf_counter()
    setup = RenderSetup(
        scene=scene,
        backend=options.backend,
        width=width,
        height=height,
        seed=options.seed,
        settings=settings,
        integrator=options.integrator,
        sampler=sampler,
    )
    first_sample = np.concatenate([[0], np.cumsum(passes)])
    jobs = [
        Job(tile, k, n, int(first_sample[k]))
        for k, n in enumerate(passes)
        for tile in tiles
        if k >= film.passes_done[tile.index]
    ]
    if executor is None:
        workers = min(workers, len(jobs))  # a pool for one job would only cost its start-up
    complete_passes = int(film.passes_done.min())
    report, bar = _progress_reports(progress, film)
    for result in run_jobs(jobs, setup, max(workers, 1), executor, stop or (lambda: False)):
        film.add(result)
        if report is not None:
            report(film)
        if film.passes_done.min() > complete_passes:
            complete_passes = int(film.passes_done.min())
            if checkpoint is not None:
                save_checkpoint(checkpoint, film, identity, command)
            if on_pass is not None:
                on_pass(film)
    if bar is not None:
        bar.close()
    complete = film.complete
    if film.spp_max == 0 and not complete:
        warnings.warn("the render stopped before any tile had a pass: its image is black", RuntimeWarning, 2)
    if checkpoint is not None and not complete:
        save_checkpoint(checkpoint, film, identity, command)
    seconds = time.perf_counter() - start
    return RenderResult(
        image=film.image(),
        spp=film.spp,
        spp_max=film.spp_max,
        complete=complete,
        seconds=seconds,
        samples=film.samples - samples_at_start,
        rays=film.rays,
        query_seconds=film.query_seconds,
        sampler_seconds=film.sampler_seconds,
        nonfinite=film.nonfinite,
        first_nonfinite=film.first_nonfinite,
        settings=dict(
            record,
            scene=scene.name,
            spp=film.spp,
            rr_depth=settings.roulette_starts,
            workers=workers if executor is None else "executor",
        ),
    )


def _progress_reports(progress, film: Film) -> tuple[Callable[[Film], None] | None, Any]:
    """What to call after each job: ``progress`` itself, or for True a new progress bar
    (``ptlab.rendering.progress``), returned again as the second value, to be closed."""
    if progress is not True:
        return progress or None, None
    from ptlab.rendering.progress import ProgressBar

    height, width = film.sums.shape[:2]
    bar = ProgressBar(width * height * sum(film.passes), len(film.passes), initial=film.samples)
    return bar, bar


def pass_schedule(spp: int, spp_per_pass: int | None = None) -> list[int]:
    """Samples per pixel of each pass of a render (``SPP_PER_PASS`` by default)."""
    spp_per_pass = SPP_PER_PASS if spp_per_pass is None else check_integer("spp per pass", spp_per_pass, 1)
    return pass_sizes(spp, min(spp, spp_per_pass))


@takes_options
def render(
    scene: Scene | str,
    *args,
    options: RenderOptions | None = None,
    executor: Executor | None = None,
    progress: bool = False,
    **keywords: Any,
) -> np.ndarray:
    """Render a scene; return (H, W, 3) float32 linear RGB.

    The options are ``RenderOptions``' fields (below), given by name, in order, or all at
    once as ``options=RenderOptions(...)`` (names given beside it then replace some).

    Args:
        scene: a ``Scene``, a built-in scene name (``"cornell-box"``) or a scene file path.
        options: the options, as one ``RenderOptions``.
        executor: run the jobs on this ``concurrent.futures.Executor`` (a thread pool, a
            Dask client's ``get_executor()``, ...) instead of ptlab's own process pool;
            the image is the same, bit for bit.
        progress: show a progress bar (on a terminal, or in a notebook), or a line per pass.
    """
    options = RenderOptions.of(args, options, keywords)
    result = render_result(scene, options=options, executor=executor, progress=progress or None)
    if result.nonfinite:  # (a bug in a material or an integrator; ``render_result`` counts them)
        warnings.warn(result.nonfinite_message(), RuntimeWarning, stacklevel=2)
    return result.image
