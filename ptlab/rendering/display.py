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

from ptlab.image import encode_srgb8, write_image


def png_bytes(image: np.ndarray, exposure: float = 0.0) -> bytes:
    """(H, W, 3) linear RGB as the bytes of an 8-bit sRGB PNG file (written by OpenImageIO)."""
    with tempfile.TemporaryDirectory(prefix="ptlab-show-") as folder:
        path = Path(folder) / "image.png"
        write_image(path, image, exposure=exposure)
        return path.read_bytes()


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (which shows images itself)."""
    return "ipykernel" in sys.modules


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
