"""Textures: a material parameter that varies over a surface, looked up by the hit's uv.

A mesh may carry texture coordinates ``uv`` at its vertices (an OBJ file's ``vt`` lines, or a
scene file's ``quad``); the renderer interpolates them at each hit with the hit's
barycentric coordinates, uv = (1 - b1 - b2) uv0 + b1 uv1 + b2 uv2 (GAMES101 lecture 9), and
a textured material turns them into its parameter for that hit (``Material.take``).

Two kinds: the checkerboard of GAMES101 Homework 5's floor, and an image (``ImageTexture``):
a mesh file's diffuse map (an OBJ material's ``map_Kd``, a glTF base colour texture) or a
scene file's ``albedo = { image = ... }``.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ptlab.atomic import path_kind
from ptlab.errors import PtlabError
from ptlab.image import srgb_decode
from ptlab.vectors import vec3


class Texture:
    """Base class: a colour for every point of a surface, given its (N, 2) uv."""

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        """(N, 3) float32 colours at texture coordinates ``uv`` (N, 2)."""
        raise NotImplementedError


class Checkerboard(Texture):
    """Two colours in squares of side 1 / (2 ``scale``) over uv (Homework 5's floor).

    The homework's ``evalDiffuseColor``: pattern = (frac(scale u) > 0.5) xor
    (frac(scale v) > 0.5), colour ``colours[1]`` where the pattern is 1 and ``colours[0]``
    where it is 0, so the square at the uv origin has ``colours[0]``. (frac is u - floor(u),
    so the squares continue past [0, 1]; the homework's ``fmodf`` mirrors them at 0.)

    Args:
        colours: (2, 3) the two colours.
        scale: pairs of squares per unit of u and of v (the homework's 5: ten squares across
            a quad whose uv runs from 0 to 1).
    """

    def __init__(self, colours, scale: float = 5.0):
        self.colours = np.asarray(colours, dtype=np.float64).reshape(2, 3)
        self.scale = float(scale)

    def __repr__(self) -> str:
        return f"Checkerboard(colours={self.colours.tolist()}, scale={self.scale!r})"

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        scaled = np.asarray(uv, dtype=np.float64) * self.scale
        odd = (scaled - np.floor(scaled)) > 0.5
        pattern = odd[:, 0] ^ odd[:, 1]
        a, b = self.colours.astype(np.float32)
        return vec3(*(np.where(pattern, b[c], a[c]) for c in range(3)))


#: What an image's integer texels are divided by, by their type: 8- and 16-bit files.
_INTEGER_RANGE = {np.dtype(np.uint8): 255, np.dtype(np.uint16): 65535}


class ImageTexture(Texture):
    """A colour image over uv in [0, 1]^2, repeated beyond it, looked up bilinearly.

    Texture coordinates follow OBJ's convention, which glTF's reader turns its own into
    (``ptlab.meshes``): u runs left to right, v bottom to top, so (0, 0) is the image's
    bottom-left corner and (0, 1) its top-left. A lookup blends the four texels around the
    point, each taken at its centre ((i + 1/2) / width, ...) and repeated past the edges (pbrt-v4
    section 10.4.3, ``Image::Bilerp`` with ``WrapMode::Repeat``), in linear values: 8- and
    16-bit images are sRGB-encoded, as PNG and JPEG files are, and are decoded first (IEC
    61966-2-1, ``ptlab.image.srgb_decode``); float images (EXR, HDR) are linear already. A grey
    image is a grey colour; an alpha channel is ignored.

    Integer texels are kept as they are stored, with a table of their 256 (or 65536) linear
    values: an 8-bit image takes a quarter of the memory of float texels, which matters
    because every worker of a render holds the scene.

    The image is a diffuse albedo, a reflectance: its linear values, tint included, must lie
    in [0, 1] (energy conservation), as a constant albedo must; an image beyond (a float
    image's -0.5 or 50, a signed integer image's negative texels) is refused, naming it.

    Args:
        path: an image file OpenImageIO reads (PNG, JPEG, EXR, HDR, TIFF, ...). Raises
            ``PtlabError`` naming the file if it cannot be read.
    """

    def __init__(self, path: str | Path):
        self._set(read_texels(Path(path)), Path(path).name)

    @classmethod
    def from_array(cls, pixels: np.ndarray, name: str = "array") -> ImageTexture:
        """A texture of (H, W), (H, W, C) ``pixels``, row 0 the image's top: uint8 or uint16
        ones sRGB-encoded, float ones linear (C = 1: grey; C = 2 or 4: the last is alpha,
        ignored). ``name`` says whose image it is in messages and ``repr``."""
        texture = cls.__new__(cls)
        texture._set(_colour_texels(np.asarray(pixels), name), name)
        return texture

    def _set(self, texels: np.ndarray, name: str) -> None:
        self.name = name
        self.height, self.width = texels.shape[:2]
        #: (H * W, 3) texels, row by row from the top, as stored (``decode`` makes them linear).
        self.texels = np.ascontiguousarray(texels.reshape(-1, 3))
        if texels.dtype in _INTEGER_RANGE:
            levels = np.arange(_INTEGER_RANGE[texels.dtype] + 1) / _INTEGER_RANGE[texels.dtype]
            self.decode: np.ndarray | None = srgb_decode(levels).astype(np.float32)
        else:
            self.texels = self.texels.astype(np.float32)
            self.decode = None
        #: The least and the greatest linear value of any channel, untinted.
        self.lowest, self.highest = (
            float(self.linear(self.texels.min())),
            float(self.linear(self.texels.max())),
        )
        #: (3,) what every colour is multiplied by (``tinted``).
        self.tint = np.ones(3, dtype=np.float32)
        self._check_range()
        # (A short fingerprint of the texels, so that a checkpoint of a scene, which keeps its
        # materials' repr, tells images apart: ``ptlab.rendering.checkpoint.scene_digest``.)
        self.digest = hashlib.sha256(self.texels.tobytes()).hexdigest()[:12]

    def tinted(self, colour) -> ImageTexture:
        """This image times ``colour`` (3,), per channel (a material's colour factor: OBJ's
        ``Kd``, glTF's ``baseColorFactor``), sharing the texels."""
        twin = copy.copy(self)
        twin.tint = self.tint * np.asarray(colour, dtype=np.float32).reshape(3)
        twin._check_range()
        return twin

    def linear(self, texels: np.ndarray) -> np.ndarray:
        """The float32 linear values of texels as stored, of any shape (integer ones sRGB-decoded)."""
        return texels if self.decode is None else self.decode.take(texels)

    def _check_range(self) -> None:
        """``PtlabError`` naming the image unless its tinted values lie in [0, 1]."""
        tint = self.tint
        if self.lowest >= 0 and tint.min() >= 0 and self.highest * tint.max() <= 1:
            return  # (most images: spared a pass over each channel for the exact range)
        # (A channel at a time: a reduction along the short axis of (N, 3) is 6x slower.)
        extremes = [
            self.linear(np.array([c.min(), c.max()])) * t for c, t in zip(self.texels.T, tint, strict=True)
        ]
        low, high = float(np.min(extremes)), float(np.max(extremes))
        if not 0 <= low <= high <= 1:  # (NaN too, from a NaN tint)
            tinted = "" if (tint == 1).all() else f" (tinted by {tint.tolist()})"
            raise PtlabError(
                f"image {self.name}: an albedo's texels must be from 0 to 1 (energy conservation), "
                f"found {low:.3g} to {high:.3g}{tinted}"
            )

    def __repr__(self) -> str:
        tint = "" if (self.tint == 1).all() else f", tint={self.tint.tolist()}"
        return f"ImageTexture({self.name!r}, {self.width}x{self.height}, sha256 {self.digest}{tint})"

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        uv = np.asarray(uv, dtype=np.float64)
        # Repeat: wrapped into [0, 1] first, in float64, so that every finite uv gives texels
        # that exist (times the width, a large one would lose its fraction, or overflow). One
        # that is not finite (a triangle's uv so far apart that their float32 differences
        # overflowed) gives NaN there, which fmax takes to 0: a texel, not an index error.
        with np.errstate(invalid="ignore"):  # (inf - inf)
            u = np.fmax(uv[:, 0] - np.floor(uv[:, 0]), 0.0)
            v = np.fmax(uv[:, 1] - np.floor(uv[:, 1]), 0.0)
        # Continuous texel coordinates: x from the left edge, y from the top (v points up).
        x = u * self.width - 0.5
        y = (1.0 - v) * self.height - 0.5
        x0, y0 = np.floor(x), np.floor(y)
        fx, fy = (x - x0).astype(np.float32), (y - y0).astype(np.float32)
        # Texel i of a row is i mod width (x0 runs from -1 to width).
        i0 = np.mod(x0, self.width).astype(np.intp)
        j0 = np.mod(y0, self.height).astype(np.intp)
        i1 = np.where(i0 + 1 == self.width, 0, i0 + 1)
        j1 = np.where(j0 + 1 == self.height, 0, j0 + 1)
        row0, row1 = j0 * self.width, j1 * self.width
        colour = np.zeros((len(uv), 3), dtype=np.float32)
        for index, weight in (
            (row0 + i0, (1 - fx) * (1 - fy)),
            (row0 + i1, fx * (1 - fy)),
            (row1 + i0, (1 - fx) * fy),
            (row1 + i1, fx * fy),
        ):
            colour += weight[:, None] * self.linear(self.texels.take(index, axis=0))
        colour *= self.tint
        return colour


def read_texels(path: Path) -> np.ndarray:
    """(H, W, 3) texels of an image file, as stored (uint8, uint16) or float32, or
    ``PtlabError`` naming the file."""
    import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)

    kind = path_kind(path)
    if kind != "file":
        found = {None: "not found", "folder": "is a folder, not an image"}.get(kind, "is not a file")
        raise PtlabError(f"image {path}: {found}")
    # (As stored: OpenImageIO would multiply the colour of an image with alpha by it.)
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    with _libpng_quiet():
        source = oiio.ImageInput.open(str(path), config)
        if source is None:
            raise _unreadable(path, oiio.geterror(), "unknown format")
        try:
            spec = source.spec()
            integer = spec.format.basetype in (oiio.UINT8, oiio.UINT16)
            # (Integers of other widths, and half floats, are read as float32.)
            pixels = source.read_image(0, 0, 0, spec.nchannels, oiio.UNKNOWN if integer else oiio.FLOAT)
            if pixels is None:  # e.g. a file cut short
                raise _unreadable(path, source.geterror(), "no pixels")
        finally:
            source.close()
    pixels = np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels)
    space = spec.get_string_attribute("oiio:ColorSpace").lower()
    if integer and space.startswith("lin"):  # (an integer image that says it is linear)
        pixels = pixels / np.float32(_INTEGER_RANGE[pixels.dtype])
    return _colour_texels(pixels, str(path))


def _unreadable(path: Path, message: str, default: str) -> PtlabError:
    """The error of an image OpenImageIO cannot read, from its message (``default`` for none):
    the message's first line, as it may hold one per layer that saw the fault (libpng's words,
    then the plugin's), and the first says it best ("Read error: hit end of file in png
    reader")."""
    first = next((line.strip() for line in message.splitlines() if line.strip()), default)
    return PtlabError(f"image {path}: cannot read it: {first}")


@contextlib.contextmanager
def _libpng_quiet() -> Iterator[None]:
    """Drop the lines libpng writes on the process's standard error while an image is read.

    libpng prints every error itself ("libpng error: IDAT: ..."), after OpenImageIO's
    handler has recorded it: its ``png_error`` calls its default handler, which prints, when
    the application's returns (libpng 1.6, pngerror.c), and OpenImageIO's returns. So the
    file descriptor 2 points to a temporary file meanwhile, and what else lands there is
    written on after. (Another thread's output in that moment comes later, not lost.)
    """
    if sys.stderr is not None:
        sys.stderr.flush()  # (what Python holds for it goes out first)
    try:
        saved = os.dup(2)
    except OSError:  # (no standard error to keep quiet)
        saved = None
    if saved is None:
        yield
        return
    with tempfile.TemporaryFile() as caught:
        os.dup2(caught.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            caught.seek(0)
            kept = b"".join(line for line in caught if not line.startswith(b"libpng error: "))
            if kept:
                os.write(2, kept)


def _colour_texels(pixels: np.ndarray, name: str) -> np.ndarray:
    """(H, W, 3) colour texels of (H, W) or (H, W, C) ``pixels``: grey repeated, alpha
    dropped; ``PtlabError`` for what is not an image."""
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    if pixels.ndim != 3 or 0 in pixels.shape or pixels.shape[2] > 4:
        raise PtlabError(f"image {name}: pixels of shape {pixels.shape} are not an image")
    if pixels.dtype not in _INTEGER_RANGE:
        pixels = pixels.astype(np.float32)
        if not np.isfinite(pixels).all():
            raise PtlabError(f"image {name}: has NaN or infinite pixels")
    colour = pixels[:, :, :3] if pixels.shape[2] >= 3 else pixels[:, :, :1]
    return np.repeat(colour, 3, axis=2) if colour.shape[2] == 1 else colour
