"""The film: per-pixel sums of radiance in float64, and how many passes each tile has.

Jobs finish in any order, but the film adds each tile's passes in pass order (a result
that arrives early waits in ``pending``), so the float64 sums, and so the image, are the
same bit for bit whatever the number of workers. Tiles are disjoint, so the order *between*
tiles does not matter.
"""

from __future__ import annotations

import numpy as np

from ptlab.rendering.jobs import JobResult, Tile


class Film:
    """Accumulated radiance of a render in progress.

    Attributes:
        sums: (H, W, 3) float64 radiance summed over every sample taken so far.
        passes: samples per pixel of each pass of the render (``ptlab.rendering.pass_schedule``).
        passes_done: (tiles,) passes added for each tile.
        rays, query_seconds, sampler_seconds: work done so far (rays traced, seconds inside
            ray queries and inside the sampler).
        nonfinite: samples that were NaN or infinite and were left out of ``sums``
            (``ptlab.integrators.wavefront.add_to_film``).
        first_nonfinite: (x, y, depth) of the first of them, by pass and tile (None if none).
    """

    def __init__(self, width: int, height: int, tiles: list[Tile], passes: list[int]):
        self.tiles = tiles
        self.passes = list(passes)
        self.sums = np.zeros((height, width, 3))
        self.passes_done = np.zeros(len(tiles), dtype=np.int64)
        self.rays = 0
        self.query_seconds = 0.0
        self.sampler_seconds = 0.0
        self.nonfinite = 0
        self.first_nonfinite: tuple[int, int, int] | None = None
        self._first_nonfinite_job = (np.inf, np.inf)
        self.pending: dict[tuple[int, int], JobResult] = {}

    def add(self, result: JobResult) -> None:
        """Add a job's sums once every earlier pass of its tile has been added."""
        self.pending[result.job.tile.index, result.job.pass_index] = result
        index = result.job.tile.index
        while (index, int(self.passes_done[index])) in self.pending:
            ready = self.pending.pop((index, int(self.passes_done[index])))
            tile = ready.job.tile
            self.sums[tile.y0 : tile.y1, tile.x0 : tile.x1] += ready.sums
            self.passes_done[index] += 1
            self.rays += ready.rays
            self.query_seconds += ready.query_seconds
            self.sampler_seconds += ready.sampler_seconds
            self.nonfinite += ready.nonfinite
            job = (ready.job.pass_index, tile.index)
            if ready.first_nonfinite is not None and job < self._first_nonfinite_job:
                self.first_nonfinite, self._first_nonfinite_job = ready.first_nonfinite, job

    @property
    def tile_spp(self) -> np.ndarray:
        """(tiles,) samples per pixel in each tile: the spp of its first passes_done passes."""
        spp_after = np.concatenate([[0], np.cumsum(self.passes, dtype=np.int64)])
        return spp_after[self.passes_done]

    @property
    def samples(self) -> int:
        """Camera samples (paths) added so far, over the whole image."""
        return int(
            sum(
                int(count) * t.shape[0] * t.shape[1]
                for t, count in zip(self.tiles, self.tile_spp, strict=True)
            )
        )

    @property
    def spp(self) -> int:
        """Samples per pixel that every pixel has (the least over tiles)."""
        return int(self.tile_spp.min()) if len(self.tile_spp) else 0

    @property
    def spp_max(self) -> int:
        """Samples per pixel of the tiles that have the most."""
        return int(self.tile_spp.max()) if len(self.tile_spp) else 0

    @property
    def complete(self) -> bool:
        """Every tile has every pass."""
        return bool(np.all(self.passes_done == len(self.passes)))

    def image(self) -> np.ndarray:
        """(H, W, 3) float32: each pixel's mean radiance (0 where a tile has no sample yet).

        Computed tile by tile, so it needs no float64 temporary the size of the image.
        """
        image = np.zeros(self.sums.shape, dtype=np.float32)
        for tile, count in zip(self.tiles, self.tile_spp, strict=True):
            if count > 0:
                rows, columns = slice(tile.y0, tile.y1), slice(tile.x0, tile.x1)
                image[rows, columns] = self.sums[rows, columns] / count
        return image
