"""``ptlab converge``: what each estimator buys per second of rendering.

Each estimator (``path:nee``, ``path:bsdf``, ``path:mis``, ...) renders the scene at a
doubling ladder of samples per pixel, 1, 2, 4, ..., until its time budget is spent (an
adaptive one, ``path:nee+adaptive``, at a halving ladder of target errors, rendering to each
with ``target_error``: ``ptlab.rendering.adaptive``; a denoised one, ``path:nee+denoise``,
denoising each render, the denoiser's time counted in the render's); every
render is timed and compared with a reference image (``ptlab.measure.metrics``). The result is a
table of (estimator, spp, seconds, rmse, relmse) and, from it, the time each estimator needs
to reach a target error: the honest way to compare methods whose samples cost different
amounts (an MIS sample traces more rays than a BSDF sample, and is worth more).

The reference is a file the user gives, or a high-spp render with the best estimator,
``path:mis``, cached on disk by scene, resolution, spp and seed, and rendered with its own
seed so that its noise is independent of the ladder's. Or there is none (``estimated``):
then only adaptive estimators run, and the error charted is each render's own estimate.
"""

from __future__ import annotations

import csv
import hashlib
import itertools
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ptlab.atomic import write_atomically
from ptlab.errors import PtlabError
from ptlab.image import read_image, write_image
from ptlab.integrators.path import STRATEGIES
from ptlab.measure.metrics import relmse, rmse
from ptlab.rendering import RenderOptions, render_result
from ptlab.rendering.checkpoint import scene_digest
from ptlab.samplers import SAMPLERS
from ptlab.scene import Scene

#: Estimators are named INTEGRATOR or INTEGRATOR:STRATEGY, either followed by @SAMPLER, and
#: then by +adaptive for a render to each of a ladder of target errors.
ESTIMATOR_INTEGRATORS = ("path", "whitted")
ADAPTIVE_SUFFIX = "+adaptive"
#: ... and by this, in either order, for a render denoised (``render_result(..., denoise=True)``).
DENOISE_SUFFIX = "+denoise"
#: An adaptive ladder's targets: the first, then halving; each render's first pass has
#: ``ADAPTIVE_FIRST_SPP`` samples per pixel.
ADAPTIVE_FIRST_TARGET = 0.5
ADAPTIVE_FIRST_SPP = 8
#: The reference's seed is the ladder's plus this, so that their noise is independent.
REFERENCE_SEED_OFFSET = 1_000_003
#: The reference is rendered with the estimator that is best on hard scenes.
REFERENCE_ESTIMATOR = "path:mis"


@dataclass(frozen=True)
class Estimator:
    """An integrator with its options, named as on the command line (``path:mis@sobol``)."""

    label: str
    integrator: str
    strategy: str = RenderOptions.strategy
    sampler: str = RenderOptions.sampler
    adaptive: bool = False
    denoise: bool = False

    def options(self) -> dict:
        """Keyword arguments of ``render_result`` that select this estimator."""
        return dict(
            integrator=self.integrator, strategy=self.strategy, sampler=self.sampler, denoise=self.denoise
        )


def parse_estimators(text: str, sampler: str = RenderOptions.sampler) -> list[Estimator]:
    """``"path:bsdf,path:nee,path:mis@independent"`` -> estimators.

    ``path`` alone is ``path`` with the default strategy (``path:nee``); an estimator without
    ``@SAMPLER`` uses ``sampler``; ``+adaptive`` at the end renders to target errors, and
    ``+denoise`` denoises each render (both may be given, in either order).
    """
    estimators = []
    for label in (part.strip() for part in text.split(",")):
        method, suffixes = _suffixes(label)
        adaptive, denoise = ADAPTIVE_SUFFIX in suffixes, DENOISE_SUFFIX in suffixes
        method, at, chosen = method.partition("@")
        if at and chosen not in SAMPLERS:
            raise PtlabError(f"estimator {label!r}: the sampler after @ must be one of {', '.join(SAMPLERS)}")
        integrator, _, strategy = method.partition(":")
        if integrator not in ESTIMATOR_INTEGRATORS:
            raise PtlabError(
                f"estimator {label!r}: the integrator must be one of "
                f"{', '.join(ESTIMATOR_INTEGRATORS)} (e.g. path:mis)"
            )
        if integrator == "path" and strategy and strategy not in STRATEGIES:
            raise PtlabError(f"estimator {label!r}: the strategy must be one of {', '.join(STRATEGIES)}")
        if integrator != "path" and strategy:
            raise PtlabError(f"estimator {label!r}: {integrator} takes no strategy")
        if adaptive and (chosen or sampler) == "stratified":
            raise PtlabError(
                f"estimator {label!r}: an adaptive render needs sobol or independent, not stratified"
            )
        if denoise and integrator != "path":
            raise PtlabError(f"estimator {label!r}: only path-traced images are denoised")
        estimators.append(
            Estimator(
                label, integrator, strategy or RenderOptions.strategy, chosen or sampler, adaptive, denoise
            )
        )
    if len({e.label for e in estimators}) != len(estimators):
        raise PtlabError(f"estimators {text!r}: each may appear once")
    return estimators


