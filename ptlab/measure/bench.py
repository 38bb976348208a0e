"""``ptlab bench``: how fast the renderer is, measured, with the share spent in ray queries.

It renders the Cornell box with each backend and with two estimators (the homework's,
uniform hemisphere sampling with Russian roulette 0.8; and ptlab's default, cosine
sampling with throughput-based roulette), with one worker (this process) and with one
worker process per core, and prints wall seconds, camera samples per second, rays per
second, rays per path and the share of the workers' time spent inside the ray queries
(timed around every ``intersect`` / ``occluded`` call, divided by wall time x workers).
The parallel speed-up over one worker is measured in the same run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ptlab.rendering import render_result
from ptlab.scene import Scene, load_scene

ESTIMATORS = {
    "homework": dict(sampling="uniform", rr=0.8),
    "default": dict(sampling="cosine", rr="throughput"),
}


@dataclass
class BenchRow:
    backend: str
    estimator: str
    workers: int
    seconds: float
    samples_per_second: float
    rays_per_second: float
    rays_per_path: float
    query_share: float
    mean: np.ndarray


def bench_one(scene: Scene, backend: str, estimator: str, workers: int, res: int, spp: int,
              seed: int = 0) -> BenchRow:
    """Render once and time it: wall time includes starting the worker processes."""
    result = render_result(scene, spp=spp, res=res, seed=seed, backend=backend, workers=workers,
                           **ESTIMATORS[estimator])
    paths = res * res * spp
    return BenchRow(backend=backend, estimator=estimator, workers=workers, seconds=result.seconds,
                    samples_per_second=result.samples_per_second,
                    rays_per_second=result.rays / result.seconds, rays_per_path=result.rays / paths,
                    query_share=result.query_seconds / (result.seconds * workers),
                    mean=result.image.mean(axis=(0, 1)))


def run_bench(backends: list[str], estimators: list[str], workers: list[int], res: int = 512,
              spp: int = 16, scene: str = "cornell-box", echo=print) -> list[BenchRow]:
    """Run every backend x estimator x worker count, print a table, and return the rows."""
    loaded = load_scene(scene)
    # A small warm-up render so that imports and first-call costs are not timed.
    render_result(loaded, spp=1, res=32, backend=backends[0])
    echo(f"{loaded.summary()}; {res}x{res}, {spp} spp")
    echo(f"{'backend':8} {'estimator':9} {'workers':>7} {'seconds':>8} {'Msamples/s':>10} "
         f"{'Mrays/s':>8} {'rays/path':>9} {'in queries':>10}  mean RGB")
    rows = []
    for estimator in estimators:
        for backend in backends:
            for count in workers:
                row = bench_one(loaded, backend, estimator, count, res, spp)
                rows.append(row)
                echo(f"{row.backend:8} {row.estimator:9} {row.workers:7d} {row.seconds:8.2f} "
                     f"{row.samples_per_second / 1e6:10.3f} {row.rays_per_second / 1e6:8.2f} "
                     f"{row.rays_per_path:9.2f} "
                     f"{row.query_share:10.0%}  {np.array2string(row.mean, precision=4)}")
    by_key = {(r.backend, r.estimator, r.workers): r for r in rows}
    for estimator in estimators:
        for count in workers:
            if ("embree", estimator, count) in by_key and ("numpy", estimator, count) in by_key:
                ratio = (by_key["numpy", estimator, count].seconds
                         / by_key["embree", estimator, count].seconds)
                echo(f"numpy / embree time, {estimator} estimator, {count} workers: {ratio:.1f}x")
        for backend in backends:
            if len(workers) > 1 and (backend, estimator, 1) in by_key:
                most = max(workers)
                speedup = (by_key[backend, estimator, 1].seconds
                           / by_key[backend, estimator, most].seconds)
                echo(f"speed-up of {most} workers over 1, {backend}, {estimator}: {speedup:.2f}x")
    return rows
