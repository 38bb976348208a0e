"""Two images compared, as pbrt-v4's ``imgtool diff`` compares them, with ptlab's metric
(``ptlab compare A B``; docs/compare.md).

B is the reference. The figures:

* the relMSE of A against B (``ptlab.measure.metrics``: the mean over pixels and channels of
  (A - B)^2 / (B + 0.01)^2), what ptlab's convergence charts and noise target use;
* the ratio of A's mean to B's, per channel: close to 1 for an unbiased render of the same
  scene (noise moves it little), and the first thing a missing factor (a cosine, a pi) moves;
* the largest absolute difference, and the pixel and channel where it is;
* how many pixels differ at all (0: the images are the same, bit for bit as read).

Both are read as linear values (``ptlab.image.ImageFile.linear``: float files as stored, 8-
and 16-bit ones decoded from sRGB). A file that holds a window of a larger image (``ptlab
render --crop`` writes one, as an EXR's data window) is compared with that window of the
other, whole image.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ptlab.atomic import write_atomically
from ptlab.errors import PtlabError
from ptlab.image import LINEAR_FORMATS, ImageFile, Window, check_output_path, read_image_file, write_image
from ptlab.measure.metrics import RELMSE_EPSILON, relative_squared_error, relmse

CHANNELS = ("R", "G", "B")


@dataclass(frozen=True)
class Side:
    """One of the two images: its file, size, encoding and window (``ImageFile``)."""

    path: str
    width: int
    height: int
    srgb: bool
    window: Window | None

    @classmethod
    def of(cls, path: str | Path, found: ImageFile) -> Side:
        """The file at ``path``, as read (``found``)."""
        height, width = found.pixels.shape[:2]
        return cls(str(path), width, height, found.srgb, found.window)

    def said(self) -> str:
        """``64x64, linear``, or ``16x16 window at (8, 8) of 64x64, sRGB decoded``."""
        size = f"{self.width}x{self.height}"
        if self.window is not None:
            w = self.window
            size += f" window at ({w.x}, {w.y}) of {w.full_width}x{w.full_height}"
        return f"{size}, {'sRGB decoded' if self.srgb else 'linear'}"

    def figures(self) -> dict[str, Any]:
        """The file as plain data (``Comparison.figures``)."""
        w = self.window
        window = None
        if w is not None:
            window = {"x": w.x, "y": w.y, "full_width": w.full_width, "full_height": w.full_height}
        encoding = "srgb" if self.srgb else "linear"
        return {
            "path": self.path,
            "width": self.width,
            "height": self.height,
            "encoding": encoding,
            "window": window,
        }


@dataclass
class Comparison:
    """Image A against the reference B (the module docstring's figures, each computed once).

    Attributes:
        a, b: the two files.
        image, reference: (H, W, 3) float64 linear values of A and B where they are compared.
        x, y: the compared pixels' top-left corner in the whole image (0, 0 unless a file is a
            window of it): every pixel said here is the whole image's.
    """

    a: Side
    b: Side
    image: np.ndarray
    reference: np.ndarray
    x: int = 0
    y: int = 0

    @cached_property
    def relmse(self) -> float:
        """The relMSE of A against B (``ptlab.measure.metrics.relmse``)."""
        return relmse(self.image, self.reference)

    @cached_property
    def mean_ratio(self) -> tuple[float | None, ...]:
        """A's mean over B's, per channel: 1.0 where both are 0, None where only B's is."""
        means, reference_means = self.image.mean(axis=(0, 1)), self.reference.mean(axis=(0, 1))
        return tuple(_ratio(float(m), float(r)) for m, r in zip(means, reference_means, strict=True))

    @cached_property
    def largest(self) -> tuple[float, int, int, int]:
        """The largest absolute difference |A - B| over pixels and channels, and where it is:
        (value, x, y, channel), the first such pixel in row order."""
        difference = np.abs(self.image - self.reference)
        row, column, channel = np.unravel_index(int(np.argmax(difference)), difference.shape)
        return float(difference[row, column, channel]), self.x + int(column), self.y + int(row), int(channel)

    @cached_property
    def differing(self) -> int:
        """Pixels whose values differ in any channel."""
        return int(np.count_nonzero((self.image != self.reference).any(axis=-1)))

    @property
    def pixels(self) -> int:
        """Pixels compared."""
        return self.image.shape[0] * self.image.shape[1]

    def error_map(self) -> np.ndarray:
        """(H, W) each pixel's relative squared error, the mean over channels (its mean is
        ``relmse``)."""
        return relative_squared_error(self.image, self.reference)

    def report(self) -> str:
        """The figures, a line each, as ``ptlab compare`` prints them."""
        height, width = self.image.shape[:2]
        ratios = "  ".join(
            f"{name} {_ratio_said(r)}" for name, r in zip(CHANNELS, self.mean_ratio, strict=True)
        )
        rows = [
            ("A", f"{self.a.path}: {self.a.said()}"),
            ("B (reference)", f"{self.b.path}: {self.b.said()}"),
        ]
        if self.a.window is not None or self.b.window is not None:
            rows.append(("compared", f"the {width}x{height} window at ({self.x}, {self.y})"))
        rows += [
            ("relMSE", f"{self.relmse:.6g}"),
            ("mean ratio A/B", ratios),
            ("largest difference", self._largest_said()),
            ("pixels that differ", _share_said(self.differing, self.pixels)),
        ]
        label = max(len(name) for name, _ in rows) + 2
        return "\n".join(f"{name:<{label}}{text}" for name, text in rows)

    def figures(self) -> dict[str, Any]:
        """The figures as plain data (``ptlab compare --json``)."""
        value, x, y, channel = self.largest
        a, b = self._values_at(x, y, channel)
        height, width = self.image.shape[:2]
        return {
            "a": self.a.figures(),
            "b": self.b.figures(),
            "compared": {"x": self.x, "y": self.y, "width": width, "height": height},
            "relmse": self.relmse,
            "mean_ratio": dict(zip(CHANNELS, self.mean_ratio, strict=True)),
            "largest_difference": {
                "value": value,
                "x": x,
                "y": y,
                "channel": CHANNELS[channel],
                "a": a,
                "b": b,
            },
            "differing_pixels": self.differing,
            "pixels": self.pixels,
            "differing_share": self.differing / self.pixels,
        }

    def _values_at(self, x: int, y: int, channel: int) -> tuple[float, float]:
        """A's and B's values at the whole image's pixel (x, y), in ``channel``."""
        row, column = y - self.y, x - self.x
        return float(self.image[row, column, channel]), float(self.reference[row, column, channel])

    def _largest_said(self) -> str:
        value, x, y, channel = self.largest
        if value == 0:
            return "0"
        a, b = self._values_at(x, y, channel)
        return f"{value:.6g} at pixel ({x}, {y}), {CHANNELS[channel]}: A {a:.6g}, B {b:.6g}"


