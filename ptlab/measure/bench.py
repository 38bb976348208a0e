"""``ptlab bench``: how fast the renderer is, and how accurate for the time it takes.

Speed (the default): it renders the Cornell box with each backend and with two estimators
(the homework's, uniform hemisphere sampling with Russian roulette 0.8; and ptlab's
default, cosine sampling with throughput-based roulette), with one worker (this process)
and with one worker process per core, and prints wall seconds, camera samples per second,
rays per second, rays per path and the shares of the workers' time spent inside the ray
queries and inside the sampler (timed around every call, divided by wall time x workers).
The parallel speed-up over one worker is measured in the same run.

Accuracy (``--accuracy``): it renders the Cornell box with each sampler at the same spp and
compares every image with a high-spp reference (``ptlab.measure.converge``'s, cached):
relMSE, seconds, their product (lower is better: the error an estimator reaches per unit of
time), and the sampler's share of the time. Renders of the samplers alternate, ``repeat``
times over, each repeat with another seed, so that a drift of the machine's speed falls on
all of them alike; the figures are the median and the range over the repeats.
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass
from typing import Any

import numpy as np

from ptlab.measure.metrics import relmse
from ptlab.rendering import RenderOptions, render_result
from ptlab.scene import Scene
from ptlab.scene_file import load_scene

#: The render options (BSDF sampling and Russian roulette) of each estimator that ``ptlab
#: bench --estimator`` names; not ``ptlab.measure.converge.Estimator``s, which name an
#: integrator, a strategy and a sampler.
ESTIMATOR_OPTIONS: dict[str, dict[str, Any]] = {
    "homework": dict(sampling="uniform", rr=0.8),
    "default": dict(sampling=RenderOptions.sampling, rr=RenderOptions.rr),
}


@dataclass
class BenchRow:
    backend: str
    estimator: str
    sampler: str
    workers: int
    seconds: float
    samples_per_second: float
    rays_per_second: float
    rays_per_path: float
    query_share: float
    sampler_share: float
    mean: np.ndarray


def bench_one(
    scene: Scene,
    backend: str,
    estimator: str,
    workers: int,
    res: int,
    spp: int,
    seed: int = 0,
    sampler: str = RenderOptions.sampler,
) -> BenchRow:
    """Render once and time it: wall time includes starting the worker processes."""
    result = render_result(
        scene,
        spp=spp,
        res=res,
        seed=seed,
        backend=backend,
        workers=workers,
        sampler=sampler,
        **ESTIMATOR_OPTIONS[estimator],
    )
    paths = res * res * spp
    worker_seconds = result.seconds * workers
    return BenchRow(
        backend=backend,
        estimator=estimator,
        sampler=sampler,
        workers=workers,
        seconds=result.seconds,
        samples_per_second=result.samples_per_second,
        rays_per_second=result.rays / result.seconds,
        rays_per_path=result.rays / paths,
        query_share=result.query_seconds / worker_seconds,
        sampler_share=result.sampler_seconds / worker_seconds,
        mean=result.image.mean(axis=(0, 1)),
    )


def run_bench(
    backends: list[str],
    estimators: list[str],
    workers: list[int],
    res: int = 512,
    spp: int = 16,
    scene: str = "cornell-box",
    samplers: tuple[str, ...] = (RenderOptions.sampler,),
    echo=print,
) -> list[BenchRow]:
    """Run every backend x estimator x sampler x worker count, print a table, return the rows."""
    loaded = load_scene(scene)
    # A small warm-up render per backend in this process (where the one-worker rows run),
    # so that imports, building the accelerator and first calls are not timed.
    for backend in backends:
        render_result(loaded, spp=1, res=32, backend=backend, workers=1)
    echo(f"{loaded.summary()}; {res}x{res}, {spp} spp")
    echo(
        f"{'backend':8} {'estimator':9} {'sampler':11} {'workers':>7} {'seconds':>8} "
        f"{'Msamples/s':>10} {'Mrays/s':>8} {'rays/path':>9} {'in queries':>10} "
        f"{'in sampler':>10}  mean RGB"
    )
    rows = []
    for estimator in estimators:
        for backend in backends:
            for sampler in samplers:
                for count in workers:
                    row = bench_one(loaded, backend, estimator, count, res, spp, sampler=sampler)
                    rows.append(row)
                    echo(
                        f"{row.backend:8} {row.estimator:9} {row.sampler:11} {row.workers:7d} "
                        f"{row.seconds:8.2f} {row.samples_per_second / 1e6:10.3f} "
                        f"{row.rays_per_second / 1e6:8.2f} {row.rays_per_path:9.2f} "
                        f"{row.query_share:10.0%} {row.sampler_share:10.1%}  "
                        f"{np.array2string(row.mean, precision=4)}"
                    )
    by_key = {(r.backend, r.estimator, r.sampler, r.workers): r for r in rows}
    for estimator in estimators:
        for sampler in samplers:
            for count in workers:
                embree, numpy = (by_key.get((b, estimator, sampler, count)) for b in ("embree", "numpy"))
                if embree and numpy:
                    echo(
                        f"numpy / embree time, {estimator} estimator, {sampler}, {count} workers: "
                        f"{numpy.seconds / embree.seconds:.1f}x"
                    )
            for backend in backends:
                if len(workers) > 1 and (backend, estimator, sampler, 1) in by_key:
                    most = max(workers)
                    speedup = (
                        by_key[backend, estimator, sampler, 1].seconds
                        / by_key[backend, estimator, sampler, most].seconds
                    )
                    echo(
                        f"speed-up of {most} workers over 1, {backend}, {estimator}, {sampler}: "
                        f"{speedup:.2f}x"
                    )
    return rows


@dataclass
class AccuracyRow:
    """One sampler's renders in ``run_accuracy``: per repeat, seconds, relMSE and shares."""

    sampler: str
    seconds: list[float]
    relmse: list[float]
    sampler_share: list[float]

    @property
    def efficiency(self) -> list[float]:
        """seconds x relMSE per repeat (lower is better)."""
        return [s * e for s, e in zip(self.seconds, self.relmse, strict=True)]


