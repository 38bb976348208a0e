"""ptlab against Mitsuba 3 on the same scene: seconds, error, and whether they agree.

1. Mitsuba's scene is written from ptlab's own (``ptlab.load_scene``) by ``mitsuba_export``:
   the same triangles, diffuse colours, area lights and camera, a box pixel filter, the
   ``path`` integrator.
2. Both render ``repeat`` rounds, a new seed each round, alternating the renderers and
   reversing the order every other round: Mitsuba with each of its samplers and Russian
   roulette depths, ptlab with each of its samplers. A render is timed as the wall-clock of
   the call that returns its pixels as a NumPy array (for Mitsuba, ``mi.render`` and the
   conversion, which waits for the kernel), after one untimed warm-up per configuration so
   that just-in-time compilation is not timed. The whole commands (``ptlab render``, and
   ``mitsuba`` on the same scene file) are also timed, as new processes from start to exit:
   that includes starting Python, imports, loading the scene, the worker processes or the
   kernels from Dr.Jit's disk cache (put there by an untimed 1-spp run of each Mitsuba
   command), and writing the EXR.
3. Every image is compared with a reference: a given EXR, or a ``reference_spp`` Mitsuba
   render (independent sampler, cached in ``$PTLAB_CACHE`` or ``~/.cache/ptlab/references``
   like ``ptlab converge``'s references).
4. The table gives, per renderer and sampler, the median and range over the rounds of the
   seconds, relMSE (``ptlab.measure.metrics``), relMSE without the pixels that see the light
   (reference above 1 in some channel), RMSE and seconds x relMSE (lower is better: an
   unbiased estimator's error falls as 1 / time, so this is its cost for a given error), and
   its speed and efficiency against ptlab with its default sampler, round by round (that
   one's seconds, and seconds x relMSE, over this one's).
5. Given a high-spp ptlab render too, the two references are compared: per-channel mean
   ratio with its z-score, and their relMSE beside what their noise alone would give. They
   must agree; a difference beyond noise is a bug in the scene's translation or in a
   renderer.
6. With ``denoise``, the race is to a clean image: ptlab's renders are denoised (``ptlab render
   --denoise``, ``render_result(..., denoise=True)``), and Mitsuba denoised by the same Intel
   Open Image Denoise runs as a process of its own (``mitsuba_denoised``), at ``spp`` and at
   ``mitsuba_denoise_spp`` samples. With ``target_from_mitsuba_spp`` N, ``ptlab render
   --target-error`` is given E_m, the true relMSE of Mitsuba's whole process at N spp: the
   median of ``repeat`` renders made before the rounds, with seeds the rounds do not use.
   A second table puts the whole processes side by side: their seconds x relMSE over that of
   (a) Mitsuba at N spp (``spp`` without a target) and (b) Mitsuba + OIDN at
   ``mitsuba_denoise_spp``, round by round (below 1: better than it), and each channel's mean
   over the reference's (a denoiser must not change the picture's brightness).

Russian roulette: Mitsuba numbers the first hit depth 1 and plays roulette once depth >=
``rr_depth``, so its ``rr_depth`` R starts roulette at the same vertex as ptlab's ``rr_depth``
R - 1: Mitsuba's 3 matches ptlab's default 2, Mitsuba's 2 starts one bounce earlier. The odds
differ too (Mitsuba: the throughput after this vertex's BSDF weight, at most 0.95; ptlab: before
it, at most 1). Mitsuba's path tracer always combines light and BSDF sampling with MIS
(ptlab's strategy ``mis`` is its equivalent; ptlab's default, ``nee``, the homework's, samples
the light only).
"""

from __future__ import annotations

import csv
import hashlib
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import numpy as np

from ptlab.atomic import write_atomically
from ptlab.denoise.oidn import require_oidn
from ptlab.errors import PtlabError
from ptlab.image import read_image, write_image
from ptlab.measure.converge import REFERENCE_SEED_OFFSET, default_cache_dir, load_reference
from ptlab.measure.metrics import relative_squared_error, rmse
from ptlab.measure.mitsuba_export import MITSUBA_RR_DEPTH, write_mitsuba_scene
from ptlab.measure.mitsuba_render import MitsubaRenderer, import_mitsuba
from ptlab.rendering import render_result
from ptlab.rendering.checkpoint import scene_digest
from ptlab.rendering.settings import MAX_SPP
from ptlab.samplers import DEFAULT_SAMPLER, SAMPLERS
from ptlab.scene import Scene
from ptlab.scene_file import load_scene

