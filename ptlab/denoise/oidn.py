"""Intel Open Image Denoise (OIDN), through its Python binding ``pyoidn``: the one denoiser
ptlab uses (an optional dependency, ``pip install 'ptlab[denoise]'``).

OIDN's ``RT`` filter is a neural network trained on path-traced images. Beside the noisy
colour it takes two *auxiliary* images, the albedo and the normal of what each pixel sees,
which show it where the picture's edges are. Ours come from the same few samples as the
colour, so they are noisy too, and OIDN's documentation (API, "RT" filter) asks for noisy
auxiliary images to be *prefiltered*: each denoised first by a filter of its own that is
given only that image and an output, then the colour denoised with them and ``cleanAux``
set, which tells the network to trust them as noise-free. Without the prefilter the network
has to guess how far to trust them, and leaves some of their noise in the image.

pyoidn's one-call ``denoise`` always binds a colour, so it cannot run the prefilter: this
module builds the three filters itself from pyoidn's ``Device`` and ``Filter`` and keeps
them for the life of the process (creating a device and a filter costs more than a small
image's denoising). A device's thread count is fixed when it is committed, so there is one
device per thread count asked for. (The filters keep their scratch memory, sized for the
largest image they denoised, until the process ends.)
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from ptlab.errors import PtlabError, is_integer

#: OIDN's filter qualities (``OIDN_QUALITY_*``).
QUALITIES = {"high": 6, "balanced": 5, "fast": 4}
#: "balanced", not OIDN's "high": with prefiltered features, "high" runs a larger network
#: that took 2.2x the time and gave 0.82-1.63x (median 1.06x) the relMSE of "balanced" on
#: four scenes at 4-64 spp (``scripts/denoise_study.py``).
DEFAULT_QUALITY = "balanced"
#: What the albedo and normal given to ``denoise_colour`` are (its docstring).
FEATURES = ("prefilter", "clean", "noisy")
#: What to say when pyoidn is not there.
MISSING = "denoising needs Intel Open Image Denoise: pip install 'ptlab[denoise]'"


def require_oidn() -> ModuleType:
    """The ``pyoidn`` module, or ``PtlabError`` saying what to install."""
    try:
        import pyoidn
    except ImportError:
        raise PtlabError(MISSING) from None
    return pyoidn


def oidn_version() -> str:
    """The version of the OIDN library itself (e.g. "2.5.1"), as its device reports it."""
    with _lock:
        version = _filters(None).device.get_int("version")  # two decimal digits per component
    return f"{version // 10000}.{version // 100 % 100}.{version % 100}"


def prepare(threads: int | None = None) -> None:
    """Make OIDN's device with ``threads`` threads and its filters now, not at the first
    denoising (a render does it while its workers render: ``ptlab.rendering.denoising``)."""
    with _lock:
        _filters(threads)


@dataclass
class _Filters:
    """A committed device and its three RT filters: the colour's and the two prefilters."""

    device: Any
    colour: Any
    albedo: Any
    normal: Any


_cache: dict[int, _Filters] = {}
#: OIDN serialises the work of one device; the filters' bound images are shared state.
_lock = threading.Lock()


def _filters(threads: int | None) -> _Filters:
    """The device with ``threads`` threads (None: OIDN's choice) and its filters, made once
    per process. Call with ``_lock`` held."""
    key = threads or 0
    if key not in _cache:
        pyoidn = require_oidn()
        device = pyoidn.Device(pyoidn.OIDN_DEVICE_TYPE_CPU)
        device.set_int("numThreads", key)  # (0 is OIDN's "as many as pays")
        device.commit()
        _check(device, "creating the device")
        made = [pyoidn.Filter(device, pyoidn.OIDN_FILTER_TYPE_RT) for _ in range(3)]
        _check(device, "creating its filters")
        _cache[key] = _Filters(device, *made)
    return _cache[key]


def _check(device: Any, doing: str) -> None:
    """Raise if OIDN reported an error (it does not raise: its errors wait to be asked for)."""
    message = device.get_error()
    if message is not None:
        raise RuntimeError(f"Open Image Denoise failed {doing}: {message}")


def _run(
    device: Any,
    image_filter: Any,
    images: dict[str, np.ndarray],
    quality: str,
    flags: dict[str, bool] | None = None,
) -> None:
    """Bind ``images`` (name -> contiguous float32 (H, W, 3)), ``quality`` and ``flags`` to
    the filter, commit and execute it."""
    import pyoidn

    for name in ("color", "albedo", "normal"):
        if name not in images:
            image_filter.unset_image(name)  # (a binding from an earlier call would stay)
    for name, image in images.items():
        image_filter.set_image(name, image, pyoidn.OIDN_FORMAT_FLOAT3)
    image_filter.set_int("quality", QUALITIES[quality])
    for name, value in (flags or {}).items():
        image_filter.set_bool(name, value)
    image_filter.commit()
    image_filter.execute()
    _check(device, "denoising")


