"""Images: the float64 film, and files through OpenImageIO.

* ``.exr`` files hold linear float32 RGB, exactly what the renderer computed, with the
  render's settings in the header (spp, seed, seconds, scene, ptlab version); so do
  ``.hdr`` (Radiance RGBE), ``.pfm`` and ``.tif`` / ``.tiff`` files, in their own ways.
* ``.png`` and ``.jpg`` / ``.jpeg`` files hold 8-bit sRGB: linear values (times 2^exposure)
  clipped to [0, 1] and encoded with the
  sRGB transfer function of IEC 61966-2-1 (``srgb_encode``; ``tests/renderer/test_image.py`` checks
  it against colour-science's ``cctf_encoding``, which gives the same numbers but costs
  a second of imports, matplotlib's among them, at every PNG). (The homework writes
  ``pow(x, 0.6)``, which is neither sRGB nor a gamma any display expects.)

A render of a window of the image (``ptlab render --crop``) is written with its ``Window``:
``.exr`` and ``.tif`` files keep it as their data window inside the display window (the
whole image), so that ``ptlab compare`` or a compositor can place it.

Files are written atomically: to a temporary file beside the target, then renamed, so a
crash never leaves a half-written image under the final name.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.atomic import check_writable_file, path_kind, write_atomically
from ptlab.errors import PtlabError

#: Formats that hold the linear values as floats, and the 8-bit sRGB ones.
LINEAR_FORMATS = (".exr", ".hdr", ".pfm", ".tif", ".tiff")
SRGB_FORMATS = (".png", ".jpg", ".jpeg")
FORMATS = LINEAR_FORMATS + SRGB_FORMATS
#: The formats whose files record a window's place in its image (``Window``: a data window
#: inside the display window); the others hold the window's pixels alone.
WINDOW_FORMATS = (".exr", ".tif", ".tiff")


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """Linear values in [0, 1] -> sRGB-encoded values in [0, 1] (IEC 61966-2-1:1999):
    12.92 L below the break point 0.0031308, 1.055 L^(1 / 2.4) - 0.055 above it."""
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1 / 2.4) - 0.055)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] -> linear values in [0, 1] (IEC 61966-2-1:1999), the
    inverse of ``srgb_encode``: V / 12.92 below 0.04045, ((V + 0.055) / 1.055)^2.4 above."""
    return np.where(encoded <= 0.04045, encoded / 12.92, np.power((encoded + 0.055) / 1.055, 2.4))


@dataclass(frozen=True)
class Window:
    """Where an image's pixels sit in a larger image: its top-left pixel (``x``, ``y``) in a
    ``full_width`` x ``full_height`` image. OpenImageIO's data window (the pixels stored)
    inside the display window (the whole picture), as an EXR header keeps them."""

    x: int
    y: int
    full_width: int
    full_height: int


#: Values that ``encode_srgb8`` encodes at a time.
ENCODE_CHUNK = 1 << 16


def encode_srgb8(linear: np.ndarray) -> np.ndarray:
    """(H, W, 3) linear RGB -> (H, W, 3) uint8 sRGB (clipped to [0, 1] first).

    Encoded in chunks of ``ENCODE_CHUNK`` values, whose float64 temporaries stay in the
    cache and are reused: whole-image ones cost the command 0.1-0.25 s more at 784 x 784,
    mostly in touching fresh memory. (The chunks change no value.)
    """
    linear = np.asarray(linear)
    encoded = np.empty(linear.shape, dtype=np.uint8)
    values, out = linear.reshape(-1), encoded.reshape(-1)
    for start in range(0, values.size, ENCODE_CHUNK):
        chunk = values[start : start + ENCODE_CHUNK].astype(np.float64)
        clipped = np.clip(np.nan_to_num(chunk), 0.0, 1.0)
        out[start : start + ENCODE_CHUNK] = np.round(srgb_encode(clipped) * 255.0)
    return encoded


def check_output_path(path: str | Path) -> Path:
    """The path, if its extension is a format we write and it can be written."""
    path = Path(path)
    if path_kind(path) == "folder":
        raise PtlabError(f"{path}: is a folder; give an image file's name (e.g. {path / 'image.png'})")
    if path.suffix.lower() not in FORMATS:
        raise PtlabError(f"{path}: unsupported image format {path.suffix!r} (use {', '.join(FORMATS)})")
    return check_writable_file(path)