MITSUBA_SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler")
#: Mitsuba rounds these samplers' sample counts up to a square or a power of two.
MITSUBA_SPP_RULES: dict[str, tuple[Callable[[int], bool], str]] = {
    "stratified": (lambda n: math.isqrt(n) ** 2 == n, "a square number"),
    "ldsampler": (lambda n: n & (n - 1) == 0, "a power of two"),
}
#: The reference is rendered in passes of this many samples (one Dr.Jit kernel launch holds
#: every sample of a pass: 256 x 256 x 256 is 17 million lanes).
REFERENCE_PASS_SPP = 256
#: Pixels whose reference exceeds this in some channel see the light (the Cornell light is
#: about 40; everything lit by it stays below 1).
LIGHT_THRESHOLD = 1.0
#: The warm-up renders' seed, which no round uses.
WARM_UP_SEED = 2**31 - 1
#: |z| above this: the references' means differ by more than noise (for two unbiased
#: renderers a chance of 6e-5 per channel, of a normal variable beyond 4 standard deviations).
AGREEMENT_Z = 4.0
#: Mitsuba's renders that set ptlab's target (``target_from_mitsuba_spp``) take the rounds'
#: seeds plus this, which neither the rounds nor the reference use.
CALIBRATION_SEED_OFFSET = 2_000_003

Echo = Callable[[str], None]
T = TypeVar("T")


class RenderError(Exception):
    """A renderer or a command failed (not the user's mistake)."""


@dataclass(frozen=True)
class ComparisonOptions:
    """What to compare, and how often (``scripts/against_mitsuba.py``'s options).

    Attributes:
        scene: a built-in scene name or a scene file, of diffuse materials only.
        res: (width, height) of every image.
        spp: samples per pixel of every timed render.
        repeat: rounds, each with its own seed.
        seed: the first round's seed.
        samplers: Mitsuba's samplers, of ``MITSUBA_SAMPLERS``.
        rr_depths: Mitsuba's Russian roulette depths (Mitsuba's default, the one that matches
            ptlab's default, and 2).
        ptlab_samplers: ptlab's samplers, of ``ptlab.samplers.SAMPLERS``.
        ptlab_target_error: also time the whole process ``ptlab render --target-error`` to
            this relMSE, or None.
        target_from_mitsuba_spp: N, to give ``ptlab render --target-error`` Mitsuba's true
            relMSE at N spp instead (module docstring, 6), or None.
        denoise: denoise ptlab's renders, and race Mitsuba + OIDN as whole processes.
        mitsuba_denoise_spp: Mitsuba + OIDN's samples per pixel in baseline (b).
        process_sampler: Mitsuba's sampler in its whole processes (its scene file's default,
            independent, unless given).
        ptlab_strategy: ptlab's path tracer's strategy (``nee`` or ``mis``).
        workers: ptlab's worker processes, None for one per core (Mitsuba uses Dr.Jit's
            default thread count).
        variant: Mitsuba's variant, an RGB one.
        reference: a linear EXR of the same resolution, or None for a Mitsuba render of
            ``reference_spp`` samples (cached).
        reference_spp: samples per pixel of that Mitsuba reference.
        ptlab_reference: a high-spp ptlab EXR to check against the reference, or None.
        ptlab_reference_spp: its samples per pixel, None to read them from its metadata.
        time_processes: also time ``ptlab render`` and ``mitsuba`` as whole processes.
        in_process: time the renders in this process (False: the whole processes only).
        csv: a file to write every run to as CSV, or None.
    """

    scene: str = "cornell-box"
    res: tuple[int, int] = (256, 256)
    spp: int = 64
    repeat: int = 3
    seed: int = 0
    samplers: tuple[str, ...] = MITSUBA_SAMPLERS
    rr_depths: tuple[int, ...] = (MITSUBA_RR_DEPTH, 3, 2)
    ptlab_samplers: tuple[str, ...] = SAMPLERS
    ptlab_target_error: float | None = None
    target_from_mitsuba_spp: int | None = None
    denoise: bool = False
    mitsuba_denoise_spp: int = 16
    process_sampler: str = "independent"
    ptlab_strategy: str = "nee"
    workers: int | None = None
    variant: str = "llvm_ad_rgb"
    reference: str | None = None
    reference_spp: int = 4096
    ptlab_reference: str | None = None
    ptlab_reference_spp: int | None = None
    time_processes: bool = True
    in_process: bool = True
    csv: str | None = None

    def check(self) -> None:
        """Raise ``PtlabError`` for an option that cannot work."""
        if not 1 <= self.spp <= MAX_SPP:
            raise PtlabError(f"--spp {self.spp}: must be from 1 to {MAX_SPP}")
        if not 1 <= self.repeat <= 100:
            raise PtlabError(f"--repeat {self.repeat}: must be from 1 to 100")
        if not 1 <= self.reference_spp <= MAX_SPP:
            raise PtlabError(f"--reference-spp {self.reference_spp}: must be from 1 to {MAX_SPP}")
        if self.seed < 0:
            raise PtlabError(f"--seed {self.seed}: must be a non-negative integer")
        if self.workers is not None and self.workers < 1:
            raise PtlabError(f"--workers {self.workers}: must be at least 1")
        if "_rgb" not in self.variant:
            raise PtlabError(
                f"--variant {self.variant}: ptlab's colours are RGB; use an RGB variant such as llvm_ad_rgb"
            )
        for sampler in self.samplers:
            _check_mitsuba_spp("--spp", self.spp, sampler)
        self._check_processes()
        if self.denoise:
            require_oidn()  # (a missing extra: one line, before any work)
        if self.ptlab_reference_spp is not None and self.ptlab_reference_spp < 1:
            raise PtlabError(f"--ptlab-reference-spp {self.ptlab_reference_spp}: must be positive")
        if self.csv and not Path(self.csv).resolve().parent.is_dir():
            raise PtlabError(f"--csv {self.csv}: folder {Path(self.csv).parent} does not exist")

    def _check_processes(self) -> None:
        """``check`` for what the whole processes are asked."""
        if not (self.time_processes or self.in_process):
            raise PtlabError("--no-process and --processes-only: that leaves nothing to time")
        if self.process_sampler not in MITSUBA_SAMPLERS:
            raise PtlabError(
                f"--process-sampler {self.process_sampler}: choose one of {', '.join(MITSUBA_SAMPLERS)}"
            )
        if self.ptlab_target_error is not None and not 0 < self.ptlab_target_error < math.inf:
            raise PtlabError(f"--ptlab-target-error {self.ptlab_target_error}: must be a positive relMSE")
        amounts = {"--spp": self.spp, "--mitsuba-denoise-spp": self.mitsuba_denoise_spp}
        if self.target_from_mitsuba_spp is not None:
            amounts["--target-from-mitsuba-spp"] = self.target_from_mitsuba_spp
            if self.ptlab_target_error is not None:
                raise PtlabError(
                    "--ptlab-target-error and --target-from-mitsuba-spp: give one target, not both"
                )
        for option, spp in amounts.items():
            if not 1 <= spp <= MAX_SPP:
                raise PtlabError(f"{option} {spp}: must be from 1 to {MAX_SPP}")
            if self.time_processes:
                _check_mitsuba_spp(option, spp, self.process_sampler)
        if self.time_processes:
            return
        for option, asked in (
            ("--denoise", self.denoise),
            ("--target-from-mitsuba-spp", self.target_from_mitsuba_spp is not None),
        ):
            if asked:
                raise PtlabError(f"{option} races whole processes: leave out --no-process")

    @property
    def configurations(self) -> list[tuple[str, int]]:
        """Every (Mitsuba sampler, rr_depth) timed, in the table's order."""
        return [(sampler, depth) for depth in self.rr_depths for sampler in self.samplers]