def _suffixes(label: str) -> tuple[str, set[str]]:
    """``label`` without its ``+adaptive`` and ``+denoise`` (at its end, in either order), and
    which of them it had."""
    found: set[str] = set()
    while True:
        for suffix in (ADAPTIVE_SUFFIX, DENOISE_SUFFIX):
            if label.endswith(suffix) and suffix not in found:
                label, found = label.removesuffix(suffix), found | {suffix}
                break
        else:
            return label, found


@dataclass
class Measurement:
    """One rung of a ladder: a render of ``spp`` samples (an adaptive render's mean, rounded),
    its time and its error (against the reference; without one, the render's own estimate),
    and the render's own estimate of its relMSE (adaptive renders only, else None)."""

    estimator: str
    spp: int
    seconds: float
    rmse: float
    relmse: float
    image: np.ndarray
    estimate: float | None = None


def measure_ladder(
    scene: Scene,
    estimator: Estimator,
    reference: np.ndarray | None,
    budget: float,
    max_spp: int = 1 << 16,
    echo: Callable[[str], None] = print,
    res: tuple[int, int] | None = None,
    **render_options,
) -> list[Measurement]:
    """Render at 1, 2, 4, ... spp (an adaptive estimator: to relMSE 0.5, 0.25, ...) while the
    next rung fits in ``budget`` seconds in total.

    Each rung takes about twice as long as the one before, so the ladder stops when the
    time spent plus twice the last rung's would exceed the budget; the first rung always
    runs. ``render_options`` go to ``render_result`` (seed, workers, backend, ...).
    Without a ``reference`` (``res`` then gives the size), the error is each render's own
    estimate, which only adaptive renders have.
    """
    if reference is not None:
        res = (reference.shape[1], reference.shape[0])
    ladder: list[Measurement] = []
    spent, rung_index = 0.0, 0
    while True:
        if estimator.adaptive:
            target = ADAPTIVE_FIRST_TARGET / 2**rung_index
            rung_options = dict(spp=ADAPTIVE_FIRST_SPP, target_error=target, max_spp=max_spp)
        else:
            rung_options = dict(spp=2**rung_index)
        result = render_result(scene, res=res, **rung_options, **estimator.options(), **render_options)
        spent += result.seconds
        spp = max(1, round(result.spp_mean))
        if not ladder or spp != ladder[-1].spp:  # (an easy target may need no more samples)
            estimate = result.relmse_estimate
            rung = Measurement(
                estimator.label,
                spp,
                result.seconds,
                rmse(result.image, reference) if reference is not None else math.nan,
                relmse(result.image, reference) if reference is not None else float(estimate or math.nan),
                result.image,
                estimate,
            )
            ladder.append(rung)
            said = f"   (estimated {estimate:.4g})" if estimate is not None and reference is not None else ""
            echo(
                f"{rung.estimator:12} {rung.spp:7d} spp {rung.seconds:9.2f} s   "
                f"rmse {rung.rmse:.4g}   relMSE {rung.relmse:.4g}{said}"
            )
        if spp * 2 > max_spp or spent + 2 * result.seconds > budget:
            return ladder
        rung_index += 1