def write_image(
    path: str | Path,
    image: np.ndarray,
    metadata: dict | None = None,
    exposure: float = 0.0,
    layers: dict[str, np.ndarray] | None = None,
    window: Window | None = None,
) -> Path:
    """Write (H, W, 3) linear RGB, atomically: as float32 to ``.exr`` (and the other
    ``LINEAR_FORMATS``), as 8-bit sRGB to ``.png`` (and the other ``SRGB_FORMATS``), scaled
    by 2^``exposure`` first (stops; the linear formats keep the values as computed).

    ``metadata`` entries become header attributes ``ptlab:<key>`` (ints and floats stay
    numbers in EXR; other formats store them as text, where they store them at all).
    ``layers`` are more (H, W, 3) images, for an EXR only, each as three channels of the
    file beside R, G and B: ``<name>.R``, ``.G``, ``.B``, but ``<name>.X``, ``.Y``, ``.Z``
    for a ``"normal"`` (the EXR convention of layers that compositing programs read).
    ``window``: the image is that window of a larger one (a crop), which ``.exr`` and ``.tif``
    files record (the other formats hold no window).
    """
    import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)

    path = check_output_path(path)
    image = np.asarray(image)
    height, width = image.shape[:2]
    suffix = path.suffix.lower()
    if layers and suffix != ".exr":
        raise PtlabError(f"{path}: only an .exr file holds more images than the colour (its layers)")
    if suffix in LINEAR_FORMATS:
        names = ["R", "G", "B"]
        planes = [np.asarray(image, np.float32)]
        for layer, plane in (layers or {}).items():
            axes = "XYZ" if layer == "normal" else "RGB"
            names += [f"{layer}.{axis}" for axis in axes]
            planes.append(np.asarray(plane, np.float32))
        pixels = np.ascontiguousarray(np.concatenate(planes, axis=-1))
        spec = oiio.ImageSpec(width, height, len(names), oiio.FLOAT)
        spec.channelnames = tuple(names)
        if suffix == ".exr":
            spec.attribute("compression", "zip")
    else:
        pixels = encode_srgb8(image * np.float32(2.0**exposure) if exposure else image)
        spec = oiio.ImageSpec(width, height, 3, oiio.UINT8)
        spec.attribute("oiio:ColorSpace", "sRGB")
    if window is not None:
        spec.x, spec.y = window.x, window.y
        spec.full_x, spec.full_y = 0, 0
        spec.full_width, spec.full_height = window.full_width, window.full_height
    # EXR headers hold typed numbers; PNG text chunks hold only strings (OpenImageIO drops
    # other types there), so a PNG gets every value as text. EXR integers are 32-bit: a
    # larger one (a big seed) goes in as text too.
    typed = suffix == ".exr"
    for key, value in (metadata or {}).items():
        keep = typed and (
            isinstance(value, float)
            or (isinstance(value, int) and not isinstance(value, bool) and -(2**31) <= value < 2**31)
        )
        spec.attribute(f"ptlab:{key}", value if keep else str(value))

    def write(temporary: str) -> None:
        out = oiio.ImageOutput.create(temporary)
        if out is None or not out.open(temporary, spec):
            raise PtlabError(f"{path}: cannot write image: {oiio.geterror()}")
        ok = out.write_image(pixels)
        out.close()
        if not ok:
            raise PtlabError(f"{path}: cannot write image: {out.geterror()}")

    return write_atomically(path, write)


@dataclass(frozen=True)
class ImageFile:
    """An image file as read (``read_image_file``).

    Attributes:
        pixels: (H, W, 3) float32 as stored: linear for float files, stored value / 255 (or
            / 65535) for integer ones, which are still sRGB-encoded.
        metadata: the file's ``ptlab:`` header entries, without the prefix.
        srgb: whether the pixels are sRGB-encoded: an integer file (8- or 16-bit, as PNG and
            JPEG are) that does not name a linear colour space.
        window: where the pixels sit in a larger image (a crop's ``.exr`` or ``.tif``), or
            None when the file is the whole image.
    """

    pixels: np.ndarray
    metadata: dict
    srgb: bool
    window: Window | None

    @property
    def linear(self) -> np.ndarray:
        """(H, W, 3) linear values: the pixels, sRGB-decoded where they are encoded."""
        if not self.srgb:
            return self.pixels
        return srgb_decode(self.pixels.astype(np.float64)).astype(np.float32)


def read_image(path: str | Path) -> tuple[np.ndarray, dict]:
    """(H, W, 3) float32 pixels of an image file and its ``ptlab:`` metadata.

    EXR pixels come back as stored (linear); 8-bit files come back as stored values / 255
    (still sRGB-encoded: ``read_image_file(path).linear`` decodes them).
    """
    found = read_image_file(path)
    return found.pixels, found.metadata


def read_image_file(path: str | Path) -> ImageFile:
    """The pixels, header, encoding and window of an image file (``ImageFile``), or
    ``PtlabError`` in one line if it cannot be read as an RGB image."""
    import OpenImageIO as oiio  # noqa: N813 (the name OpenImageIO documents)

    path = Path(path)
    kind = path_kind(path)
    if kind != "file":
        raise PtlabError(
            f"{path}: "
            + {None: "no such image file", "folder": "is a folder, not an image file"}.get(
                kind, "is not a regular file (a device or a pipe?)"
            )
        )
    source = oiio.ImageInput.open(str(path))
    if source is None:
        raise PtlabError(f"{path}: cannot read image: {oiio.geterror()}")
    try:
        spec = source.spec()
        if spec.nchannels < 3:
            raise PtlabError(f"{path}: has {spec.nchannels} channel(s), not the 3 of an RGB image")
        pixels = source.read_image(0, 0, 0, 3, oiio.FLOAT)
        if pixels is None:  # e.g. a file cut short
            raise PtlabError(f"{path}: cannot read image: {source.geterror() or 'no pixels'}")
    finally:
        source.close()
    metadata = {
        a.name.removeprefix("ptlab:"): a.value for a in spec.extra_attribs if a.name.startswith("ptlab:")
    }
    image = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, 3)
    if path.suffix.lower() == ".pfm":
        # A PFM file stores its bottom row first, as OpenImageIO writes it, but OpenImageIO
        # 3.2 reads the rows back in file order (tests/renderer/test_cli.py checks both).
        image = image[::-1]
    # (OpenImageIO takes integer pixels for sRGB unless the file names its colour space:
    # "srgb_rec709_scene" for a PNG, a "lin_..." or "linear" one for linear values.)
    space = spec.get_string_attribute("oiio:ColorSpace").lower()
    integer = spec.format.basetype not in (oiio.HALF, oiio.FLOAT, oiio.DOUBLE)
    srgb = integer and not space.startswith("lin")
    whole = (spec.x, spec.y, spec.width, spec.height) == (
        spec.full_x,
        spec.full_y,
        spec.full_width,
        spec.full_height,
    )
    window = None
    if not whole:
        window = Window(spec.x - spec.full_x, spec.y - spec.full_y, spec.full_width, spec.full_height)
    return ImageFile(image, metadata, srgb, window)