def _check_mitsuba_spp(option: str, spp: int, sampler: str) -> None:
    """``PtlabError`` if Mitsuba's ``sampler`` would not render exactly ``spp`` samples."""
    rule = MITSUBA_SPP_RULES.get(sampler)
    if rule and not rule[0](spp):
        raise PtlabError(
            f"{option} {spp}: Mitsuba's {sampler} sampler needs {rule[1]} "
            f"(it would round it up and render more samples)"
        )


# ---------------------------------------------------------------------------------------------
# What is measured


@dataclass
class Run:
    """One timed render and its errors against the reference."""

    round: int
    seed: int
    seconds: float
    relmse: float
    relmse_unlit: float
    rmse: float
    image: np.ndarray

    @property
    def cost(self) -> float:
        """seconds x relMSE: the same for any spp of an unbiased estimator."""
        return self.seconds * self.relmse


@dataclass
class Contender:
    """One renderer with one configuration: a row of the table.

    Attributes:
        label: its name in the table.
        render: seed -> (H, W, 3) image and the seconds it took.
        warm_up: one untimed render before the rounds, or None.
        runs: its timed renders so far.
    """

    label: str
    render: Callable[[int], tuple[np.ndarray, float]]
    warm_up: Callable[[], object] | None = None
    runs: list[Run] = field(default_factory=list)


def measure(contender: Contender, round_: int, seed: int, reference: np.ndarray, unlit: np.ndarray) -> Run:
    """Render once with ``seed``, compare with ``reference`` ((H, W, 3); ``unlit``: (H, W) bool,
    the pixels that do not see the light), and add the run to ``contender.runs``."""
    image, seconds = contender.render(seed)
    if image.shape != reference.shape:
        raise RenderError(f"{contender.label}: the image is {image.shape}, the reference {reference.shape}")
    errors = relative_squared_error(image, reference)
    run = Run(
        round_,
        seed,
        seconds,
        float(errors.mean()),
        float(errors[unlit].mean()),
        rmse(image, reference),
        image,
    )
    contender.runs.append(run)
    return run


def run_command(command: list[str], label: str) -> float:
    """Run ``command`` to the end; its wall-clock seconds. Raises ``RenderError``."""
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        lines = [line for line in (done.stderr + done.stdout).splitlines() if line.strip()]
        raise RenderError(
            f"{label} failed (exit code {done.returncode}): {lines[-1] if lines else 'no output'}"
        )
    return seconds


