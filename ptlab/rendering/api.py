"""The ``ptlab.render`` API (re-exported by ``ptlab.rendering`` and ``ptlab``).

``render_result`` below cuts the image into tiles and the samples into passes, runs the jobs
where they were asked to run, and adds their results into the film. Along the way it reports
progress, saves a checkpoint after every pass, and stops early, keeping what is done, when
asked to. ``render`` is the same, returning only the image. Its jobs are of the size
``sizes`` sets (``TILE_SIZE``, ``SPP_PER_PASS``).
"""

from __future__ import annotations

import pickle
import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import ptlab.rendering.adaptive as adaptive
from ptlab.errors import PtlabError
from ptlab.image import Window
from ptlab.integrators.features import FEATURES
from ptlab.rendering.checkpoint import load_checkpoint, save_checkpoint, scene_digest
from ptlab.rendering.denoising import DenoisedFilm, check_denoised_size, denoise_film, warm_up_denoiser
from ptlab.rendering.film import Film
from ptlab.rendering.jobs import Job, RenderSetup, make_tiles, pass_sizes
from ptlab.rendering.memory import keep_freed_memory
from ptlab.rendering.options import DEFAULT_MAX_SPP, DEFAULT_RES, RenderOptions, resolution, takes_options
from ptlab.rendering.pieces import LIBRARY, Pieces
from ptlab.rendering.scheduler import interruptible, run_jobs
from ptlab.rendering.settings import check_flag, check_integer, check_workers
from ptlab.rendering.sizes import SPP_PER_PASS
from ptlab.samplers import Sampler, make_sampler
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
        counts: (H, W) int64 samples each pixel has (the same everywhere, but for a render
            stopped mid-pass, unless the render had a target error).
        relmse_estimate: the image's relMSE as its own samples estimate it
            (``ptlab.rendering.adaptive``), for a render to a target error; for a denoised
            render, the denoised image's (``ptlab.denoise.estimate``), or None where that
            cannot be trusted (``estimate_refused`` says why); else None.
        settings: what made the image, for its file's header: the options
            (``RenderOptions.record``) with the scene's name, the spp every pixel has, the
            depth at which Russian roulette started and the workers (and, denoised, with
            what, and how long it took).
        noisy: for a denoised render, the image before denoising (``image`` is the denoised
            one); else None.
        features: the denoiser's feature images, where the render gathered them (``denoise``,
            or ``features=True``): ``"albedo"``, ``"normal"`` and ``"direct"`` (the emission
            seen directly, kept out of the denoiser), each (H, W, 3) float32
            (``ptlab.integrators.features``); else None.
        estimate_refused: for a denoised render without ``relmse_estimate``, why its error
            could not be estimated honestly; else "".
        window: for a render of a window of the image (``crop``), where ``image`` sits in the
            whole image, for its file (``ptlab.image.write_image``); else None.
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
    counts: np.ndarray | None = None
    relmse_estimate: float | None = None
    settings: dict = field(default_factory=dict)
    noisy: np.ndarray | None = None
    features: dict[str, np.ndarray] | None = None
    estimate_refused: str = ""
    window: Window | None = None

    @property
    def denoised(self) -> bool:
        """Whether ``image`` is denoised (``noisy`` is then the image before)."""
        return self.noisy is not None

    @property
    def spp_mean(self) -> float:
        """Samples per pixel on average over the image."""
        return float(self.counts.mean()) if self.counts is not None and self.counts.size else float(self.spp)

    @property
    def target_reached(self) -> bool | None:
        """With a target error: whether the estimate fell to it; else None."""
        target = self.settings.get("target_error")
        if target is None:
            return None
        # (A denoised image whose estimate is refused may still be known to be below a bound.)
        known = (
            self.relmse_estimate if self.relmse_estimate is not None else self.settings.get("relmse_bound")
        )
        return known is not None and known <= target

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
@interruptible()  # (SIGINT stops it even where it was ignored when Python started)
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
    pieces: Pieces | None = None,
    features: bool = False,
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
        pieces: the functions the render is made of, if not the library's
            (``ptlab.rendering.pieces``); a render with worker processes needs them to be
            functions of a module that the workers can import.
        features: gather the denoiser's feature images (``RenderResult.features``) without
            denoising (``denoise=True`` gathers them anyway).
    """
    options = RenderOptions.of(args, options, keywords)
    gather = _gathers_features(options, features)
    if isinstance(scene, str | Path):
        scene = load_scene(scene)
    options, workers = _decided_for(scene, options)
    # (The film holds the window's pixels, a crop's or the whole image's.)
    x0, y0, width, height = options.window
    setup = render_setup(scene, options, pieces, features=gather, origin=(x0, y0))
    scene, sampler, settings = setup.scene, setup.sampler, setup.settings
    assert sampler is not None  # (render_setup gives one)
    keep_freed_memory()

    tiles = make_tiles(width, height, options.tile_size)
    # (A render to a noise target has only passes of its own, the first of spp everywhere.)
    adaptive_render = options.target_error is not None
    passes = [] if adaptive_render else pass_schedule(options.spp, options.spp_per_pass)
    film = Film(width, height, tiles, passes, halves=setup.halves, features=gather)
    record = options.record()
    identity = _identity(record, scene, sampler, gather)
    if resume is not None:
        load_checkpoint(resume, film, identity)
    samples_at_start = film.samples

    start = time.perf_counter()
    jobs = _jobs_left(film)
    pass_ended = _PassEnd(checkpoint, identity, command, on_pass)
    more = None
    if options.target_error is not None:
        more = _NoiseTarget(film, options, start, pass_ended)
    if executor is None:
        workers = _pool_size(workers, len(jobs) if more is None else None, setup.pieces)
    complete_passes = int(film.passes_done.min())
    report, bar = _progress_reports(progress, film, options.denoise)
    for result in run_jobs(jobs, setup, max(workers, 1), executor, stop or (lambda: False), more):
        film.add(result)
        if report is not None:
            report(film)
        if film.passes_done.min() > complete_passes:
            complete_passes = int(film.passes_done.min())
            pass_ended(film)
    if report is not None and more is not None:  # (the last pass's estimate, made after it)
        report(film)
    if bar is not None:
        bar.close()
    # (A render to a noise target is complete when it decided to end, not stopped before.)
    complete = film.complete and film.samples > 0 and (more is None or more.end != "")
    if film.spp_max == 0 and not complete:
        warnings.warn("the render stopped before any tile had a pass: its image is black", RuntimeWarning, 2)
    if not complete:
        pass_ended.save(film)
    denoised = _denoised(film, more, options.workers) if options.denoise else None
    seconds = time.perf_counter() - start
    return RenderResult(
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
        counts=film.counts,
        settings=dict(
            record,
            scene=scene.name,
            spp=film.spp,
            rr_depth=settings.rr_depth,
            workers=workers if executor is None else "executor",
            **_target_record(more),
            **_denoise_record(denoised, film),
        ),
        features=_feature_images(film),
        window=None if options.crop is None else Window(x0, y0, *options.size),
        **_images(film, denoised),
    )


def render_setup(
    scene: Scene,
    options: RenderOptions,
    pieces: Pieces | None = None,
    features: bool = False,
    origin: tuple[int, int] = (0, 0),
) -> RenderSetup:
    """What every job of a render of ``scene`` shares (options decided ``for_scene``): the
    scene with the options' diffuse sampling, the sampler, the path settings, the pieces
    (the library's unless given); each pixel's samples in two independent halves for a
    render to a target error or a denoised one (whose error the halves measure); the
    denoiser's feature images gathered if ``features``; ``origin``, the image's pixel at
    the film's top left (``RenderSetup.origin``: a crop's window; tiles of the whole image,
    as the inspector's, have (0, 0))."""
    width, height = options.size
    return RenderSetup(
        scene=scene.with_sampling(options.sampling),
        backend=options.backend,
        width=width,
        height=height,
        seed=options.seed,
        settings=options.path_settings(),
        integrator=options.integrator,
        sampler=make_sampler(options.sampler, options.seed, options.spp),
        halves=options.target_error is not None or options.denoise,
        pieces=pieces or LIBRARY,
        features=features,
        origin=origin,
    )


def _pool_size(workers: int, jobs: int | None, pieces: Pieces) -> int:
    """The worker processes of a render of ``jobs`` jobs (None: not known beforehand, as in
    a render to a noise target): no more than its jobs, as a pool for one job would only cost
    its start-up. ``PtlabError`` in one line, before any worker starts, if a pool is needed
    and ``pieces`` cannot be sent to it (a lambda, a function of a notebook's or of a
    closure: pickled by name, they are not found there)."""
    if jobs is not None:
        workers = min(workers, jobs)
    if workers <= 1:
        return workers
    try:
        pickle.dumps(pieces)
    except (pickle.PicklingError, AttributeError, TypeError) as error:
        raise PtlabError(
            f"the render's pieces cannot go to worker processes ({error}): render with "
            "workers=1, or give functions of a module the workers can import"
        ) from None
    return workers


def _target_record(noise_target: _NoiseTarget | None) -> dict:
    """What a render to a target error adds to its settings: its pixels' most samples, and
    why it ended (``_NoiseTarget.end``)."""
    if noise_target is None:
        return {}
    record: dict[str, Any] = {"max_spp": noise_target.most, "target_end": noise_target.end}
    if noise_target.decided_by:  # (a denoised render: its estimate, its bound, or the noisy one's)
        record["target_decided_by"] = noise_target.decided_by
    return record


def _decided_for(scene: Scene, options: RenderOptions) -> tuple[RenderOptions, int]:
    """The options decided for ``scene`` (``RenderOptions.for_scene``), checked against it,
    and the workers (checked)."""
    options = options.for_scene(scene)
    if options.denoise:
        check_denoised_size(*options.window[2:])
    return options, check_workers(options.workers)


def _identity(record: dict, scene: Scene, sampler: Sampler, features: bool) -> dict:
    """What a checkpoint must match to be resumed by a render: its options but the workers
    and time limit (any number of workers may resume a render), the scene's fingerprint, and
    the sampler's identity (what of it the image depends on: its name, for some the spp)."""
    identity = dict(record, scene=scene_digest(scene), sampler=sampler.identity)
    del identity["workers"], identity["time_limit"]
    if features:  # (a checkpoint with feature images resumes only a render that gathers them)
        identity["features"] = True
    return identity


def _gathers_features(options: RenderOptions, features: bool) -> bool:
    """Whether a render gathers the denoiser's feature images: if it denoises, or is asked
    to. Checked before the scene is loaded: a missing extra fails in one line, at once; the
    denoiser is then made ready while the render goes on (``warm_up_denoiser``)."""
    if options.denoise:
        from ptlab.denoise.oidn import require_oidn

        require_oidn()
        warm_up_denoiser(options.workers)
    gather = options.denoise or check_flag("features", features)
    if gather and options.integrator != "path":
        raise PtlabError(f"features: only the path integrator gathers them, not {options.integrator!r}")
    return gather


def _denoised(film: Film, noise_target: _NoiseTarget | None, threads: int | None) -> DenoisedFilm | None:
    """The film denoised after the last pass (by at most ``threads`` threads, the render's
    workers: None, as many as the denoiser finds worth it): by the last pass of a render to
    a target error, if it denoised it; not a picture with pixels that have no sample yet
    (None)."""
    if film.spp == 0:
        return None
    if noise_target is not None and noise_target.denoised is not None:
        return noise_target.denoised
    return denoise_film(film, threads=threads)


def _denoise_record(denoised: DenoisedFilm | None, film: Film) -> dict:
    """What a denoised render adds to its settings (its image's header): with what, in how
    long, and, if its error has no estimate, why, and the noisy image's estimate instead."""
    if denoised is None:
        return {}
    how = dict(denoised.settings)  # (the denoiser's own words: ``ptlab.denoise.Denoised``)
    record: dict[str, Any] = {
        "denoised": how.pop("denoiser", denoised.about),
        "denoised_images": how.pop("denoised", ""),
        **how,
        "denoise_seconds": round(denoised.seconds, 3),
    }
    if denoised.refused:
        record["relmse_estimate_refused"] = denoised.refused
        if denoised.error_bound is not None:
            record["relmse_bound"] = denoised.error_bound
        if (noisy := _estimate(film)) is not None:
            record["noisy_relmse_estimate"] = noisy
    return record


def _images(film: Film, denoised: DenoisedFilm | None) -> dict[str, Any]:
    """``RenderResult``'s image and its error estimate: the film's, or denoised, with the
    film's image kept as ``noisy``."""
    if denoised is None:
        return {"image": film.image(), "relmse_estimate": _estimate(film)}
    return {
        "image": denoised.image,
        "noisy": film.image(),
        "relmse_estimate": denoised.relmse_estimate,
        "estimate_refused": denoised.refused,
    }


def _feature_images(film: Film) -> dict[str, np.ndarray] | None:
    """``RenderResult.features``: the film's feature images, as float32."""
    if film.features is None:
        return None
    return {name: film.feature_image(name).astype(np.float32) for name in FEATURES}


def _estimate(film: Film) -> float | None:
    """The film's estimate of its image's relMSE: from its two independent halves, which only
    a render to a target error has (``RenderSetup.halves``)."""
    if not film.halves or film.spp < 2:
        return None
    variance = adaptive.variance_of_mean_from_halves(film.differences, film.counts)
    return adaptive.estimated_relmse(variance, film.sums, film.counts)


def _jobs_left(film: Film) -> list[Job]:
    """The jobs of the fixed passes that the film does not have yet (all of them but in a
    resumed render), or of the noise-target pass that a resumed render was stopped in."""
    if film.plan is not None:
        return plan_jobs(film)
    first_sample = np.concatenate([[0], np.cumsum(film.passes)])
    return [
        Job(tile, k, n, int(first_sample[k]))
        for k, n in enumerate(film.passes)
        for tile in film.tiles
        if k >= film.passes_done[tile.index]
    ]


@dataclass
class _PassEnd:
    """What a render does when a pass over the whole image is done: save the checkpoint,
    if it keeps one, and call ``on_pass``."""

    checkpoint: str | Path | None
    identity: dict
    command: dict | None
    on_pass: Callable[[Film], None] | None

    def __call__(self, film: Film) -> None:
        self.save(film)
        if self.on_pass is not None:
            self.on_pass(film)

    def save(self, film: Film) -> None:
        if self.checkpoint is not None:
            save_checkpoint(self.checkpoint, film, self.identity, self.command)


class _NoiseTarget:
    """A render to a target error: ``run_jobs``' ``more``, called each time a pass over the
    image has been added whole. It estimates the image's relMSE from the film and, until the
    estimate is at the target (or no pixel may have more samples, or the time is up), plans
    the next pass (``ptlab.rendering.adaptive``) and returns its jobs.

    A denoised render's target is the *denoised* image's error: each pass's film is denoised
    and that image's error estimated (``ptlab.rendering.denoising``). Where that estimate is
    refused, and no bound of it is known, the noisy image's own estimate decides."""

    def __init__(self, film: Film, options: RenderOptions, start: float, pass_ended: _PassEnd):
        self.film, self.options, self.start, self.pass_ended = film, options, start, pass_ended
        self.samples_at_start = film.samples
        self.most = options.max_spp or DEFAULT_MAX_SPP
        #: Why the render ended: "target", "max spp" or "time limit" (what the last call saw).
        self.end = ""
        #: The last pass's film denoised (a denoised render), which is the final image if
        #: the render ends there, and what decided whether it was done (``_denoised_decision``).
        self.denoised: DenoisedFilm | None = None
        self.decided_by = ""

    def __call__(self) -> list[Job]:
        film, target = self.film, self.options.target_error
        assert target is not None
        if film.samples == 0 and film.plan is None:  # (the first pass: spp everywhere)
            film.start_plan(np.full(film.counts.shape, self.options.spp, dtype=np.int64))
            return plan_jobs(film)
        ended = film.plan is not None
        film.end_plan()
        variance = adaptive.variance_of_mean_from_halves(film.differences, film.counts)
        estimate, aim = adaptive.estimated_relmse(variance, film.sums, film.counts), target
        if self.options.denoise:
            estimate, aim = self._denoised_decision(film, estimate, target)
        film.estimate = estimate
        if ended:
            self.pass_ended(film)
        if estimate <= target:
            self.end = "target"
            return []
        weights = adaptive.allocation_weights(variance, film.sums, film.counts)
        # (No pixel more than GROWTH times its samples in one pass: one pass's estimate of a
        # pixel is not trusted with more.)
        most = np.minimum(self.most, adaptive.GROWTH * film.counts)
        budget = adaptive.pass_budget(weights, film.counts, aim, most)
        self.end = "max spp"
        if self.options.time_limit is not None:  # (at the speed so far)
            elapsed = time.perf_counter() - self.start
            rate = (film.samples - self.samples_at_start) / max(elapsed, 1e-9)
            if rate * (self.options.time_limit - elapsed) < budget:
                budget, self.end = int(rate * (self.options.time_limit - elapsed)), "time limit"
        if budget < film.counts.size // 8:  # (less than an eighth of a sample per pixel: done)
            return []
        # (In pairs, one sample for each half: ``RenderSetup.halves``.)
        pairs = adaptive.allocate(weights, film.counts // 2, budget // 2, most // 2)
        film.start_plan(2 * pairs)
        return plan_jobs(film)

    def _denoised_decision(self, film: Film, noisy: float, target: float) -> tuple[float, float]:
        """A denoised render's pass: the film denoised, and what decides whether it is done:
        the denoised image's estimated error, or where that is refused for its spread or for
        the truth's brightness, what the error is below (``error_bound``); else ``noisy``,
        the noisy image's estimate. Returns that, and the error ``pass_budget`` aims the
        estimate's value at, so that the decision's value reaches ``target``.

        The next pass's samples go by the noisy image's weights (``allocation_weights``), not
        by the denoised error's map: that map is a product of the two halves' residuals,
        which the denoiser makes alike over many pixels, so a pixel whose pooled map is high
        is one whose own product came out high; giving it more samples dilutes exactly those,
        and the next estimate is biased low (on the Cornell box at 32 spp: -0.005 for a true
        0.0014). The noisy variance is pooled over 49 pixels whose noises are independent: a
        pixel's own product hardly moves its weight (there: 0.00106 for a true 0.0012)."""
        self.denoised = denoised = denoise_film(film, threads=self.options.workers)
        deciding = denoised.relmse_estimate if denoised.relmse_estimate is not None else denoised.error_bound
        if deciding is None or denoised.error_value is None:
            self.decided_by = "the noisy image's estimate"
            return noisy, target
        self.decided_by = "the estimate" if denoised.relmse_estimate is not None else "the bound"
        # (Both are positive there: a trusted estimate and a bound are.)
        return deciding, target * denoised.error_value / deciding


def plan_jobs(film: Film) -> list[Job]:
    """The jobs of the noise-target pass under way (``Film.plan``) that are not done: one per
    plan tile (``Film.plan_tiles``) that has samples in it, each pixel going on from the
    samples it has."""
    assert film.plan is not None
    jobs = []
    for tile in film.plan_tiles:
        counts = film.plan[tile.y0 : tile.y1, tile.x0 : tile.x1]
        if not film.plan_done[tile.index] and counts.any():
            firsts = film.counts[tile.y0 : tile.y1, tile.x0 : tile.x1].copy()
            index = len(film.passes) + film.adaptive_passes
            jobs.append(Job(tile, index, int(counts.max()), 0, counts.copy(), firsts))
    return jobs


def _progress_reports(progress, film: Film, denoise: bool) -> tuple[Callable[[Film], None] | None, Any]:
    """What to call after each job: ``progress`` itself, or for True a new progress bar
    (``ptlab.rendering.progress``; in a notebook it shows each pass's image, denoised for a
    render that denoises), returned again as the second value, to be closed."""
    if progress is not True:
        return progress or None, None
    from ptlab.rendering.progress import ProgressBar

    height, width = film.sums.shape[:2]
    bar = ProgressBar(
        width * height * sum(film.passes), len(film.passes), initial=film.samples, denoise=denoise
    )
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
    pieces: Pieces | None = None,
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
        pieces: the functions the render is made of, if not the library's
            (``ptlab.rendering.pieces``).
    """
    options = RenderOptions.of(args, options, keywords)
    result = render_result(
        scene, options=options, executor=executor, progress=progress or None, pieces=pieces
    )
    if result.nonfinite:  # (a bug in a material or an integrator; ``render_result`` counts them)
        warnings.warn(result.nonfinite_message(), RuntimeWarning, stacklevel=2)
    return result.image
