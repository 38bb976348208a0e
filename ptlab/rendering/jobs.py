"""A render split into jobs: one tile of the image in one pass of samples.

The image is cut into square tiles, and the samples into passes (so that a long render
can show and save what it has after every pass). One job traces all the camera paths of
one tile in one pass, as one wavefront batch; any process can run it, since a job carries
everything it needs to reproduce its result exactly:

* its random numbers are the render's sampler's (``ptlab.samplers``), a pure function of
  (seed, pixel, sample index, dimension): no generator is shared between jobs, and a pixel
  gets the same numbers whatever tile or pass it is rendered in, or window of the image (a
  crop: ``RenderSetup.origin``);
* its result is the sum of its paths' radiance per pixel (float64), which the main
  process adds into the film in pass order, tile by tile.

So the image is bit-identical whatever the number of workers, the order in which jobs
finish, or the tile size (passes have a fixed number of samples, ``SPP_PER_PASS``, so every
pixel's sums are added up in the same order). A worker process builds the ray-query
structure once per render, not per job.
"""

from __future__ import annotations

import threading
import uuid
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field, replace
from typing import cast

import numpy as np

from ptlab.accel import Accelerator, make_accelerator
from ptlab.accel.timed import TimedAccelerator
from ptlab.integrators import INTEGRATORS, Integrator
from ptlab.integrators.features import FeatureBuffers, gathering_features
from ptlab.integrators.path import BATCH_PATHS, PathSettings
from ptlab.integrators.wavefront import NonFinite, Paths, counting_nonfinite
from ptlab.rendering.pieces import LIBRARY, Pieces
from ptlab.samplers import DEFAULT_SAMPLER, BounceUniforms, Sampler, TimedSampler, make_sampler
from ptlab.scene import Scene