def command_contender(label: str, command: Callable[[int, Path], list[str]], output: Path) -> Contender:
    """A whole process that writes ``output`` (an EXR), timed from start to exit."""

    def render(seed: int) -> tuple[np.ndarray, float]:
        seconds = run_command(command(seed, output), label)
        return read_image(output)[0], seconds

    return Contender(label, render)


def interleave(first: list[T], second: list[T]) -> list[T]:
    """Both lists in one, each spread evenly over the whole (a1 b1 a2 a3 b2 a4 ...)."""

    def place(items: list[T]) -> list[tuple[float, T]]:
        return [((k + 0.5) / len(items), item) for k, item in enumerate(items)]

    return [item for _, item in sorted(place(first) + place(second), key=lambda p: p[0])]


# ---------------------------------------------------------------------------------------------
# The reference


def mitsuba_reference(
    mitsuba: MitsubaRenderer,
    scene: Scene,
    res: tuple[int, int],
    spp: int,
    seed: int,
    cache_dir: Path,
    echo: Echo,
) -> tuple[np.ndarray, int]:
    """An ``spp``-sample Mitsuba render (independent sampler) and its spp, from the cache if it
    is there."""
    mi = mitsuba.mi
    identity = (
        mi.__version__,
        mi.variant(),
        scene_digest(scene),
        res,
        spp,
        seed,
        MITSUBA_RR_DEPTH,
        "independent",
        REFERENCE_PASS_SPP,
    )
    key = hashlib.sha256(repr(identity).encode()).hexdigest()[:16]
    cached = cache_dir / f"mitsuba-{scene.name}-{key}.exr"
    if cached.is_file():
        echo(f"reference: {cached} (cached)")
        return read_image(cached)[0], spp
    passes = [min(REFERENCE_PASS_SPP, spp - done) for done in range(0, spp, REFERENCE_PASS_SPP)]
    echo(f"reference: rendering {spp} spp with Mitsuba in {len(passes)} passes ...")
    total, seconds = np.zeros((res[1], res[0], 3)), 0.0
    for k, pass_spp in enumerate(passes):
        image, took = mitsuba.render(
            "independent", MITSUBA_RR_DEPTH, pass_spp, seed + REFERENCE_SEED_OFFSET + k
        )
        total += image.astype(np.float64) * pass_spp
        seconds += took
        if (k + 1) % 4 == 0 or k + 1 == len(passes):
            echo(f"reference: {k + 1}/{len(passes)} passes, {seconds:.0f} s")
    reference = (total / spp).astype(np.float32)
    cached.parent.mkdir(parents=True, exist_ok=True)
    write_image(
        cached,
        reference,
        dict(spp=spp, renderer=f"mitsuba {mi.__version__}", variant=mi.variant(), seconds=seconds),
    )
    echo(f"reference: wrote {cached}")
    return reference, spp


# ---------------------------------------------------------------------------------------------
# The report


def _summary(values: list[float], digits: int = 3) -> str:
    """median [min, max] with ``digits`` significant digits."""

    def fmt(v: float) -> str:
        return f"{v:.{digits}g}"

    if len(values) == 1:
        return fmt(values[0])
    return f"{fmt(statistics.median(values))} [{fmt(min(values))}, {fmt(max(values))}]"


def _markdown(rows: list[list[str]], legend: str) -> str:
    """The rows as a Markdown table (the first its header), and the legend below."""
    return "\n".join("| " + " | ".join(row) + " |" for row in rows) + "\n" + legend


def table(contenders: list[Contender], baseline: Contender) -> str:
    """The Markdown table of every contender, medians and ranges over the rounds."""
    header = [
        "renderer",
        "seconds",
        "relMSE",
        "relMSE w/o light",
        "RMSE",
        "s x relMSE",
        f"speed vs {baseline.label}",
        f"efficiency vs {baseline.label}",
    ]
    rows = [header, ["---"] * len(header)]
    by_round = {run.round: run for run in baseline.runs}
    for contender in contenders:
        runs = contender.runs
        rows.append(
            [
                contender.label,
                _summary([r.seconds for r in runs]),
                _summary([r.relmse for r in runs]),
                _summary([r.relmse_unlit for r in runs]),
                _summary([r.rmse for r in runs]),
                _summary([r.cost for r in runs]),
                _summary([by_round[r.round].seconds / r.seconds for r in runs]),
                _summary([by_round[r.round].cost / r.cost for r in runs]),
            ]
        )
    legend = (
        f"median [min, max] over the rounds; speed: {baseline.label}'s seconds / this "
        f"one's, efficiency: {baseline.label}'s s x relMSE / this one's, in the same round "
        f"(above 1: better than {baseline.label})"
    )
    return _markdown(rows, legend)


