"""A render's film, denoised: what ``render_result(..., denoise=True)`` and ``ptlab render
--denoise`` do after the last pass (and, in a render to a target error, after each pass, to
know the denoised image's error).

The film gives the denoiser (``ptlab.denoise``) each pixel's two independent halves, the part
of them that lights seen directly make (kept out of the denoiser), and the albedo and normal
images (``ptlab.integrators.features``). It runs in the main process, once per call, whatever
ran the render's jobs (processes, threads, a Dask cluster).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

import numpy as np

from ptlab.denoise import DenoiseInputs, ErrorEstimate
from ptlab.denoise.estimate import BLOCK, MAX_RELMSE
from ptlab.errors import PtlabError
from ptlab.rendering.film import Film, per_sample


@dataclass(frozen=True)
class DenoisedFilm:
    """The film's image denoised, and what is known of its error.

    Attributes:
        image: (H, W, 3) float32 the denoised image.
        relmse_estimate: its relMSE as the samples estimate it, or None where the estimate
            cannot be trusted (``refused`` says why).
        refused: why there is no estimate ("" when there is one).
        error_value: the estimate's value, trusted or not (where there is one), which a render
            to a target error aims its next pass's samples by.
        seconds: the denoiser's time (with the estimate's).
        about: what denoised it, for the image's header.
        settings: how (``ptlab.denoise.Denoised.settings``), for the header too.
        error_bound: where the estimate is refused only for its own spread or for a small
            light's edges, what the error is below all the same (``error_bound``), else None:
            a render to a target error may stop on it.
    """

    image: np.ndarray
    relmse_estimate: float | None
    refused: str
    error_value: float | None
    seconds: float
    about: str
    settings: dict = field(default_factory=dict)
    error_bound: float | None = None


def film_inputs(film: Film) -> tuple[DenoiseInputs, str]:
    """The denoiser's inputs from ``film`` (which gathers features), and "" or why they have
    no independent halves (then both halves are the image: it can be denoised, but not its
    error estimated)."""
    direct = film.feature_image("direct")
    image = per_sample(film.sums, film.counts)
    halves = film.halves_of(film.sums, film.differences)
    direct_halves = film.halves_of(*film.feature_sums("direct"))
    why_not = ""
    if halves is None or direct_halves is None:
        halves, direct_halves = (image, image), (direct, direct)
        why_not = "each pixel needs an even number of samples, 2 or more, to measure its error with"
    inputs = DenoiseInputs(
        half_a=halves[0],
        half_b=halves[1],
        direct_a=direct_halves[0],
        direct_b=direct_halves[1],
        albedo=film.feature_image("albedo"),
        normal=film.feature_image("normal"),
    )
    return inputs, why_not


#: The smallest image edge, in pixels, that is denoised: OIDN's network sees a neighbourhood
#: of pixels, and on a 1 x 1 or 2 x 2 image it gave a picture 2-9 times too dark.
MIN_DENOISED_SIZE = 16


def warm_up_denoiser(threads: int | None) -> None:
    """Start making ready, in a thread of this process, what denoising the render will need:
    the imports its error's estimate takes (scipy.ndimage: 0.15-0.2 s) and OIDN's device and
    filters, while the workers render and the main process waits for them. The render does
    not wait for it: denoising later finds them made, or waits on the same imports and locks.
    A failure here is left for the denoiser itself to report, where it runs."""

    def warm() -> None:
        from ptlab.denoise.oidn import prepare

        try:
            import scipy.ndimage  # noqa: F401 (only imported: ``ptlab.denoise.estimate``)

            prepare(threads)
        except Exception:  # (reported by the denoiser, in the main thread)
            return

    threading.Thread(target=warm, name="ptlab-denoiser-warm-up", daemon=True).start()


def check_denoised_size(width: int, height: int) -> None:
    """``PtlabError`` in one line if a ``width`` x ``height`` image is too small to denoise."""
    if min(width, height) < MIN_DENOISED_SIZE:
        raise PtlabError(
            f"denoise: a {width}x{height} image is too small to denoise "
            f"(at least {MIN_DENOISED_SIZE}x{MIN_DENOISED_SIZE} pixels)"
        )


def denoise_film(film: Film, estimate: bool = True, threads: int | None = None) -> DenoisedFilm:
    """Denoise the film's image; with ``estimate``, estimate the denoised image's error too
    (``ptlab.denoise.pipeline``: each half denoised, the image their mean). ``threads``: the
    most threads the denoiser may use (None: as many as it finds worth it)."""
    from ptlab.denoise import denoise, oidn_version

    start = time.perf_counter()
    inputs, why_not = film_inputs(film)
    if not (np.any(inputs.half_a) or np.any(inputs.half_b)):  # (OIDN would make up a faint haze)
        black = f"Intel Open Image Denoise {oidn_version()} (not run: the image is black)"
        return DenoisedFilm(
            image=np.zeros(film.sums.shape, np.float32),
            relmse_estimate=None,
            refused="the image is black: no light to denoise",
            error_value=None,
            seconds=time.perf_counter() - start,
            about=black,
            settings={"denoiser": black},
        )
    result = denoise(inputs, estimate=estimate and not why_not, threads=threads)
    refused = why_not if estimate else "not asked for"
    value, bound = None, None
    if result.estimate is not None:
        refused, value = result.estimate.reason or "", result.estimate.value
        bound = error_bound(result.estimate)
    return DenoisedFilm(
        image=np.asarray(result.image, np.float32),
        relmse_estimate=None if result.estimate is None else result.estimate.relmse,
        refused=refused,
        error_value=value,
        seconds=time.perf_counter() - start,
        about=result.settings["denoiser"],
        settings=result.settings,
        error_bound=bound,
    )


def preview(film: Film, denoise: bool) -> tuple[np.ndarray, str]:
    """The image of a render under way, as a preview shows it (a file's, ``ptlab render
    --preview-every``; a notebook's, ``ptlab.rendering.progress``): denoised at once, with no
    estimate, for a render that denoises (once every pixel has a sample), with what denoised
    it; else the film's image and ""."""
    if not denoise or film.spp == 0:
        return film.image(), ""
    denoised = denoise_film(film, estimate=False)
    return denoised.image, denoised.about


#: Standard errors above an estimate that ``error_bound`` takes the error to be below.
BOUND_STANDARD_ERRORS = 2.0
#: ... if the estimate's standard error, a share of it, is at most this, and it is measured
#: from this many blocks at least: from fewer (below 80 x 80 pixels) the spread of the blocks
#: came out small exactly where the estimate came out low, and 5 of 17 bounds at 32 x 32 and
#: 64 x 64 did not hold, where all held at 128 x 128.
BOUND_MAX_STANDARD_ERROR = 1 / 3
BOUND_MIN_BLOCKS = 100


def error_bound(estimate: ErrorEstimate) -> float | None:
    """What the denoised image's relMSE is below, with about 98% confidence, where its estimate
    is refused only because it is too uncertain to print (its standard error) or because the
    truth's brightness is uncertain (``ptlab.denoise.estimate``: the estimate with the other
    plausible brightness, ``alternative``): the larger of the two, plus
    ``BOUND_STANDARD_ERRORS`` standard errors (the block means' spread: one-sided, a normal
    variable exceeds 2 standard deviations 2.3% of the time). None where the estimate says
    nothing (not positive, or too large for its own denominators to hold), or where its
    spread is not known well enough (``BOUND_MIN_BLOCKS``, ``BOUND_MAX_STANDARD_ERROR``)."""
    larger = max(estimate.value, estimate.alternative)
    blocks = (estimate.error_map.shape[0] // BLOCK) * (estimate.error_map.shape[1] // BLOCK)
    if not estimate.value > 0 or larger > MAX_RELMSE or blocks < BOUND_MIN_BLOCKS:
        return None
    if not estimate.standard_error <= BOUND_MAX_STANDARD_ERROR:
        return None
    return larger * (1.0 + BOUND_STANDARD_ERRORS * estimate.standard_error)