def _float32(image: np.ndarray, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """``image`` as a contiguous float32 copy (the prefilters write into theirs), checked:
    (H, W, 3) like the colour, finite."""
    image = np.array(image, dtype=np.float32, order="C", copy=True)
    if image.shape != shape or len(shape) != 3 or shape[2] != 3:
        raise PtlabError(
            f"denoising: the {name} image is {image.shape}, not (H, W, 3) like the colour {shape}"
        )
    if not np.isfinite(image).all():
        raise PtlabError(f"denoising: the {name} image has NaN or infinite pixels")
    return image


def _check_options(quality: str, threads: int | None) -> None:
    """One line for a quality that OIDN does not have, or a thread count below 1."""
    if quality not in QUALITIES:
        raise PtlabError(f"denoising: quality {quality!r}: choose one of {', '.join(QUALITIES)}")
    if threads is not None and (not is_integer(threads) or threads < 1):
        raise PtlabError(f"denoising: threads {threads!r}: give a whole number, 1 or more (or None)")


def _prefilter_in_place(filters: _Filters, images: dict[str, np.ndarray], quality: str) -> None:
    """Denoise ``images``' albedo and normal, where given, each with its own filter (given
    only that image and an output: OIDN's prefiltering), in place (as OIDN allows; they are
    copies). Call with ``_lock`` held."""
    for name, image_filter in (("albedo", filters.albedo), ("normal", filters.normal)):
        if name in images:
            _run(filters.device, image_filter, {name: images[name], "output": images[name]}, quality)


def denoise_colour(
    colour: np.ndarray,
    albedo: np.ndarray | None = None,
    normal: np.ndarray | None = None,
    *,
    threads: int | None = None,
    quality: str = DEFAULT_QUALITY,
    features: str = "prefilter",
) -> np.ndarray:
    """(H, W, 3) float32: the HDR image ``colour`` (H, W, 3), >= 0, denoised by OIDN's RT filter.

    Args:
        colour: linear radiance, not negative.
        albedo: (H, W, 3) in [0, 1], the albedo each pixel sees (optional).
        normal: (H, W, 3) its shading normal, length at most 1 (optional; needs ``albedo``,
            as OIDN's filters do).
        threads: the most threads OIDN may use (None: as many as it finds worth it).
        quality: OIDN's filter quality, one of ``QUALITIES``.
        features: what ``albedo`` and ``normal`` are: "prefilter", noisy, to be denoised
            first (module docstring); "clean", noise-free already (prefiltered, or exact);
            "noisy", given to the network as they are (OIDN's choice for previews).
    """
    if features not in FEATURES:
        raise PtlabError(f"denoising: features {features!r}: choose one of {', '.join(FEATURES)}")
    _check_options(quality, threads)
    require_oidn()
    shape = np.shape(colour)
    images = {"color": _float32(colour, "colour", shape)}
    if normal is not None and albedo is None:
        raise PtlabError("denoising: OIDN takes a normal image only with an albedo image")
    if float(images["color"].min(initial=0.0)) < 0.0:
        raise PtlabError("denoising: the colour has negative pixels (OIDN's HDR input is >= 0)")
    for name, image in (("albedo", albedo), ("normal", normal)):
        if image is not None:
            images[name] = _float32(image, name, shape)
    output = np.empty_like(images["color"])
    with _lock:
        filters = _filters(threads)
        if features == "prefilter":
            _prefilter_in_place(filters, images, quality)
        flags = {"hdr": True, "cleanAux": features != "noisy" and "albedo" in images}
        _run(filters.device, filters.colour, dict(images, output=output), quality, flags)
    return output


def prefilter(
    albedo: np.ndarray,
    normal: np.ndarray | None = None,
    *,
    threads: int | None = None,
    quality: str = DEFAULT_QUALITY,
) -> tuple[np.ndarray, np.ndarray | None]:
    """``albedo`` and ``normal`` (H, W, 3) denoised by their own filters (float32), to be
    given to ``denoise_colour`` as ``features="clean"``: its prefilter done once for several
    colour images of the same render."""
    _check_options(quality, threads)
    require_oidn()
    shape = np.shape(albedo)
    images = {"albedo": _float32(albedo, "albedo", shape)}
    if normal is not None:
        images["normal"] = _float32(normal, "normal", shape)
    with _lock:
        _prefilter_in_place(_filters(threads), images, quality)
    return images["albedo"], images.get("normal")