def process_table(contenders: list[Contender], baselines: dict[str, Contender], reference: np.ndarray) -> str:
    """The Markdown table of the whole processes against ``baselines`` (name -> contender):
    seconds x relMSE over each baseline's in the same round, and each channel's mean over the
    reference's; medians and ranges over the rounds."""
    header = [
        "process",
        "seconds",
        "relMSE",
        "s x relMSE",
        *(f"s x relMSE / {name}'s" for name in baselines),
        "mean / reference's (R, G, B)",
    ]
    rows = [header, ["---"] * len(header)]
    reference_means = reference.reshape(-1, 3).mean(axis=0, dtype=np.float64)
    for contender in contenders:
        runs = contender.runs
        ratios = []
        for baseline in baselines.values():
            by_round = {run.round: run for run in baseline.runs}
            ratios.append(_summary([r.cost / by_round[r.round].cost for r in runs]))
        means = [r.image.reshape(-1, 3).mean(axis=0, dtype=np.float64) / reference_means for r in runs]
        rows.append(
            [
                contender.label,
                _summary([r.seconds for r in runs]),
                _summary([r.relmse for r in runs]),
                _summary([r.cost for r in runs]),
                *ratios,
                ", ".join(f"{m:.4f}" for m in np.median(means, axis=0)),
            ]
        )
    legend = "; ".join(f"{name}: {baseline.label}" for name, baseline in baselines.items())
    legend += (
        "; median [min, max] over the rounds; below 1: less error for its time than the "
        "baseline's in the same round; channel means: the median over the rounds"
    )
    return _markdown(rows, legend)


def _mean_standard_error(run: Run, reference: np.ndarray, spp: int, reference_spp: int) -> np.ndarray:
    """(3,) standard error of the image mean of a ``reference_spp`` render, per channel.

    From an independent-sampler ``spp`` render: its per-pixel squared errors estimate each
    pixel's variance at ``spp``, which falls as 1 / samples.
    """
    squared = ((run.image.astype(np.float64) - reference) ** 2).reshape(-1, 3)
    return np.sqrt(squared.sum(axis=0)) / len(squared) * math.sqrt(spp / reference_spp)


def agreement(
    reference: np.ndarray,
    reference_spp: int | None,
    ptlab_reference: np.ndarray,
    ptlab_spp: int | None,
    unlit: np.ndarray,
    mitsuba_independent: Contender | None,
    ptlab_independent: Contender | None,
    spp: int,
    echo: Echo,
) -> bool:
    """Compare ptlab's reference with the reference; echo the verdict; True if they agree
    within noise (or if there is nothing to tell the noise by)."""
    errors = relative_squared_error(ptlab_reference, reference)
    ratio = ptlab_reference.reshape(-1, 3).mean(axis=0) / reference.reshape(-1, 3).mean(axis=0)
    echo(f"ptlab's reference / the reference, mean of each channel: {', '.join(f'{r:.5f}' for r in ratio)}")
    echo(
        f"relMSE of ptlab's reference against the reference: {errors.mean():.3g} "
        f"(without the light's pixels {errors[unlit].mean():.3g})"
    )
    if reference_spp is None or ptlab_spp is None or mitsuba_independent is None or ptlab_independent is None:
        echo("(no noise estimate: it needs both references' spp and the independent samplers)")
        return True
    # What their noise alone gives: each reference's relMSE is about that of its renderer's
    # independent spp-sample render times spp / its own spp (variance falls as 1 / samples;
    # a reference made with a QMC sampler is less noisy, so this is an upper estimate).
    noise = (
        statistics.median(r.relmse for r in mitsuba_independent.runs) * spp / reference_spp
        + statistics.median(r.relmse for r in ptlab_independent.runs) * spp / ptlab_spp
    )
    echo(f"relMSE that the references' noise alone gives: about {noise:.3g} or less")
    error = np.hypot(
        _mean_standard_error(mitsuba_independent.runs[-1], reference, spp, reference_spp),
        _mean_standard_error(ptlab_independent.runs[-1], reference, spp, ptlab_spp),
    )
    z = (ptlab_reference - reference).reshape(-1, 3).mean(axis=0) / error
    echo(f"difference of the means in standard errors (z), per channel: {', '.join(f'{v:+.1f}' for v in z)}")
    agree = bool(np.all(np.abs(z) < AGREEMENT_Z) and errors.mean() < 2 * noise)
    echo(
        "the references agree within noise"
        if agree
        else "the references DIFFER by more than noise: a bug in the scene translation or a renderer"
    )
    return agree


def write_csv(path: Path, contenders: list[Contender]) -> None:
    """Every run of every contender, one row each, written atomically."""

    def write(temporary: str) -> None:
        with open(temporary, "w", newline="") as out:
            rows = csv.writer(out)
            rows.writerow(["renderer", "round", "seed", "seconds", "relmse", "relmse_unlit", "rmse"])
            for contender in contenders:
                for r in contender.runs:
                    rows.writerow(
                        [
                            contender.label,
                            r.round,
                            r.seed,
                            f"{r.seconds:.4f}",
                            f"{r.relmse:.6g}",
                            f"{r.relmse_unlit:.6g}",
                            f"{r.rmse:.6g}",
                        ]
                    )

    write_atomically(path, write)


