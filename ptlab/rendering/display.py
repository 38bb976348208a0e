"""Showing an image: in a Jupyter notebook, in a matplotlib window, or as a PNG file.

A render is linear light (the Cornell box's light is 48.5), which ``plt.imshow`` would clip
and show without the sRGB encoding a display expects; these show it as ``ptlab render``
writes a PNG: times 2^exposure, clipped to [0, 1], sRGB-encoded (``ptlab.image``).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from ptlab.image import SRGB_FORMATS, Window, encode_srgb8, write_image


def png_bytes(image: np.ndarray, exposure: float = 0.0) -> bytes:
    """(H, W, 3) linear RGB as the bytes of an 8-bit sRGB PNG file (written by OpenImageIO)."""
    with tempfile.TemporaryDirectory(prefix="ptlab-show-") as folder:
        path = Path(folder) / "image.png"
        write_image(path, image, exposure=exposure)
        return path.read_bytes()


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (which shows images itself): IPython's shell there
    is a ``ZMQInteractiveShell``, or a subclass of it (Colab's shell is one). (Not "ipykernel
    was imported": a program that talks to kernels, such as a test that runs a notebook,
    imports it too.)"""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    return any(kind.__name__ == "ZMQInteractiveShell" for kind in type(shell).__mro__)


def show(image, exposure: float = 0.0, out: str | Path = "ptlab-show.png") -> Path | None:
    """Show a render: ``image`` is (H, W, 3) linear RGB or anything with an ``image`` (a
    ``RenderResult``), brightened by 2^``exposure`` (stops).

    In a notebook it is displayed below the cell; from a script, in a matplotlib window,
    or, where matplotlib has no window to open (no display), written to ``out`` as a PNG,
    whose path is returned and printed.
    """
    linear = np.asarray(getattr(image, "image", image))
    if in_notebook():
        from IPython.display import Image, display

        display(Image(data=png_bytes(linear, exposure)))
        return None
    import matplotlib

    if matplotlib.get_backend().lower() == "agg":  # (what matplotlib falls back to with no display)
        path = write_image(out, linear, exposure=exposure)
        print(f"ptlab.show: no window to open here; wrote {Path(path).resolve()}")
        return Path(path)
    import matplotlib.pyplot as plt

    height, width = linear.shape[:2]
    figure = plt.figure(figsize=(width / 100, height / 100), dpi=100)
    figure.figimage(encode_srgb8(linear * np.float32(2.0**exposure)))
    plt.show()
    return None


def write_spp_map(path: str | Path, counts: np.ndarray, window: Window | None = None) -> Path:
    """Write where a render's samples went: (H, W) samples per pixel, as a heat map to a PNG
    or JPEG (matplotlib's viridis on a log scale, the fewest dark blue, the most yellow) or
    as the counts themselves, in every channel, to a linear format (``.exr``, which records
    the ``window`` of a crop, as the image's own file does)."""
    counts = np.asarray(counts, np.float64)
    if Path(path).suffix.lower() not in SRGB_FORMATS:
        return write_image(path, np.repeat(counts[..., None], 3, axis=-1).astype(np.float32), window=window)
    from matplotlib import colormaps

    low, high = np.log2(max(counts.min(), 1.0)), np.log2(max(counts.max(), 1.0))
    level = (np.log2(np.maximum(counts, 1.0)) - low) / max(high - low, 1e-9)
    colours = colormaps["viridis"](level)[..., :3]
    # The colours are meant as they show; write_image encodes linear values to sRGB, so
    # they go in decoded (the sRGB curve's inverse, IEC 61966-2-1).
    linear = np.where(colours <= 0.04045, colours / 12.92, ((colours + 0.055) / 1.055) ** 2.4)
    return write_image(path, linear.astype(np.float32))