@dataclass(frozen=True)
class Tile:
    """A rectangle of pixels: columns x0..x1-1, rows y0..y1-1."""

    index: int
    x0: int
    y0: int
    x1: int
    y1: int

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) in pixels."""
        return self.y1 - self.y0, self.x1 - self.x0


def make_tiles(width: int, height: int, size: int) -> list[Tile]:
    """The image cut into ``size`` x ``size`` tiles (smaller at the right and bottom)."""
    tiles: list[Tile] = []
    for y0 in range(0, height, size):
        for x0 in range(0, width, size):
            tiles.append(Tile(len(tiles), x0, y0, min(x0 + size, width), min(y0 + size, height)))
    return tiles


def pass_sizes(spp: int, spp_per_pass: int) -> list[int]:
    """Samples per pixel of each pass: full passes, then what is left."""
    return [min(spp_per_pass, spp - done) for done in range(0, spp, spp_per_pass)]


@dataclass(frozen=True)
class Job:
    """One tile in one pass: ``spp`` samples for each of the tile's pixels, the samples
    ``first_sample``, ..., ``first_sample + spp - 1`` of each.

    A pass of a render to a noise target (``ptlab.rendering.adaptive``) gives each pixel its
    own number of samples: ``counts`` (tile height, tile width), continuing from each pixel's
    own ``firsts`` (the samples it already has), and ``spp`` is then the most of them. (Two
    jobs of one render differ by tile or pass, which is what they are compared by.)
    """

    tile: Tile
    pass_index: int
    spp: int
    first_sample: int = 0
    counts: np.ndarray | None = field(default=None, compare=False, repr=False)
    firsts: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def samples(self) -> int:
        """Camera samples (paths) of the job."""
        if self.counts is not None:
            return int(self.counts.sum())
        return self.tile.shape[0] * self.tile.shape[1] * self.spp


@dataclass
class JobResult:
    """What a job sends back: per-pixel radiance sums (and the difference of the two halves'
    sums, for the noise estimate: ``RenderSetup.halves``) and counts of its work."""

    job: Job
    sums: np.ndarray  # (tile height, tile width, 3) float64
    differences: np.ndarray  # (tile height, tile width, 3) float64: even samples' sum - odd's
    rays: int
    query_seconds: float
    sampler_seconds: float = 0.0
    nonfinite: int = 0  # samples NaN or infinite, left out of the sums (``add_to_film``)
    #: The first of them, (x, y, depth): the least depth, then the first row (sample-major).
    first_nonfinite: tuple[int, int, int] | None = None
    #: Where the setup gathers ``features``: their sums, (tile height, tile width, 9) float64,
    #: ``FEATURES``' three images side by side, and the even samples' sums less the odd ones'.
    features: np.ndarray | None = None
    feature_differences: np.ndarray | None = None


@dataclass(frozen=True)
class RenderSetup:
    """Everything that is the same for all jobs of one render.

    ``sampler`` gives every random number (by default the ``DEFAULT_SAMPLER`` with this
    setup's seed). ``token`` names the render, so that a worker process keeps one ray-query
    structure per render however many of its jobs it runs. ``pieces`` are the functions
    the render is made of (``ptlab.rendering.pieces``; the path loop's steps go into
    ``settings``, where each step finds them).
    """

    scene: Scene
    backend: str
    width: int
    height: int
    seed: int
    settings: PathSettings
    integrator: str = "path"
    sampler: Sampler | None = None
    token: str = field(default_factory=lambda: uuid.uuid4().hex)
    #: Draw each pixel's even and odd samples as two independent sequences (a render to a
    #: noise target measures its error by how the two halves differ: ``ptlab.rendering.adaptive``).
    halves: bool = False
    pieces: Pieces = LIBRARY
    #: Gather the denoiser's feature images (``ptlab.integrators.features``; the path tracer).
    features: bool = False
    #: (x, y) of the film's top-left pixel in the image, for a render of a window of it
    #: (``RenderOptions.crop``): tiles are in the film's pixels, while a camera ray and its
    #: sampler keys are the whole image's (``width`` x ``height``), so a window's pixels are
    #: those of the whole image's render, bit for bit.
    origin: tuple[int, int] = (0, 0)

    def __post_init__(self):
        if self.settings.pieces != self.pieces.path:
            object.__setattr__(self, "settings", replace(self.settings, pieces=self.pieces.path))
        if self.sampler is None:
            object.__setattr__(self, "sampler", make_sampler(DEFAULT_SAMPLER, self.seed))
        elif self.sampler.seed != self.seed:
            raise ValueError(f"the sampler's seed {self.sampler.seed} is not the setup's {self.seed}")


class CameraSamples:
    """The camera samples of a list of jobs, one after the other, handed out as camera paths.

    Sample k of the list is row k of the jobs' film, which has a row per path: a path adds
    its radiance to its own row, and ``sums`` adds up each pixel's paths afterwards, in
    sample order. A pixel's sum is then the same however its paths were batched (with which
    other jobs, in which batch, at which bounce), which path regeneration needs: a batch
    holds whichever paths are left, from one job or the next.

    Within a job the samples are in sample-major order: the tile's pixel k is row k, k + n,
    k + 2 n, ... (n pixels in the tile). A job with its own count per pixel
    (``Job.counts``) is in the same order with the pixels that have no more samples left out:
    first every pixel's first sample, then the second of those that have two, and so on
    (the pixels of each ordered from the most samples to the fewest: ``_order``).
    """

    def __init__(self, setup: RenderSetup, jobs: list[Job], sampler: TimedSampler):
        self.setup, self.jobs, self.sampler = setup, jobs, sampler
        #: Row of each job's first sample, and the total, as in ``np.cumsum``.
        self.starts = np.concatenate([[0], np.cumsum([job.samples for job in jobs])]).astype(np.intp)
        self.handed_out = 0
        self._orders: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}

    @property
    def count(self) -> int:
        """How many samples (film rows) the jobs have in all."""
        return int(self.starts[-1])

    def more(self, count: int) -> Paths | None:
        """The next ``count`` camera paths (fewer at the end), or None when none is left."""
        first = self.handed_out
        last = min(first + count, self.count)
        if first == last:
            return None
        self.handed_out = last
        return self.paths(first, last)

    def paths(self, first: int, last: int) -> Paths:
        """The camera paths of film rows ``first``, ..., ``last`` - 1."""
        pixel_x, pixel_y, index = [np.zeros(0, np.intp)], [np.zeros(0, np.intp)], [np.zeros(0, np.intp)]
        for j, job in enumerate(self.jobs):  # the part of the rows in each job
            start, stop = (
                max(first, self.starts[j]) - self.starts[j],
                min(last, self.starts[j + 1]) - self.starts[j],
            )
            if start >= stop:
                continue
            height, width = job.tile.shape
            n_pixels = width * height
            if job.counts is not None:
                in_tile, sample_index, _, _ = self._order(j)
                in_tile, sample_index = in_tile[start:stop], sample_index[start:stop]
                pixel_x.append(job.tile.x0 + in_tile % width)
                pixel_y.append(job.tile.y0 + in_tile // width)
                index.append(sample_index)
                continue
            # Whole samples of the tile's pixels (np.tile and np.repeat: integer division is
            # slow), cut to the rows asked for.
            first_sample, last_sample = start // n_pixels, (stop - 1) // n_pixels + 1
            samples = last_sample - first_sample
            cut = slice(start - first_sample * n_pixels, stop - first_sample * n_pixels)
            in_tile = np.arange(n_pixels)
            pixel_x.append(np.tile(job.tile.x0 + in_tile % width, samples)[cut])
            pixel_y.append(np.tile(job.tile.y0 + in_tile // width, samples)[cut])
            index.append(np.repeat(np.arange(first_sample, last_sample) + job.first_sample, n_pixels)[cut])
        setup = self.setup
        # (The image's pixels: a window's film starts at its ``origin``.)
        xs, ys = np.concatenate(pixel_x) + setup.origin[0], np.concatenate(pixel_y) + setup.origin[1]
        pixel, index_in_pixel = ys * setup.width + xs, np.concatenate(index)
        if setup.halves:
            # Odd samples are the samples of a pixel that does not exist (its number past the
            # image's), so their sequence is scrambled on its own, independent of the even ones'.
            odd = index_in_pixel & 1
            pixel, index_in_pixel = pixel + odd * (setup.width * setup.height), index_in_pixel >> 1
        sample = self.sampler.keys(pixel, index_in_pixel)
        jitter = self.sampler.get(sample, BounceUniforms.PIXEL, 2)
        origins, dirs = setup.pieces.generate_rays(
            setup.scene.camera, setup.width, setup.height, xs, ys, jitter
        )
        return Paths.camera(origins, dirs, np.arange(first, last), sample)

    def _order(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """For job ``j`` with a count per pixel, made once: each row's pixel in the tile and
        sample index (the class docstring's order); the tile's pixels from the most samples
        to the fewest (ties in pixel order), and how many of them have a k-th sample, for
        each k. A k-th sample's pixels are then the first few of that order, and within a
        k they come in that order: ``sums`` adds each k's samples as one slice."""
        if j not in self._orders:
            job = self.jobs[j]
            assert job.counts is not None
            assert job.firsts is not None
            counts = job.counts.reshape(-1)
            by_count = np.argsort(-counts, kind="stable")
            having = np.count_nonzero(counts[None, :] > np.arange(job.spp)[:, None], axis=1)
            in_tile = np.concatenate([by_count[:n] for n in having])
            k = np.repeat(np.arange(job.spp), having)
            self._orders[j] = (in_tile, job.firsts.reshape(-1)[in_tile] + k, by_count, having)
        return self._orders[j]

    def sums(self, film: np.ndarray, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Job ``j``'s per-pixel radiance sums, and the sums of its even samples less those of
        its odd ones (where ``RenderSetup.halves``; else 0), each (tile height, tile width,
        3), from the per-path ``film``. A pixel's sums are made in an order of its own
        samples that no batching changes: in sample order; with a count per pixel, the
        even samples in order plus the odd ones in order."""
        job = self.jobs[j]
        n_pixels = job.tile.shape[0] * job.tile.shape[1]
        rows = film[self.starts[j] : self.starts[j + 1]]
        if job.counts is not None:
            return self._plan_sums(j, rows, n_pixels)
        channels = film.shape[1]  # (3 for radiance; the feature images have more)
        total, differences = np.zeros((n_pixels, channels)), np.zeros((n_pixels, channels))
        for k in range(job.spp):
            block = rows[k * n_pixels : (k + 1) * n_pixels]
            total += block
            if self.setup.halves:
                differences += -block if (job.first_sample + k) & 1 else block
        return total.reshape(*job.tile.shape, channels), differences.reshape(*job.tile.shape, channels)

    def _plan_sums(self, j: int, rows: np.ndarray, n_pixels: int) -> tuple[np.ndarray, np.ndarray]:
        """``sums`` for a job with a count per pixel: a slice of the pixels (``_order``) per k."""
        job = self.jobs[j]
        _, _, by_count, having = self._order(j)
        # (A pixel's first sample here is even, as every count in such a render is: its
        # k-th sample here is even when k is.)
        assert job.firsts is not None
        assert not np.any(job.firsts & 1)
        channels = rows.shape[1]
        halves = np.zeros((2, n_pixels, channels))
        start = 0
        for k, size in enumerate(having):
            halves[k & 1, :size] += rows[start : start + size]
            start += size
        total, differences = np.empty((n_pixels, channels)), np.empty((n_pixels, channels))
        total[by_count] = halves[0] + halves[1]
        differences[by_count] = halves[0] - halves[1]
        return total.reshape(*job.tile.shape, channels), differences.reshape(*job.tile.shape, channels)

    def job_of(self, rows: np.ndarray) -> np.ndarray:
        """The job (its place in the list) of each film row ``rows``."""
        return np.searchsorted(self.starts, rows, side="right") - 1


def run_job(setup: RenderSetup, job: Job, accel: Accelerator) -> JobResult:
    """Trace one job's camera paths and return their per-pixel radiance sums."""
    return run_job_group(setup, [job], accel)[0]


def run_job_group(setup: RenderSetup, jobs: list[Job], accel: Accelerator) -> list[JobResult]:
    """Trace the camera paths of several jobs in one stream of batches (the path tracer keeps
    its batch full from the next job's samples as paths end: ``trace_paths``'s ``more``) and
    return each job's per-pixel radiance sums.

    The sums are the same, bit for bit, as each job's alone: a path's random numbers are a
    function of its pixel and sample, and its radiance is added up on its own (``CameraSamples``).
    """
    assert setup.sampler is not None  # (``RenderSetup.__post_init__`` makes one)
    # (A TimedSampler is a Sampler by what it does, keys and get, not by class.)
    sampler = TimedSampler(setup.sampler)
    camera = CameraSamples(setup, jobs, sampler)
    film = np.zeros((camera.count, 3), order="F")
    timed = TimedAccelerator(accel)
    integrator = integrator_of(setup)
    with counting_nonfinite() as nonfinite, _features_of(setup, camera.count) as buffers:
        if integrator.refills:
            # An empty batch, which the loop fills from the jobs' samples (``more``).
            empty = camera.paths(0, 0)
            rays = integrator.trace(
                film, setup.scene, timed, empty, cast(Sampler, sampler), setup.settings, camera.more
            )
        else:  # (Whitted, a debug view, a path loop given as a piece: a job at a time)
            rays = 0
            for j in range(len(jobs)):
                paths = camera.paths(camera.starts[j], camera.starts[j + 1])
                rays += integrator.trace(
                    film, setup.scene, timed, paths, cast(Sampler, sampler), setup.settings
                )
    sums = [camera.sums(film, j) for j in range(len(jobs))]
    feature_rows = buffers.values if buffers is not None else None
    return [
        JobResult(
            job=job,
            sums=sums[j][0],
            differences=sums[j][1],
            # The work of the whole stream, counted with its first job (the film adds it up).
            rays=rays if j == 0 else 0,
            query_seconds=timed.seconds if j == 0 else 0.0,
            sampler_seconds=sampler.seconds if j == 0 else 0.0,
            **_nonfinite_in(camera, nonfinite, j),
            **_features_in(camera, feature_rows, j),
        )
        for j, job in enumerate(jobs)
    ]


def _features_of(setup: RenderSetup, rows: int) -> AbstractContextManager[FeatureBuffers | None]:
    """Gathering the feature images of ``rows`` film rows, if the setup asks for them."""
    return gathering_features(rows) if setup.features else nullcontext()


def _features_in(camera: CameraSamples, feature_rows: np.ndarray | None, j: int) -> dict:
    """``JobResult``'s ``features`` and ``feature_differences`` for job ``j``."""
    if feature_rows is None:
        return {}
    sums, differences = camera.sums(feature_rows, j)
    return {"features": sums, "feature_differences": differences}


def integrator_of(setup: RenderSetup) -> Integrator:
    """The integrator a render runs: the registry's of its name, but for a path loop given
    as one of the render's pieces (``Pieces.trace_paths``)."""
    integrator = INTEGRATORS[setup.integrator]
    if setup.integrator == "path" and setup.pieces.trace_paths is not None:
        return Integrator(setup.pieces.trace_paths, max_depth=integrator.max_depth)
    return integrator


def _nonfinite_in(camera: CameraSamples, nonfinite: NonFinite, j: int) -> dict:
    """``JobResult``'s ``nonfinite`` and ``first_nonfinite`` for job ``j``: which of the samples
    left out (``NonFinite``) were its own, and the first of them."""
    if not nonfinite.count:
        return {}
    rows, depths = np.concatenate(nonfinite.rows), np.concatenate(nonfinite.depths)
    mine = camera.job_of(rows) == j
    if not mine.any():
        return {}
    rows, depths = rows[mine], depths[mine]
    first = np.lexsort((rows, depths))[0]
    job = camera.jobs[j]
    height, width = job.tile.shape
    y, x = divmod(int(rows[first] - camera.starts[j]) % (width * height), width)
    x0, y0 = job.tile.x0 + camera.setup.origin[0], job.tile.y0 + camera.setup.origin[1]  # (the image's pixel)
    return {"nonfinite": len(rows), "first_nonfinite": (x0 + x, y0 + y, int(depths[first]))}


#: The most samples a group of jobs has (``job_groups``): 4 jobs of 128 x 128 pixels and 16
#: spp, about a second of one core's work, and 24 MB of per-path film.
MAX_GROUP_SAMPLES = 2**20


def job_groups(jobs: list[Job], workers: int) -> list[list[Job]]:
    """The jobs, in order, cut into groups that a worker runs as one (``run_job_group``).

    Each group's batches end once, in a tail of bounces with few paths left, each bounce
    paying NumPy's fixed costs: fewer, larger groups waste less. But the last groups must be
    small, or one worker would still be busy when the others have nothing left. So the groups
    shrink as the render goes on ("guided self-scheduling", Polychronopoulos and Kuck 1987):
    each takes about its share of what is left, 1 / (2 workers), and at most
    ``MAX_GROUP_SAMPLES`` samples (so that progress is shown, and a stop heard, every second
    or so), but at least a batch of paths (``BATCH_PATHS``) if each worker has that much: a
    smaller group would be all tail (a render to a noise target has passes of a few batches).
    One worker has no one to wait for: its groups are all of the largest size. A group holds
    one pass: a pass is what the film shows, saves and is stopped after.
    """
    sizes = [job.samples for job in jobs]
    left = sum(sizes)
    # (No group smaller than a batch of paths, while each worker has that much to do: a
    # smaller one would be all tail.)
    least = min(BATCH_PATHS, left / workers)
    groups: list[list[Job]] = []
    group: list[Job] = []
    taken = 0
    for job, size in zip(jobs, sizes, strict=True):
        share = max(left / (2 * workers), least) if workers > 1 else left
        next_pass = bool(group) and job.pass_index != group[-1].pass_index
        if group and (next_pass or taken + size > min(MAX_GROUP_SAMPLES, share)):
            groups.append(group)
            left -= taken
            group, taken = [], 0
        group.append(job)
        taken += size
    if group:
        groups.append(group)
    return groups


# What a worker process keeps between jobs: the setup and accelerator of recent renders.
_worker_renders: dict[str, tuple[RenderSetup, Accelerator]] = {}
_worker_lock = threading.Lock()


def install_setup(setup: RenderSetup) -> None:
    """Keep ``setup`` in this process, with its accelerator built once."""
    with _worker_lock:
        if setup.token not in _worker_renders:
            _worker_renders.clear()  # one render at a time: free the last one
            accel = make_accelerator(setup.scene.triangles, setup.backend, setup.pieces.bvh)
            _worker_renders[setup.token] = (setup, accel)


def run_job_group_in_worker(setup: RenderSetup | str, jobs: list[Job]) -> list[JobResult]:
    """``run_job_group`` in a worker: ``setup`` is the setup itself, or the token of one that
    was installed in this process beforehand (the process pool's initializer does that,
    so jobs need not carry the scene)."""
    if not isinstance(setup, str):
        install_setup(setup)
        setup = setup.token
    installed, accel = _worker_renders[setup]
    return run_job_group(installed, jobs, accel)
