"""The film: per-pixel sums of radiance in float64 (and, for the noise estimate, the even
samples' sum less the odd ones'), each pixel's count of samples, and how many passes each
tile has.

Jobs finish in any order, but the film adds each tile's passes in pass order (a result
that arrives early waits in ``pending``), so the float64 sums, and so the image, are the
same bit for bit whatever the number of workers. Tiles are disjoint, so the order *between*
tiles does not matter.

A render to a noise target (``ptlab.rendering.adaptive``) has passes of its own instead: each
gives every pixel its own number of samples (``plan``), in jobs of ``PLAN_TILE_SIZE`` tiles
(``plan_tiles``). Such a pass begins only once the one before has been added whole, and its
jobs have disjoint pixels, so it too is added in the same order whatever the workers.
"""

from __future__ import annotations

import numpy as np

from ptlab.integrators.features import FEATURES
from ptlab.rendering.jobs import JobResult, Tile, make_tiles

#: Edge of the tiles a noise-target pass is cut into (``Film.plan_tiles``): small enough that
#: a small image still makes a job for every worker, and the pixels' samples are unequal anyway.
PLAN_TILE_SIZE = 32


class Film:
    """Accumulated radiance of a render in progress.

    Attributes:
        sums: (H, W, 3) float64 radiance summed over every sample taken so far.
        halves: whether each pixel's even and odd samples are independent halves
            (``RenderSetup.halves``), as in a render to a target error.
        differences: (H, W, 3) float64 the sum of the even samples less the sum of the odd
            ones, where ``halves`` (for the noise estimate, ``ptlab.rendering.adaptive``).
        counts: (H, W) int64 samples taken so far per pixel.
        passes: samples per pixel of each pass of the render (``ptlab.rendering.pass_schedule``).
        passes_done: (tiles,) passes added for each tile.
        plan: (H, W) the samples per pixel of the noise-target pass under way, or None.
        plan_tiles: the tiles of a noise-target pass's jobs.
        plan_done: (plan tiles,) which of them have that pass's samples.
        adaptive_passes: noise-target passes added whole.
        estimate: the last estimate of the image's relMSE (None before a noise-target
            render's first estimate).
        rays, query_seconds, sampler_seconds: work done so far (rays traced, seconds inside
            ray queries and inside the sampler).
        nonfinite: samples that were NaN or infinite and were left out of ``sums``
            (``ptlab.integrators.wavefront.add_to_film``).
        first_nonfinite: (x, y, depth) of the first of them, by pass and tile (None if none);
            x, y are the image's pixel (a window's film starts elsewhere: ``RenderSetup.origin``).
        features: (H, W, 9) float64 sums of the denoiser's feature images
            (``ptlab.integrators.features``: direct, albedo, normal), or None where the render
            gathers none; ``feature_differences`` the even samples' sums less the odd ones'.
    """

    def __init__(
        self,
        width: int,
        height: int,
        tiles: list[Tile],
        passes: list[int],
        halves: bool = False,
        features: bool = False,
    ):
        self.tiles = tiles
        self.passes = list(passes)
        self.sums = np.zeros((height, width, 3))
        self.halves = halves
        self.differences = np.zeros((height, width, 3))
        self.counts = np.zeros((height, width), dtype=np.int64)
        self.plan: np.ndarray | None = None
        self.plan_total = 0  # (samples once the plan is done)
        self.plan_tiles = make_tiles(width, height, PLAN_TILE_SIZE)
        self.plan_done = np.zeros(len(self.plan_tiles), dtype=bool)
        self.adaptive_passes = 0
        self.estimate: float | None = None
        self.passes_done = np.zeros(len(tiles), dtype=np.int64)
        self.rays = 0
        self.query_seconds = 0.0
        self.sampler_seconds = 0.0
        self.nonfinite = 0
        self.first_nonfinite: tuple[int, int, int] | None = None
        self._first_nonfinite_job = (np.inf, np.inf)
        self.pending: dict[tuple[int, int], JobResult] = {}
        self.features = np.zeros((height, width, 3 * len(FEATURES))) if features else None
        self.feature_differences = np.zeros_like(self.features) if features else None

    def add(self, result: JobResult) -> None:
        """Add a job's sums once every earlier pass of its tile has been added."""
        if result.job.counts is not None:  # (a noise-target pass: the one under way)
            self._add_sums(result)
            self.plan_done[result.job.tile.index] = True
            return
        self.pending[result.job.tile.index, result.job.pass_index] = result
        index = result.job.tile.index
        while (index, int(self.passes_done[index])) in self.pending:
            self._add_sums(self.pending.pop((index, int(self.passes_done[index]))))
            self.passes_done[index] += 1

    def _add_sums(self, ready: JobResult) -> None:
        tile = ready.job.tile
        rows, columns = slice(tile.y0, tile.y1), slice(tile.x0, tile.x1)
        self.sums[rows, columns] += ready.sums
        self.differences[rows, columns] += ready.differences
        if self.features is not None and self.feature_differences is not None:
            if ready.features is None or ready.feature_differences is None:
                raise RuntimeError("a job of a render that gathers features came back without them")
            self.features[rows, columns] += ready.features
            self.feature_differences[rows, columns] += ready.feature_differences
        self.counts[rows, columns] += ready.job.spp if ready.job.counts is None else ready.job.counts
        self.rays += ready.rays
        self.query_seconds += ready.query_seconds
        self.sampler_seconds += ready.sampler_seconds
        self.nonfinite += ready.nonfinite
        job = (ready.job.pass_index, tile.index)
        if ready.first_nonfinite is not None and job < self._first_nonfinite_job:
            self.first_nonfinite, self._first_nonfinite_job = ready.first_nonfinite, job

    def start_plan(self, plan: np.ndarray) -> None:
        """Begin a noise-target pass of ``plan`` (H, W) samples per pixel."""
        self.plan = plan
        self.plan_total = self.samples + int(plan.sum())
        self.plan_done[:] = [not plan[t.y0 : t.y1, t.x0 : t.x1].any() for t in self.plan_tiles]

    def end_plan(self) -> None:
        """The noise-target pass under way has been added whole."""
        if self.plan is not None:
            self.plan = None
            self.adaptive_passes += 1

    @property
    def samples(self) -> int:
        """Camera samples (paths) added so far, over the whole image."""
        return int(self.counts.sum())

    @property
    def spp(self) -> int:
        """Samples per pixel that every pixel has (the least over pixels)."""
        return int(self.counts.min()) if self.counts.size else 0

    @property
    def spp_max(self) -> int:
        """Samples per pixel of the pixels that have the most."""
        return int(self.counts.max()) if self.counts.size else 0

    @property
    def complete(self) -> bool:
        """Every tile has every pass (and no noise-target pass is under way)."""
        return bool(np.all(self.passes_done == len(self.passes))) and self.plan is None

    def image(self) -> np.ndarray:
        """(H, W, 3) float32: each pixel's mean radiance (0 where it has no sample yet).

        Computed tile by tile, so it needs no float64 temporary the size of the image.
        """
        image = np.zeros(self.sums.shape, dtype=np.float32)
        for tile in self.tiles:
            rows, columns = slice(tile.y0, tile.y1), slice(tile.x0, tile.x1)
            counts = self.counts[rows, columns, None]
            image[rows, columns] = np.divide(
                self.sums[rows, columns], counts, out=np.zeros((*counts.shape[:2], 3)), where=counts > 0
            )
        return image

    def feature_sums(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(H, W, 3) float64 each: the sums of feature image ``name`` (``FEATURES``) over every
        sample, and over the even samples less the odd ones."""
        assert self.features is not None, "this render gathers no features"
        assert self.feature_differences is not None
        k = slice(3 * FEATURES.index(name), 3 * FEATURES.index(name) + 3)
        return self.features[..., k], self.feature_differences[..., k]

    def feature_image(self, name: str) -> np.ndarray:
        """(H, W, 3) float64: the mean of feature image ``name`` (``FEATURES``) per pixel (0
        where a pixel has no sample yet)."""
        return per_sample(self.feature_sums(name)[0], self.counts)

    def halves_of(self, sums: np.ndarray, differences: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """The means of each pixel's even and of its odd samples, from the sums of all of them
        and the even ones' less the odd ones' (``halves``): None unless every pixel has an
        even number of samples, at least 2 (then both halves have as many)."""
        if not self.halves or self.counts.min() < 2 or np.any(self.counts & 1):
            return None
        half = self.counts // 2
        return per_sample((sums + differences) / 2, half), per_sample((sums - differences) / 2, half)


def per_sample(sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``sums`` (H, W, C) divided by ``counts`` (H, W), 0 where a count is 0."""
    return np.divide(sums, counts[..., None], out=np.zeros(sums.shape), where=counts[..., None] > 0)