def time_to_reach(
    ladder: list[Measurement], target: float, unbiased: bool = True
) -> tuple[float, bool] | None:
    """Seconds the estimator needs for relMSE ``target``, and whether that is extrapolated.

    Between two rungs that bracket the target, interpolate on the log-log line through
    them. Past the last rung, extrapolate from it with the slope -1 of an unbiased
    estimator (error x time is constant); a denoised image's error has no such known slope
    (not ``unbiased``): not past its last rung. None if even the first rung is below the
    target (the answer is then below the ladder's resolution), if the error stops falling,
    or if a biased estimator's ladder never reached it.
    """
    if not ladder or ladder[0].relmse <= target:
        return None
    for before, after in itertools.pairwise(ladder):
        if after.relmse <= target < before.relmse:
            slope = math.log(after.seconds / before.seconds) / math.log(after.relmse / before.relmse)
            return before.seconds * (target / before.relmse) ** slope, False
    last = ladder[-1]
    if not unbiased or (len(ladder) >= 2 and last.relmse >= ladder[-2].relmse):
        return None
    return last.seconds * last.relmse / target, True


def reference_image(
    scene: Scene,
    res: tuple[int, int],
    spp: int,
    seed: int,
    cache_dir: Path | None,
    echo: Callable[[str], None] = print,
    quiet: bool = False,
    **render_options,
) -> np.ndarray:
    """A ``spp``-sample ``path:mis`` render of the scene, from the cache if it is there
    (with a progress bar on the terminal while it renders, unless ``quiet``)."""
    from ptlab.rendering import pass_schedule
    from ptlab.rendering.progress import ProgressBar

    estimator = parse_estimators(REFERENCE_ESTIMATOR)[0]
    key = hashlib.sha256(repr((scene_digest(scene), res, spp, seed, estimator.sampler)).encode()).hexdigest()[
        :16
    ]
    cached = None if cache_dir is None else cache_dir / f"{scene.name}-{key}.exr"
    if cached is not None and cached.is_file():
        image, _ = read_image(cached)
        echo(f"reference: {cached} (cached)")
        return image
    echo(f"reference: rendering {spp} spp with {REFERENCE_ESTIMATOR}@{estimator.sampler} ...")
    bar = ProgressBar(res[0] * res[1] * spp, len(pass_schedule(spp)), quiet=quiet)
    try:
        result = render_result(
            scene,
            spp=spp,
            res=res,
            seed=seed + REFERENCE_SEED_OFFSET,
            progress=bar,
            **estimator.options(),
            **render_options,
        )
    finally:
        bar.close()
    echo(f"reference: {result.seconds:.1f} s")
    if cached is not None:
        cached.parent.mkdir(parents=True, exist_ok=True)
        write_image(cached, result.image, dict(result.settings, reference=1))
    return result.image


def load_reference(path: str | Path, res: tuple[int, int]) -> np.ndarray:
    """A reference image from a linear (EXR) file, checked against the resolution."""
    path = Path(path)
    if path.suffix.lower() != ".exr":
        raise PtlabError(f"{path}: the reference must be a linear .exr image")
    image, _ = read_image(path)
    width, height = res
    if image.shape[:2] != (height, width):
        raise PtlabError(
            f"{path}: the reference is {image.shape[1]}x{image.shape[0]}, the "
            f"renders {width}x{height}: give --res {image.shape[1]}x{image.shape[0]}"
        )
    if not np.isfinite(image).all():
        raise PtlabError(f"{path}: the reference has NaN or infinite pixels")
    return image