def _median_range(values: list[float], digits: str) -> str:
    text = f"{statistics.median(values):{digits}}"
    if len(values) > 1:
        text += f" ({min(values):{digits}}-{max(values):{digits}})"
    return text


def run_accuracy(
    samplers: list[str],
    res: int = 256,
    spp: int = 64,
    repeat: int = 3,
    scene: str = "cornell-box",
    reference: str | None = None,
    reference_spp: int = 4096,
    workers: int = 1,
    cache_dir=None,
    echo=print,
    **render_options,
) -> list[AccuracyRow]:
    """Render ``scene`` with each sampler, ``repeat`` times alternately; print relMSE against
    a cached reference, seconds, their product and the sampler's share of the time."""
    from ptlab.measure.converge import load_reference, reference_image

    loaded = load_scene(scene)
    if reference is not None:
        reference_pixels = load_reference(reference, (res, res))
    else:
        reference_pixels = reference_image(
            loaded, (res, res), reference_spp, 0, cache_dir, echo, workers=None, **render_options
        )
    render_result(loaded, spp=1, res=32, workers=1)  # warm-up: imports, first calls
    rows = {name: AccuracyRow(name, [], [], []) for name in samplers}
    for k in range(repeat):
        for name in samplers:
            result = render_result(
                loaded, spp=spp, res=res, seed=k, workers=workers, sampler=name, **render_options
            )
            row = rows[name]
            row.seconds.append(result.seconds)
            row.relmse.append(relmse(result.image, reference_pixels))
            row.sampler_share.append(result.sampler_seconds / (result.seconds * workers))
    source = reference if reference is not None else f"{reference_spp} spp"
    echo(
        f"{loaded.summary()}; {res}x{res}, {spp} spp, {workers} worker(s), reference "
        f"{source}; median (range) over {repeat} seeds"
    )
    echo(f"{'sampler':11} {'relMSE':>24} {'seconds':>20} {'seconds x relMSE':>26} {'in sampler':>22}")
    for row in rows.values():
        echo(
            f"{row.sampler:11} {_median_range(row.relmse, '.5f'):>24} "
            f"{_median_range(row.seconds, '.2f'):>20} "
            f"{_median_range(row.efficiency, '.5f'):>26} "
            f"{_median_range(row.sampler_share, '.1%'):>22}"
        )
    return list(rows.values())
