"""``ptlab bench --tail``: how much of a render goes to bounces with few live paths.

A batch of paths dwindles as paths end. Every bounce pays NumPy's fixed costs (some hundred
calls, about a millisecond) whatever the number of paths, so once fewer than about 10k paths
live, a bounce costs more per path, and below 1000 it is nearly all overhead. The path
tracer keeps its batches full ("path regeneration": new camera paths join a batch as old
ones end, ``ptlab.integrators.path.trace_paths``) and the scheduler gives a worker several
jobs at once (``ptlab.rendering.jobs.job_groups``), so that a batch runs dry once per group
of jobs rather than once per job.

This module measures what that buys. It renders the Cornell box in this process (one
worker) with the batches kept full and, alternately, the way it was done before: a batch per
job, left to run dry. Each bounce is timed (from one ``surface_hit`` to the next, within one
call of ``trace_paths``) with the number of paths it started with; the table gives, per
layout, the wall time, the share of it in bounces with fewer than 1k, 10k and 30k paths, and
the time per path in bounces of more than 30k paths.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import ptlab.integrators.path as path_module
import ptlab.rendering.jobs as jobs_module
from ptlab.integrators import INTEGRATORS
from ptlab.rendering import render_result
from ptlab.scene import Scene

#: The live-path counts below which the table gives the share of the render's time.
SMALL_BATCHES = (1_000, 10_000, 30_000)


@dataclass
class BounceLog:
    """(paths, seconds) of every bounce timed while ``timing_bounces`` was on."""

    bounces: list[tuple[int, float]] = field(default_factory=list)

    def seconds_below(self, paths: int) -> float:
        """Time in bounces that started with fewer than ``paths`` live paths."""
        return sum(seconds for count, seconds in self.bounces if count < paths)

    def seconds_per_path_above(self, paths: int) -> float:
        """Time per path in bounces of ``paths`` or more live paths."""
        big = [(count, seconds) for count, seconds in self.bounces if count >= paths]
        return sum(seconds for _, seconds in big) / max(sum(count for count, _ in big), 1)


@contextmanager
def timing_bounces() -> Iterator[BounceLog]:
    """Time each bounce of ``trace_paths`` in this process, into the ``BounceLog`` yielded.

    A bounce runs from one call of ``surface_hit`` to the next (the last from its call to
    the end of ``trace_paths``), so it includes the refill of the batch before its rays.
    """
    log = BounceLog()
    started: list[tuple[int, float]] = []  # (paths, time) of the bounce under way
    surface_hit, trace_paths = path_module.surface_hit, path_module.trace_paths

    def timed_surface_hit(scene, paths, hits):
        now = time.perf_counter()
        if started:
            log.bounces.append((started[0][0], now - started[0][1]))
        started[:] = [(len(paths.pixel), now)]
        return surface_hit(scene, paths, hits)

    def timed_trace_paths(*args, **kwargs):
        started.clear()
        try:
            return trace_paths(*args, **kwargs)
        finally:
            if started:
                log.bounces.append((started[0][0], time.perf_counter() - started[0][1]))

    # (A measurement's instruments: the path loop's module's ``surface_hit``, and the path
    # integrator of the registry, each put back when the block ends.)
    path_integrator = INTEGRATORS["path"]
    path_module.surface_hit = timed_surface_hit
    INTEGRATORS["path"] = replace(path_integrator, trace=timed_trace_paths)
    try:
        yield log
    finally:
        path_module.surface_hit = surface_hit
        INTEGRATORS["path"] = path_integrator


@contextmanager
def batches_left_to_run_dry() -> Iterator[None]:
    """Render as before path regeneration: a job per group, all its paths in one batch."""
    saved = path_module.BATCH_PATHS, path_module.REFILL_BELOW, jobs_module.MAX_GROUP_SAMPLES
    path_module.BATCH_PATHS = path_module.REFILL_BELOW = 1 << 62
    jobs_module.MAX_GROUP_SAMPLES = 1
    try:
        yield
    finally:
        path_module.BATCH_PATHS, path_module.REFILL_BELOW, jobs_module.MAX_GROUP_SAMPLES = saved


def run_tail(
    scene: Scene, options: dict, res: int, spp: int, repeat: int, backend: str, echo=print
) -> dict[str, list[tuple[float, BounceLog]]]:
    """Render ``scene`` ``repeat`` times with each layout, alternately; print the table and
    the ratio of their times; return {layout: [(seconds, log)]}."""
    layouts = {"kept full": contextmanager(lambda: iter([None])), "run dry": batches_left_to_run_dry}
    runs: dict[str, list[tuple[float, BounceLog]]] = {name: [] for name in layouts}
    render_result(scene, spp=1, res=32, backend=backend, workers=1)  # (warm-up)
    for _ in range(repeat):
        for name, layout in layouts.items():
            with layout(), timing_bounces() as log:
                seconds = render_result(
                    scene, spp=spp, res=res, backend=backend, workers=1, **options
                ).seconds
            runs[name].append((seconds, log))
    echo(
        f"{'batches':10} {'seconds':>8} {'bounces':>8} "
        + " ".join(f"{'<' + format(n, ',') + ' paths':>13}" for n in SMALL_BATCHES)
        + f" {'us/path >30k':>13}"
    )
    for name, results in runs.items():
        seconds, log = min(results, key=lambda result: result[0])  # (the least disturbed)
        shares = " ".join(f"{log.seconds_below(n) / seconds:13.1%}" for n in SMALL_BATCHES)
        echo(
            f"{name:10} {seconds:8.2f} {len(log.bounces):8d} {shares} "
            f"{log.seconds_per_path_above(SMALL_BATCHES[-1]) * 1e6:13.3f}"
        )
    ratios = [full[0] / dry[0] for full, dry in zip(runs["kept full"], runs["run dry"], strict=True)]
    echo(
        f"time kept full / run dry: median {statistics.median(ratios):.3f} "
        f"(from {min(ratios):.3f} to {max(ratios):.3f}, {repeat} pairs)"
    )
    return runs