def default_cache_dir() -> Path:
    """Where references are cached: $PTLAB_CACHE, else ~/.cache/ptlab/references."""
    if "PTLAB_CACHE" in os.environ:
        return Path(os.environ["PTLAB_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "ptlab" / "references"


def write_csv(path: Path, ladders: list[list[Measurement]]) -> None:
    """The table: one row per rung, columns integrator, spp, seconds, rmse, relmse and the
    render's own estimate of its relMSE (adaptive estimators; else empty)."""

    def write(temporary: str) -> None:
        with open(temporary, "w", newline="") as out:
            table = csv.writer(out)
            table.writerow(["integrator", "spp", "seconds", "rmse", "relmse", "relmse_estimate"])
            for ladder in ladders:
                for rung in ladder:
                    table.writerow(
                        [
                            rung.estimator,
                            rung.spp,
                            f"{rung.seconds:.4f}",
                            f"{rung.rmse:.6g}",
                            f"{rung.relmse:.6g}",
                            "" if rung.estimate is None else f"{rung.estimate:.6g}",
                        ]
                    )

    write_atomically(path, write)


def run_converge(
    scene: Scene,
    estimators: list[Estimator],
    out_dir: Path,
    res: tuple[int, int],
    budget: float,
    seed: int = 0,
    reference: str | Path | None = None,
    reference_spp: int = 1024,
    cache_dir: Path | None = None,
    target: float = 0.01,
    echo: Callable[[str], None] = print,
    quiet: bool = False,
    estimated: bool = False,
    **render_options,
) -> list[list[Measurement]]:
    """Measure every estimator's ladder and write the CSV, the chart and the strip.

    Writes ``convergence.csv``, ``convergence.png``, ``equal-time.png`` and
    ``reference.exr`` into ``out_dir``, and echoes each estimator's time to reach relMSE
    ``target``. ``render_options`` (workers, backend, ...) go to every render. With
    ``estimated``, there is no reference: every estimator must be adaptive, the errors are
    the renders' own estimates, and there is no strip (it shows errors against a reference).
    """
    from ptlab.measure.charts import convergence_chart, equal_time_strip

    if not 0 < budget < math.inf:
        raise PtlabError(f"budget {budget!r}: must be a positive, finite number of seconds")
    if any(estimator.denoise for estimator in estimators):  # (a missing extra: at once)
        from ptlab.denoise.oidn import require_oidn

        require_oidn()
    reference_pixels: np.ndarray | None = None
    if estimated:
        fixed = [e.label for e in estimators if not e.adaptive]
        if fixed:
            raise PtlabError(
                f"without a reference only adaptive estimators have an error to chart (their own "
                f"estimate): {', '.join(fixed)} is not (add {ADAPTIVE_SUFFIX})"
            )
    elif reference is not None:
        reference_pixels = load_reference(reference, res)
    else:
        reference_pixels = reference_image(
            scene, res, reference_spp, seed, cache_dir, echo, quiet, **render_options
        )
    # Warm up imports and first calls, so that the first rung is not charged for them.
    render_result(scene, spp=1, res=16, workers=1)
    ladders = [
        measure_ladder(
            scene, estimator, reference_pixels, budget, echo=echo, res=res, seed=seed, **render_options
        )
        for estimator in estimators
    ]
    out_dir.mkdir(parents=True, exist_ok=True)  # only now: no empty folder on an error
    write_csv(out_dir / "convergence.csv", ladders)
    width, height = res
    title = f"{scene.name}, {width}x{height}" + (", each render's own estimate" if estimated else "")
    convergence_chart(ladders, out_dir / "convergence.png", title, target, estimated=estimated)
    written = ["convergence.csv", "convergence.png"]
    if reference_pixels is not None:
        common = equal_time_strip(ladders, reference_pixels, out_dir / "equal-time.png")
        write_image(out_dir / "reference.exr", reference_pixels)
        written += ["equal-time.png", "reference.exr"]
    _echo_times_to_reach(estimators, ladders, target, estimated, echo)
    most_spp = max(ladder[-1].spp for ladder in ladders)
    if reference is None and not estimated and most_spp * 8 > reference_spp:
        echo(
            f"note: the ladder reached {most_spp} spp and the reference has {reference_spp}: "
            f"its noise inflates the last errors; use --reference-spp {most_spp * 16}"
        )
    if reference_pixels is not None:
        echo(f"equal-time strip at about {common:.1f} s")
    for name in written:
        echo(f"wrote {(out_dir / name).resolve()}")
    return ladders


def _echo_times_to_reach(
    estimators: list[Estimator],
    ladders: list[list[Measurement]],
    target: float,
    estimated: bool,
    echo: Callable[[str], None],
) -> None:
    """Echo each estimator's time to reach relMSE ``target`` (``time_to_reach``)."""
    echo(f"time to reach relMSE {target:g}" + (" (estimated)" if estimated else "") + ":")
    for estimator, ladder in zip(estimators, ladders, strict=True):
        reached = time_to_reach(ladder, target, unbiased=not estimator.denoise)
        if reached is None:
            text = "n/a (already below it at the first rung, or the error stopped falling)"
            if estimator.denoise:
                text = (
                    "n/a (below it at the first rung, or not reached: a denoised error is not extrapolated)"
                )
        else:
            text = f"{reached[0]:.2f} s" + (" (extrapolated with slope -1)" if reached[1] else "")
        echo(f"  {ladder[0].estimator:12} {text}")