# ---------------------------------------------------------------------------------------------
# The contenders and the rounds


def mitsuba_contenders(mitsuba: MitsubaRenderer, options: ComparisonOptions) -> list[Contender]:
    """Mitsuba with every sampler and Russian roulette depth, in this process."""

    def contender(sampler: str, depth: int) -> Contender:
        return Contender(
            f"mitsuba {sampler} rr_depth {depth}",
            lambda seed: mitsuba.render(sampler, depth, options.spp, seed),
            lambda: mitsuba.render(sampler, depth, options.spp, WARM_UP_SEED),
        )

    return [contender(sampler, depth) for sampler, depth in options.configurations]


def ptlab_contenders(scene: Scene, options: ComparisonOptions) -> list[Contender]:
    """ptlab with every sampler, in this process (its workers are processes of their own),
    denoised with ``denoise``."""

    def contender(sampler: str) -> Contender:
        def render(seed: int, spp: int = options.spp) -> tuple[np.ndarray, float]:
            start = time.perf_counter()
            image = render_result(
                scene,
                spp=spp,
                res=options.res,
                seed=seed,
                workers=options.workers,
                strategy=options.ptlab_strategy,
                sampler=sampler,
                denoise=options.denoise,
            ).image
            return image, time.perf_counter() - start

        label = f"ptlab {sampler} {options.ptlab_strategy}" + (" --denoise" if options.denoise else "")
        return Contender(label, render, lambda: render(WARM_UP_SEED, spp=1))

    return [contender(sampler) for sampler in options.ptlab_samplers]


def _executable(name: str) -> str | None:
    """The command ``name`` installed beside this Python, else on the PATH."""
    beside = Path(sys.executable).with_name(name)
    return str(beside) if beside.is_file() else shutil.which(name)


@dataclass
class Processes:
    """The whole-process contenders, and the two that the denoised race compares with.

    Attributes:
        ptlab: ``ptlab render`` at ``spp`` and, given a target, to it.
        mitsuba: ``mitsuba`` at ``spp`` (and at ``target_from_mitsuba_spp``) and, with
            ``denoise``, Mitsuba + OIDN at ``spp`` and ``mitsuba_denoise_spp``.
        baselines: "(a)": Mitsuba at ``target_from_mitsuba_spp`` (else ``spp``), if the
            mitsuba command is there; "(b)": Mitsuba + OIDN at ``mitsuba_denoise_spp``, with
            ``denoise``.
    """

    ptlab: list[Contender] = field(default_factory=list)
    mitsuba: list[Contender] = field(default_factory=list)
    baselines: dict[str, Contender] = field(default_factory=dict)


class ProcessCommands:
    """The whole processes, each a contender that writes an EXR of its own into ``folder``.

    Args:
        options: what to run (the scene, resolution, seeds, workers, strategy, variant).
        scene_xml: Mitsuba's scene file, written from the scene (``mitsuba_export``).
        folder: where the EXRs go.
    """

    def __init__(self, options: ComparisonOptions, scene_xml: Path, folder: Path):
        ptlab_command = _executable("ptlab")
        if ptlab_command is None:
            raise PtlabError("the ptlab command is not installed: pip install -e . from the repository")
        self.options, self.scene_xml, self.folder = options, scene_xml, folder
        self.ptlab_command = ptlab_command
        #: None where the mitsuba command is not installed.
        self.mitsuba_command = _executable("mitsuba")
        self._outputs = 0

    def _output(self) -> Path:
        self._outputs += 1
        return self.folder / f"process{self._outputs}.exr"

    def ptlab(self, target: float | None = None) -> Contender:
        """``ptlab render`` (its default sampler) at ``spp``, or to ``target``: then
        ``--target-error``, its first pass the command's default."""
        options = self.options
        width, height = options.res
        amount = ["--spp", str(options.spp)] if target is None else ["--target-error", repr(target)]
        denoise = ["--denoise"] if options.denoise else []
        workers = [] if options.workers is None else ["--workers", str(options.workers)]
        label = f"ptlab render {DEFAULT_SAMPLER} {options.ptlab_strategy}" + (
            f" {options.spp} spp" if target is None else f" to {target:.3g}"
        )
        return command_contender(
            f"{label}{' --denoise' if options.denoise else ''} [process]",
            lambda seed, out: [
                self.ptlab_command,
                "render",
                options.scene,
                "--res",
                f"{width}x{height}",
                *amount,
                *denoise,
                "--seed",
                str(seed),
                "--strategy",
                options.ptlab_strategy,
                "--quiet",
                "--out",
                str(out),
                *workers,
            ],
            self._output(),
        )

    def mitsuba(self, spp: int) -> Contender | None:
        """``mitsuba`` at ``spp`` (``process_sampler``, the scene file's rr_depth), or None
        without the command; its warm-up renders 1 spp (Dr.Jit's kernels do not depend on
        the spp or the seed: it compiles them once, into its disk cache)."""
        command, options = self.mitsuba_command, self.options
        if command is None:
            return None

        def argv(spp: int, seed: int, out: Path) -> list[str]:
            parameters = dict(spp=spp, seed=seed, sampler=options.process_sampler)
            defines = [part for name, value in parameters.items() for part in ("-D", f"{name}={value}")]
            return [command, "-m", options.variant, "-o", str(out), *defines, str(self.scene_xml)]

        return self._contender(f"{spp} spp", spp, argv)

    def mitsuba_denoised(self, spp: int) -> Contender:
        """Mitsuba + OIDN at ``spp``: ``python -m ptlab.measure.mitsuba_denoised``."""
        options = self.options

        def argv(spp: int, seed: int, out: Path) -> list[str]:
            return [
                *(sys.executable, "-m", "ptlab.measure.mitsuba_denoised", str(self.scene_xml), str(out)),
                *("--spp", str(spp), "--seed", str(seed), "--variant", options.variant),
                *("--sampler", options.process_sampler),
            ]

        return self._contender(f"{spp} spp + OIDN", spp, argv)

    def _contender(self, what: str, spp: int, argv: Callable[[int, int, Path], list[str]]) -> Contender:
        """The Mitsuba process ``argv(spp, seed, out)``, labelled with ``what`` it renders; its
        warm-up renders 1 spp."""
        label = f"mitsuba {self.options.process_sampler} rr_depth {MITSUBA_RR_DEPTH} {what} [process]"
        contender = command_contender(label, lambda seed, out: argv(spp, seed, out), self._output())
        warm_up = argv(1, WARM_UP_SEED, self.folder / "warm-up.exr")
        contender.warm_up = lambda: run_command(warm_up, f"{label} (warm-up)")
        return contender