def compare_files(a: str | Path, b: str | Path) -> Comparison:
    """Image file ``a`` against the reference file ``b`` (``PtlabError`` in one line if one
    cannot be read, their sizes or windows do not match, or a compared pixel is NaN or
    infinite)."""
    found_a, found_b = read_image_file(a), read_image_file(b)
    side_a, side_b = Side.of(a, found_a), Side.of(b, found_b)
    for side in (side_a, side_b):
        _check_window(side)
    image, reference, (x, y) = _matched(side_a, found_a.linear, side_b, found_b.linear)
    for side, pixels in ((side_a, image), (side_b, reference)):
        _check_finite(side, pixels, x, y)
    _check_not_negative(side_b, reference, x, y)
    return Comparison(side_a, side_b, image.astype(np.float64), reference.astype(np.float64), x, y)


def _matched(
    a: Side, image: np.ndarray, b: Side, reference: np.ndarray
) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """The pixels of A and B to compare, and the whole image's pixel at their top left: the
    images as they are, if of one size (and, if both are windows, of the same window); else
    the window one of them is, cut from the other, if that is the whole image."""
    if (a.width, a.height) == (b.width, b.height):
        if a.window is not None and b.window is not None and a.window != b.window:
            wa, wb = a.window, b.window
            if (wa.full_width, wa.full_height) != (wb.full_width, wb.full_height):
                raise PtlabError(
                    f"{a.path} and {b.path} are windows of images of different sizes "
                    f"({wa.full_width}x{wa.full_height} and {wb.full_width}x{wb.full_height}): "
                    "they show other pixels"
                )
            raise PtlabError(
                f"{a.path} and {b.path} are windows at different places of the image "
                f"({a.window.x}, {a.window.y}) and ({b.window.x}, {b.window.y}): they show other pixels"
            )
        window = a.window or b.window
        return image, reference, (0, 0) if window is None else (window.x, window.y)
    for part, whole, part_pixels, whole_pixels, swap in (
        (a, b, image, reference, False),
        (b, a, reference, image, True),
    ):
        w = part.window
        if (
            w is None
            or (w.full_width, w.full_height) != (whole.width, whole.height)
            or whole.window is not None
        ):
            continue
        if w.x < 0 or w.y < 0 or w.x + part.width > whole.width or w.y + part.height > whole.height:
            raise PtlabError(
                f"{part.path}: its window reaches outside its {whole.width}x{whole.height} image"
            )
        cut = whole_pixels[w.y : w.y + part.height, w.x : w.x + part.width]
        return (cut, part_pixels, (w.x, w.y)) if swap else (part_pixels, cut, (w.x, w.y))
    raise PtlabError(
        f"{a.path} is {a.width}x{a.height}, {b.path} {b.width}x{b.height}: the sizes differ"
        + ("" if a.window is None and b.window is None else " (and neither is a window of the other)")
    )


