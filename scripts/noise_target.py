"""Rendering to a noise target, measured: is the estimate honest, and what does adapting gain?

Not run in CI (it takes minutes). For each scene it renders a reference (``--reference-spp``,
another seed, with the two independent halves, so that its own relMSE is estimated and taken
off the measured errors), then, for each target and each of ``--repeat`` seeds:

* a render to the target (``render_result(target_error=E)``): its estimate, its true relMSE
  against the reference, true / E and estimate / true, its mean spp and seconds;
* alternately before or after it, a uniform render with the same samples per pixel on
  average (a plain render: one sobol sequence per pixel), timed the same way.

The gain at equal time is (uniform error x uniform seconds) / (adaptive error x adaptive
seconds): both errors fall as 1 / time, so this is how much sooner adapting reaches the same
error. Medians and the spread (min-max) over the seeds are printed per scene and target.

    python scripts/noise_target.py                                  # cornell-box, 128x128
    python scripts/noise_target.py --scene veach-mis --strategy mis --targets 0.02
    python scripts/noise_target.py --scene cornell-box --res 256 --targets 0.02,0.005
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from ptlab.measure.metrics import relmse
from ptlab.rendering import render_result


def timed(**options):
    start = time.perf_counter()
    result = render_result(**options)
    return result, time.perf_counter() - start


def measure(scene: str, strategy: str, res: int, targets: list[float], repeat: int, workers: int, spp: int):
    common = dict(scene=scene, res=res, strategy=strategy, workers=workers)
    reference, seconds = timed(spp=spp, seed=987_654, target_error=1e-12, max_spp=spp, **common)
    print(
        f"{scene} ({strategy}), {res}x{res}: reference {spp} spp in {seconds:.0f} s, its own relMSE "
        f"{reference.relmse_estimate:.2g} (taken off)"
    )
    for target in targets:
        rows = []
        spp_mean = None  # (a uniform render that goes first takes the last seed's mean spp)
        for seed in range(repeat):
            made = {}
            for kind in (
                ("adaptive", "uniform") if seed % 2 == 0 or spp_mean is None else ("uniform", "adaptive")
            ):
                if kind == "adaptive":
                    made[kind] = timed(seed=seed, target_error=target, **common)
                    spp_mean = made[kind][0].spp_mean
                else:
                    made[kind] = timed(seed=seed, spp=max(1, round(spp_mean)), **common)
            (adaptive, adaptive_seconds), (uniform, uniform_seconds) = made["adaptive"], made["uniform"]
            # (the uniform render may have a little more or fewer samples: its error scaled to
            # the adaptive render's samples, as 1 / samples)
            uniform_scale = uniform.samples / adaptive.samples
            true = relmse(adaptive.image, reference.image) - reference.relmse_estimate
            uniform_error = (
                relmse(uniform.image, reference.image) - reference.relmse_estimate
            ) * uniform_scale
            means = adaptive.image.reshape(-1, 3).mean(0) / reference.image.reshape(-1, 3).mean(0) - 1
            rows.append(
                dict(
                    estimate=adaptive.relmse_estimate,
                    true=true,
                    over_target=true / target,
                    honest=adaptive.relmse_estimate / true,
                    spp=adaptive.spp_mean,
                    seconds=adaptive_seconds,
                    equal_spp=uniform_error / true,
                    equal_time=uniform_error * uniform_seconds / uniform_scale / (true * adaptive_seconds),
                    bias=float(np.abs(means).max()),
                )
            )
            row = rows[-1]
            print(
                f"  E={target:g} seed {seed}: estimate {row['estimate']:.4g}, true {row['true']:.4g} "
                f"(true/E {row['over_target']:.2f}, estimate/true {row['honest']:.2f}), "
                f"{row['spp']:.1f} spp, {row['seconds']:.1f} s; uniform: error {uniform_error:.4g} "
                f"in {uniform_seconds:.1f} s; gain {row['equal_spp']:.2f}x at equal spp, "
                f"{row['equal_time']:.2f}x at equal time; channel means off by {100 * row['bias']:.2f}%",
                flush=True,
            )
        summary = ", ".join(
            f"{name} {statistics.median(r[name] for r in rows):.2f} "
            f"({min(r[name] for r in rows):.2f}-{max(r[name] for r in rows):.2f})"
            for name in ("over_target", "honest", "equal_spp", "equal_time")
        )
        print(f"  E={target:g}, median (spread) over {repeat} seeds: {summary}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="cornell-box")
    parser.add_argument("--strategy", default="nee")
    parser.add_argument("--res", type=int, default=128)
    parser.add_argument("--targets", default="0.02,0.005", help="comma-separated target relMSEs")
    parser.add_argument("--repeat", type=int, default=3, help="seeds per target")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--reference-spp", type=int, default=4096)
    args = parser.parse_args()
    targets = [float(t) for t in args.targets.split(",")]
    measure(args.scene, args.strategy, args.res, targets, args.repeat, args.workers, args.reference_spp)


if __name__ == "__main__":
    main()