def process_contenders(
    options: ComparisonOptions, commands: ProcessCommands, target: float | None
) -> Processes:
    """The whole processes (``Processes``), ptlab's target ``target`` (or None)."""
    processes = Processes(ptlab=[commands.ptlab()])
    if target is not None:
        processes.ptlab.append(commands.ptlab(target))
    baseline_spp = options.target_from_mitsuba_spp or options.spp
    for spp in dict.fromkeys([options.spp, baseline_spp]):
        if (plain := commands.mitsuba(spp)) is not None:
            processes.mitsuba.append(plain)
            if spp == baseline_spp:
                processes.baselines["(a)"] = plain
    if options.denoise:
        for spp in dict.fromkeys([options.spp, options.mitsuba_denoise_spp]):
            processes.mitsuba.append(denoised := commands.mitsuba_denoised(spp))
            if spp == options.mitsuba_denoise_spp:
                processes.baselines["(b)"] = denoised
    return processes


def mitsuba_error(
    commands: ProcessCommands,
    options: ComparisonOptions,
    reference: np.ndarray,
    unlit: np.ndarray,
    echo: Echo,
) -> float:
    """E_m: the median true relMSE of ``repeat`` renders by Mitsuba's whole process at
    ``target_from_mitsuba_spp``, with seeds that the rounds do not use."""
    assert options.target_from_mitsuba_spp is not None
    spp = options.target_from_mitsuba_spp
    contender = commands.mitsuba(spp)
    if contender is None:
        raise PtlabError(
            f"--target-from-mitsuba-spp {spp}: no mitsuba command beside this Python or on the PATH"
        )
    assert contender.warm_up is not None
    contender.warm_up()
    for round_ in range(options.repeat):
        run = measure(contender, round_, options.seed + round_ + CALIBRATION_SEED_OFFSET, reference, unlit)
        echo(f"target: {contender.label} {run.seconds:.2f} s, relMSE {run.relmse:.4g}")
    error = statistics.median(run.relmse for run in contender.runs)
    echo(f"target: {error:.4g}, the median of Mitsuba's {len(contender.runs)} renders at {spp} spp")
    return error


def warm_up(contenders: list[Contender], mitsuba: MitsubaRenderer, echo: Echo) -> None:
    """One untimed render of each contender that has a warm-up; say what Dr.Jit compiled."""
    for contender in contenders:
        if contender.warm_up is None:
            continue
        mitsuba.kernels()
        start = time.perf_counter()
        contender.warm_up()
        seconds = time.perf_counter() - start
        kernels = mitsuba.kernels()
        echo(f"warm-up {contender.label}: {seconds:.1f} s" + (f"; {kernels}" if kernels.launched else ""))


def run_rounds(
    order: list[Contender], options: ComparisonOptions, reference: np.ndarray, unlit: np.ndarray, echo: Echo
) -> None:
    """Every contender once per round, a new seed each round, every other round backwards."""
    for round_ in range(options.repeat):
        seed = options.seed + round_
        for contender in order if round_ % 2 == 0 else order[::-1]:
            run = measure(contender, round_, seed, reference, unlit)
            echo(
                f"round {round_ + 1}/{options.repeat}  {contender.label:42} {run.seconds:7.2f} s  "
                f"relMSE {run.relmse:.4g}"
            )


