"""A render's film, denoised: what ``render_result(..., denoise=True)`` and ``ptlab render
--denoise`` do after the last pass (and, in a render to a target error, after each pass, to
know the denoised image's error).

The film gives the denoiser (``ptlab.denoise``) each pixel's two independent halves, the part
of them that lights seen directly make (kept out of the denoiser), and the albedo and normal
images (``ptlab.integrators.features``). It runs in the main process, once per call, whatever
ran the render's jobs (processes, threads, a Dask cluster).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ptlab.denoise import DenoiseInputs, ErrorEstimate
from ptlab.denoise.estimate import MAX_RELMSE
from ptlab.rendering.film import Film


@dataclass(frozen=True)
class DenoisedFilm:
    """The film's image denoised, and what is known of its error.

    Attributes:
        image: (H, W, 3) float32 the denoised image.
        relmse_estimate: its relMSE as the samples estimate it, or None where the estimate
            cannot be trusted (``refused`` says why).
        refused: why there is no estimate ("" when there is one).
        error_map: (H, W) each pixel's estimated relative squared error (where estimated),
            for a render to a target error to put its next samples where it is.
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
    error_map: np.ndarray | None
    seconds: float
    about: str
    settings: dict = field(default_factory=dict)
    error_bound: float | None = None


def film_inputs(film: Film) -> tuple[DenoiseInputs, str]:
    """The denoiser's inputs from ``film`` (which gathers features), and "" or why they have
    no independent halves (then both halves are the image: it can be denoised, but not its
    error estimated)."""
    direct = film.feature_image("direct")
    image = np.divide(
        film.sums, film.counts[..., None], out=np.zeros(film.sums.shape), where=film.counts[..., None] > 0
    )
    halves = film.halves_of(film.sums, film.differences)
    assert film.features is not None
    assert film.feature_differences is not None
    direct_sums, direct_differences = film.features[..., 0:3], film.feature_differences[..., 0:3]
    direct_halves = film.halves_of(direct_sums, direct_differences)
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


def denoise_film(film: Film, estimate: bool = True) -> DenoisedFilm:
    """Denoise the film's image; with ``estimate``, estimate the denoised image's error too
    (``ptlab.denoise.pipeline``: each half denoised, the image their mean)."""
    from ptlab.denoise import denoise

    start = time.perf_counter()
    inputs, why_not = film_inputs(film)
    result = denoise(inputs, estimate=estimate and not why_not)
    refused = why_not if estimate else "not asked for"
    error_map, bound = None, None
    if result.estimate is not None:
        refused, error_map = result.estimate.reason or "", result.estimate.error_map
        bound = error_bound(result.estimate)
    return DenoisedFilm(
        image=np.asarray(result.image, np.float32),
        relmse_estimate=None if result.estimate is None else result.estimate.relmse,
        refused=refused,
        error_map=error_map,
        seconds=time.perf_counter() - start,
        about=result.settings["denoiser"],
        settings=result.settings,
        error_bound=bound,
    )


#: Standard errors above an estimate that ``error_bound`` takes the error to be below.
BOUND_STANDARD_ERRORS = 2.0


def error_bound(estimate: ErrorEstimate) -> float | None:
    """What the denoised image's relMSE is below, with about 98% confidence, where its estimate
    is refused only because it is too uncertain to print (its standard error) or because the
    truth's brightness is uncertain (``ptlab.denoise.estimate``: the estimate with the other
    plausible brightness, ``alternative``): the larger of the two, plus
    ``BOUND_STANDARD_ERRORS`` standard errors (the block means' spread: one-sided, a normal
    variable exceeds 2 standard deviations 2.3% of the time). None where the estimate says
    nothing (not positive, or too large for its own denominators to hold)."""
    larger = max(estimate.value, estimate.alternative)
    if not estimate.value > 0 or larger > MAX_RELMSE or not np.isfinite(estimate.standard_error):
        return None
    return larger * (1.0 + BOUND_STANDARD_ERRORS * estimate.standard_error)
