"""Pictures of a chi-square test: observed histogram, expected counts, their difference.

Each tested ``wo``, and each wall whose test failed (its samples in its own frame against
an even spread in azimuth), gives three PNG images over the (phi, cos theta) grid of the
test (phi across, cos theta = 1 at the top, the horizon in the middle), each cell a block of
pixels: ``observed`` and ``expected`` counts on one shared colour scale (black, blue, red,
yellow, white as the count rises), and ``residual``, (observed - expected) / sqrt(expected),
blue where pdf promises more samples than ``sample`` gives, red where it promises fewer,
saturating at 5 standard deviations. Written with OpenImageIO (``ptlab.image.write_image``),
so no plotting library is needed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ptlab.image import write_image

#: A "heat" colour map in linear RGB, from 0 to 1.
_HEAT = np.array([[0, 0, 0], [0.05, 0.05, 0.6], [0.8, 0.05, 0.05], [1.0, 0.8, 0.0], [1, 1, 1]], dtype=float)
#: A diverging map in linear RGB, from -1 (blue) through 0 (white) to 1 (red).
_DIVERGING = np.array([[0.02, 0.1, 0.8], [1, 1, 1], [0.8, 0.02, 0.02]], dtype=float)
CELL_PIXELS = 4


def _colour_map(values: np.ndarray, anchors: np.ndarray) -> np.ndarray:
    """(H, W) values in [0, 1] -> (H, W, 3) colours interpolated between the anchors."""
    x = np.clip(values, 0, 1) * (len(anchors) - 1)
    low = np.minimum(x.astype(int), len(anchors) - 2)
    t = (x - low)[..., None]
    return anchors[low] * (1 - t) + anchors[low + 1] * t


def _image(cells: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(cells,) per-cell values -> (H, W) image with cos theta = 1 at the top, enlarged."""
    grid = cells.reshape(shape)[::-1]
    return np.kron(grid, np.ones((CELL_PIXELS, CELL_PIXELS)))


def write_plots(report, directory: str | Path) -> list[Path]:
    """Write the chi-square pictures of ``report`` into ``directory``; returns the paths.

    Only a failed chi-square check is drawn (nothing is written otherwise). Files:
    ``chi2-wo<degrees>-observed.png``, ``-expected.png``, ``-residual.png``, and
    ``chi2-wall<k>-...`` for each wall that failed.
    """
    directory = Path(directory)
    try:
        check = report["chi-square"]
    except KeyError:
        return []
    if check.passed or "lobes" not in check.data:
        return []
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    tests = [(f"chi2-wo{lobe['degrees']:g}", lobe) for lobe in check.data["lobes"]]
    tests += [(f"chi2-wall{wall['wall']}", wall) for wall in check.data.get("walls", [])]
    for stem, test in tests:
        observed, expected, shape = test["observed"], test["expected"], test["shape"]
        top = max(observed.max(), expected.max(), 1)
        residual = (observed - expected) / np.sqrt(np.maximum(expected, 1.0))
        for name, image in (
            ("observed", _colour_map(_image(observed / top, shape), _HEAT)),
            ("expected", _colour_map(_image(expected / top, shape), _HEAT)),
            ("residual", _colour_map(_image((residual / 5 + 1) / 2, shape), _DIVERGING)),
        ):
            written.append(write_image(directory / f"{stem}-{name}.png", image))
    return written