def _load_average() -> str:
    return ", ".join(f"{v:.2f}" for v in os.getloadavg())


def _read_reference(path: str | None, res: tuple[int, int]) -> tuple[np.ndarray, int | None] | None:
    """The EXR at ``path`` (checked to be ``res``) and the spp its metadata gives, if it gives
    an integer; None if there is no path."""
    if path is None:
        return None
    image = load_reference(path, res)
    try:
        spp = int(read_image(path)[1]["spp"])
    except (KeyError, TypeError, ValueError):
        spp = None
    return image, spp


# ---------------------------------------------------------------------------------------------
# The whole comparison


def compare(options: ComparisonOptions, echo: Echo) -> bool:
    """The whole comparison, said line by line through ``echo``; True if it ran and the
    references agree (or there is only one).

    Raises ``PtlabError`` for what the user can fix (an option, a scene Mitsuba cannot
    express, Mitsuba missing) and ``RenderError`` when a renderer or a command fails.
    """
    options.check()
    with tempfile.TemporaryDirectory(prefix="against-mitsuba-") as folder:
        return _compare_in(options, Path(folder), echo)


def _compare_in(options: ComparisonOptions, folder: Path, echo: Echo) -> bool:
    """``compare``, with its scene files and EXRs in ``folder``."""
    scene = load_scene(options.scene)
    width, height = res = options.res
    given = _read_reference(options.reference, res)
    ptlab_given = _read_reference(options.ptlab_reference, res)
    mi, dr = import_mitsuba(options.variant)
    mitsuba = MitsubaRenderer(
        mi,
        dr,
        write_mitsuba_scene(scene, folder, width, height),
        [*(options.configurations if options.in_process else []), ("independent", MITSUBA_RR_DEPTH)],
    )
    echo(f"{scene.summary()}; {width}x{height}, {options.spp} spp, {options.repeat} rounds")
    echo(
        f"mitsuba {mi.__version__} ({options.variant}, {dr.thread_count()} threads), ptlab with "
        f"{options.workers or 'one per core'} workers; load average {_load_average()} "
        f"on {os.cpu_count()} cores"
    )
    reference, reference_spp = (
        mitsuba_reference(mitsuba, scene, res, options.reference_spp, options.seed, default_cache_dir(), echo)
        if given is None
        else given
    )
    unlit = reference.max(axis=-1) <= LIGHT_THRESHOLD
    echo(f"{(~unlit).sum()} of {unlit.size} pixels see the light")

    mitsuba_runs, ptlab_runs = (
        (mitsuba_contenders(mitsuba, options), ptlab_contenders(scene, options))
        if options.in_process
        else ([], [])
    )
    processes = Processes()
    if options.time_processes:
        commands = ProcessCommands(options, mitsuba.scene_xml, folder)
        if commands.mitsuba_command is None:
            echo("no mitsuba command beside this Python or on the PATH: its process is not timed")
        target = options.ptlab_target_error
        if options.target_from_mitsuba_spp is not None:
            target = mitsuba_error(commands, options, reference, unlit, echo)
        processes = process_contenders(options, commands, target)
    warm_up(mitsuba_runs + ptlab_runs + processes.mitsuba, mitsuba, echo)
    run_rounds(
        interleave(mitsuba_runs + processes.mitsuba, ptlab_runs + processes.ptlab),
        options,
        reference,
        unlit,
        echo,
    )
    echo(f"timed Mitsuba renders in this process: {mitsuba.kernels()}")
    echo(f"load average after: {_load_average()}")

    contenders = mitsuba_runs + ptlab_runs + processes.ptlab + processes.mitsuba
    baseline = next(
        (c for c in ptlab_runs if c.label.startswith(f"ptlab {DEFAULT_SAMPLER} ")),
        (ptlab_runs + processes.ptlab)[0],
    )
    echo(f"\n{table(contenders, baseline)}\n")
    if options.denoise or options.target_from_mitsuba_spp is not None:
        echo(f"{process_table(processes.ptlab + processes.mitsuba, processes.baselines, reference)}\n")
    if options.csv:
        write_csv(Path(options.csv), contenders)
        echo(f"wrote {Path(options.csv).resolve()}")
    if ptlab_given is None:
        return True
    ptlab_reference, ptlab_reference_spp = ptlab_given

    def independent(runs: list[Contender], renderer: str) -> Contender | None:
        return next((c for c in runs if c.label.startswith(f"{renderer} independent ")), None)

    return agreement(
        reference,
        reference_spp,
        ptlab_reference,
        options.ptlab_reference_spp or ptlab_reference_spp,
        unlit,
        independent(mitsuba_runs, "mitsuba"),
        independent(ptlab_runs, "ptlab"),
        options.spp,
        echo,
    )