def _check_window(side: Side) -> None:
    """``PtlabError`` if ``side``'s pixels reach outside the image they are a window of (an
    EXR may store more than its display window: overscan, which has no place to compare)."""
    w = side.window
    if w is not None and (
        w.x < 0 or w.y < 0 or w.x + side.width > w.full_width or w.y + side.height > w.full_height
    ):
        raise PtlabError(
            f"{side.path}: its {side.width}x{side.height} pixels at ({w.x}, {w.y}) reach outside its "
            f"{w.full_width}x{w.full_height} image (its display window): compare takes windows inside it"
        )


def _check_not_negative(side: Side, pixels: np.ndarray, x: int, y: int) -> None:
    """``PtlabError`` if the reference has a negative value: relMSE divides by (B + 0.01)^2,
    which takes B to be radiance, 0 or more (at B = -0.01 it divides by 0)."""
    bad = (pixels < 0).any(axis=-1)
    if bad.any():
        row, column = divmod(int(np.argmax(bad)), pixels.shape[1])
        raise PtlabError(
            f"{side.path}: {int(bad.sum())} pixel(s) negative, the first at ({x + column}, {y + row}) "
            f"({float(pixels.min()):.3g} the least): a reference is radiance, 0 or more (relMSE "
            f"divides by (B + {RELMSE_EPSILON})^2)"
        )


def _check_finite(side: Side, pixels: np.ndarray, x: int, y: int) -> None:
    """``PtlabError`` if a pixel of ``side`` is NaN or infinite (no relMSE can be had)."""
    bad = ~np.isfinite(pixels).all(axis=-1)
    if bad.any():
        row, column = divmod(int(np.argmax(bad)), pixels.shape[1])
        raise PtlabError(
            f"{side.path}: {int(bad.sum())} pixel(s) NaN or infinite, the first at ({x + column}, "
            f"{y + row}): they have no error to measure"
        )


