"""The ``ptlab.render`` API (re-exported by ``ptlab.rendering`` and ``ptlab``).

``render_result`` below cuts the image into tiles and the samples into passes, runs the jobs
where they were asked to run, and adds their results into the film. Along the way it reports
progress, saves a checkpoint after every pass, and stops early, keeping what is done, when
asked to. ``render`` is the same, returning only the image. Its jobs are of the size
``sizes`` sets (``TILE_SIZE``, ``SPP_PER_PASS``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ptlab.accel import resolve_backend
from ptlab.errors import PtlabError
from ptlab.integrators import INTEGRATORS
from ptlab.integrators.path import PathSettings
from ptlab.rendering.checkpoint import load_checkpoint, save_checkpoint, scene_digest
from ptlab.rendering.film import Film
from ptlab.rendering.jobs import Job, RenderSetup, make_tiles, pass_sizes
from ptlab.rendering.memory import keep_freed_memory
from ptlab.rendering.scheduler import run_jobs
from ptlab.rendering.settings import check_settings, check_tile_size, check_workers, parse_resolution
from ptlab.rendering.sizes import SPP_PER_PASS, TILE_SIZE
from ptlab.samplers import DEFAULT_SAMPLER, make_sampler
from ptlab.scene import Scene, load_scene

#: The resolution of a render that gives none, of a scene whose file has no ``[render] res``.
DEFAULT_RES = (512, 512)


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
        settings: the options that made the image (for metadata).
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
    settings: dict = field(default_factory=dict)

    @property
    def samples_per_second(self) -> float:
        """Camera samples (paths) per second of this call."""
        return self.samples / max(self.seconds, 1e-9)


def render_result(scene: Scene | str, spp: int = 16, res=None, seed: int = 0,
                  workers: int | None = None, executor: Executor | None = None,
                  backend: str = "auto", integrator: str = "path", sampling: str = "cosine",
                  rr: float | str = "throughput", max_depth: int | None = None,
                  strategy: str = "nee", heuristic: str = "power", rr_depth: int | None = None,
                  sampler: str = DEFAULT_SAMPLER,
                  tile_size: int = TILE_SIZE, spp_per_pass: int | None = None,
                  checkpoint: str | Path | None = None, resume: str | Path | None = None,
                  progress: Callable[[Film], None] | None = None,
                  on_pass: Callable[[Film], None] | None = None,
                  stop: Callable[[], bool] | None = None) -> RenderResult:
    """Render and return the image with its statistics (arguments as for ``render``).

    Args (beyond ``render``'s):
        executor: run the jobs on this ``concurrent.futures.Executor`` (a thread pool, a
            Dask client's executor, ...) instead of ptlab's own process pool.
        tile_size: tile edge in pixels (the image does not depend on it).
        spp_per_pass: samples per pixel in each pass (default ``SPP_PER_PASS``); part of the
            image's identity, since each pass's sums are added up on their own.
        checkpoint: save the film here after every pass (and when stopped).
        resume: continue the render saved in this checkpoint.
        progress: called with the film after every job.
        on_pass: called with the film whenever a pass over the whole image completes.
        stop: polled between jobs; when it returns True the render stops early and
            returns what it has (``complete`` is then False).
    """
    if isinstance(scene, str | Path):
        scene = load_scene(scene)
    width, height = resolution(scene, res)
    if max_depth is None:
        max_depth = scene.defaults.max_depth
    if max_depth is None:   # the integrator's (an unknown one is check_settings' to report)
        max_depth = INTEGRATORS[integrator].max_depth if integrator in INTEGRATORS else 0
    rr = check_settings(spp, seed, sampling, rr, max_depth, integrator, strategy, heuristic,
                        rr_depth, sampler)
    sampler_name, sampler = sampler, make_sampler(sampler, seed, spp)
    workers = check_workers(workers)
    tile_size = check_tile_size(tile_size)
    try:
        backend = resolve_backend(backend)
    except ValueError as error:
        raise PtlabError(str(error)) from None
    scene = scene.with_sampling(sampling)
    settings = PathSettings(rr=rr, max_depth=int(max_depth), strategy=strategy,
                            heuristic=heuristic, rr_min_depth=rr_depth)
    keep_freed_memory()

    tiles = make_tiles(width, height, tile_size)
    passes = pass_schedule(spp, spp_per_pass)
    spp_per_pass = passes[0]
    film = Film(width, height, tiles, passes)
    identity = dict(scene=scene_digest(scene), width=width, height=height, seed=seed,
                    backend=backend, sampling=sampling, rr=str(rr), max_depth=int(max_depth),
                    strategy=strategy, heuristic=heuristic, rr_depth=str(rr_depth),
                    integrator=integrator, sampler=sampler.identity, tile_size=tile_size,
                    spp_per_pass=spp_per_pass, spp=spp)
    if resume is not None:
        load_checkpoint(resume, film, identity)
    samples_at_start = film.samples

    start = time.perf_counter()
    setup = RenderSetup(scene=scene, backend=backend, width=width, height=height, seed=seed,
                        settings=settings, integrator=integrator, sampler=sampler)
    first_sample = np.concatenate([[0], np.cumsum(passes)])
    jobs = [Job(tile, k, n, int(first_sample[k])) for k, n in enumerate(passes) for tile in tiles
            if k >= film.passes_done[tile.index]]
    if executor is None:
        workers = min(workers, len(jobs))   # a pool for one job would only cost its start-up
    complete_passes = int(film.passes_done.min())
    for result in run_jobs(jobs, setup, max(workers, 1), executor, stop or (lambda: False)):
        film.add(result)
        if progress is not None:
            progress(film)
        if film.passes_done.min() > complete_passes:
            complete_passes = int(film.passes_done.min())
            if checkpoint is not None:
                save_checkpoint(checkpoint, film, identity)
            if on_pass is not None:
                on_pass(film)
    complete = film.complete
    if checkpoint is not None and not complete:
        save_checkpoint(checkpoint, film, identity)
    seconds = time.perf_counter() - start
    return RenderResult(
        image=film.image(), spp=film.spp, spp_max=film.spp_max, complete=complete,
        seconds=seconds, samples=film.samples - samples_at_start, rays=film.rays,
        query_seconds=film.query_seconds, sampler_seconds=film.sampler_seconds,
        settings=dict(scene=scene.name, spp=film.spp, seed=seed, backend=backend,
                      integrator=integrator, strategy=strategy, heuristic=heuristic,
                      sampler=sampler_name, sampling=sampling, rr=str(rr),
                      rr_depth=settings.roulette_starts,
                      max_depth=int(max_depth), width=width, height=height,
                      workers=workers if executor is None else "executor"))


def resolution(scene: Scene, res=None) -> tuple[int, int]:
    """(width, height) of a render of ``scene``: ``res`` if given (checked), else the scene
    file's ``[render] res``, else ``DEFAULT_RES``."""
    if res is None:
        res = scene.defaults.res or DEFAULT_RES
    return parse_resolution(res)


def pass_schedule(spp: int, spp_per_pass: int | None = None) -> list[int]:
    """Samples per pixel of each pass of a render (``SPP_PER_PASS`` by default)."""
    if spp_per_pass is None:
        spp_per_pass = SPP_PER_PASS
    elif not isinstance(spp_per_pass, int) or spp_per_pass < 1:
        raise PtlabError(f"spp per pass {spp_per_pass!r}: must be a positive integer")
    return pass_sizes(spp, min(spp, spp_per_pass))


def render(scene: Scene | str, spp: int = 16, res=None, seed: int = 0,
           workers: int | None = None, backend: str = "auto", integrator: str = "path",
           sampling: str = "cosine", rr: float | str = "throughput",
           max_depth: int | None = None, executor: Executor | None = None,
           strategy: str = "nee", heuristic: str = "power",
           rr_depth: int | None = None, sampler: str = DEFAULT_SAMPLER) -> np.ndarray:
    """Render a scene; return (H, W, 3) float32 linear RGB.

    Args:
        scene: a ``Scene``, a built-in scene name (``"cornell-box"``) or a scene file path.
        spp: samples (camera paths) per pixel.
        res: ``N`` for N x N, ``(width, height)`` or ``"WxH"``; None for the scene file's
            ``[render] res``, or 512 x 512.
        seed: the random seed; the same seed gives the same image, bit for bit, whatever
            ``workers`` or ``executor``.
        workers: processes rendering tiles at once; None for one per core, 1 for this
            process only.
        backend: ray queries by ``"embree"``, ``"numpy"`` or ``"auto"`` (embree if it imports).
        integrator: ``"path"``, ``"whitted"`` (Homework 5's ray tracer: mirrors, glass and
            direct light, no diffuse interreflection), or a debug view: ``"normals"``,
            ``"albedo"``, ``"depth"`` (``ptlab.integrators.debug``).
        sampling: diffuse sampling, ``"cosine"`` or ``"uniform"`` (the homework's).
        rr: Russian roulette survival probability (the homework's 0.8) or ``"throughput"``.
        max_depth: the most bounces per path (default: the scene file's ``[render]
            max_depth``, else 100; 5 for ``"whitted"``).
        strategy: direct light by light sampling (``"nee"``, the homework's), by BSDF
            sampling only (``"bsdf"``) or both with multiple importance sampling (``"mis"``).
        heuristic: MIS weights, ``"power"`` (default) or ``"balance"``.
        rr_depth: bounces before Russian roulette starts (default 0 with a fixed ``rr``,
            like the homework; 2 with ``"throughput"``, like pbrt-v4).
        sampler: where the random numbers come from (``ptlab.samplers``): ``"sobol"``
            (default), ``"stratified"`` or ``"independent"``.
        executor: run on this ``concurrent.futures.Executor`` instead (e.g. a Dask
            client's ``get_executor()``).
    """
    return render_result(scene, spp=spp, res=res, seed=seed, workers=workers, backend=backend,
                         integrator=integrator, sampling=sampling, rr=rr,
                         max_depth=max_depth, executor=executor, strategy=strategy,
                         heuristic=heuristic, rr_depth=rr_depth, sampler=sampler).image