def write_difference(path: str | Path, comparison: Comparison) -> Path:
    """Write each pixel's relative squared error (``Comparison.error_map``): to a picture
    (.png, .jpg) in false colour on a log scale with its scale, identical pixels grey; to a
    linear file (.exr, ...) as the values themselves, in each channel (an .exr of a window
    records its place)."""
    path = check_output_path(path)
    errors = comparison.error_map()
    if path.suffix.lower() in LINEAR_FORMATS:
        full = comparison.a.window or comparison.b.window
        window = (
            None if full is None else Window(comparison.x, comparison.y, full.full_width, full.full_height)
        )
        metadata = {"relmse": comparison.relmse, "a": comparison.a.path, "b": comparison.b.path}
        planes = np.repeat(errors[..., None], 3, axis=-1).astype(np.float32)
        return write_image(path, planes, metadata, window=window)
    figure = _difference_figure(errors, comparison)
    return write_atomically(path, lambda temporary: figure.savefig(temporary, format=path.suffix.lower()[1:]))


#: The least longest side, in screen pixels, of the map in ``--diff``'s picture: a smaller
#: image is enlarged a whole number of times, each of its pixels a square (a larger one is
#: shown at its size: shrunk, its one-pixel differences would vanish).
MAP_SIZE = 512
#: The decades of relative squared error the picture's scale spans, below the largest.
MAP_DECADES = 5


def _difference_figure(errors: np.ndarray, comparison: Comparison):
    """The picture of ``write_difference``: a matplotlib figure (its object interface, not
    pyplot's, which would change a global backend)."""
    from matplotlib import colormaps
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    height, width = errors.shape
    inches = max(1, MAP_SIZE // max(width, height)) / 100  # (per pixel of the image, at 100 dpi)
    figure = Figure(figsize=(width * inches + 1.6, height * inches + 0.8), dpi=100, layout="constrained")
    axes = figure.subplots()
    x, y = comparison.x, comparison.y
    extent = (x - 0.5, x + width - 0.5, y + height - 0.5, y - 0.5)  # (the whole image's pixels)
    # (0 is masked, here and by a log scale: the "bad" grey of identical pixels.)
    masked = np.ma.masked_equal(errors, 0.0)
    colours = colormaps["inferno"].with_extremes(bad="0.55")
    largest = float(errors.max())
    if largest > 0:
        smallest = max(float(masked.min()), largest * 10.0**-MAP_DECADES)
        norm = LogNorm(smallest, largest)
        shown = axes.imshow(masked, cmap=colours, norm=norm, interpolation="nearest", extent=extent)
        bar = figure.colorbar(shown, ax=axes, fraction=0.08)
        bar.set_label(f"(A - B)² / (B + {RELMSE_EPSILON:g})², mean over R, G, B", fontsize=7)
        bar.ax.tick_params(labelsize=7)
        said = f"relMSE {comparison.relmse:.4g}; grey: identical pixels"
    else:
        axes.imshow(masked, cmap=colours, interpolation="nearest", extent=extent)
        said = "identical: every pixel the same"
    names = f"{Path(comparison.a.path).name} against {Path(comparison.b.path).name}"
    axes.set_title(f"relative squared error, {names}\n{said}", fontsize=8)
    axes.tick_params(labelsize=7)
    return figure


def _ratio(mean: float, reference_mean: float) -> float | None:
    """A mean over the reference's: 1.0 where both are 0, None where only the reference's is."""
    if reference_mean == 0:
        return 1.0 if mean == 0 else None
    return mean / reference_mean


def _ratio_said(ratio: float | None) -> str:
    return "- (B's mean is 0)" if ratio is None else f"{ratio:.6g}"


def _share_said(differing: int, pixels: int) -> str:
    if differing == 0:
        return f"0 of {pixels} (identical)"
    shown = f"{100 * differing / pixels:.3g}"
    if shown == "100" and differing < pixels:  # (not all: never rounded up to all)
        shown = ">99.9"
    return f"{differing} of {pixels} ({shown}%)"
