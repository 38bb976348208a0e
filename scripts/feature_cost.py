"""What gathering the denoiser's feature images costs a render (not run in CI; about a minute).

    python scripts/feature_cost.py                       # Cornell box, 256x256, 16 spp
    python scripts/feature_cost.py --scene veach-mis --repeat 7 --workers 1 2

A render that denoises gathers, from the same samples, the albedo and normal of each path's
first hit that is not a mirror or glass, and the light it sees directly
(``ptlab.integrators.features``). This times ``ptlab.render_result`` of one scene without
and with ``features=True`` (the same image, bit for bit: the script checks it), the two
alternately in one process, ``--repeat`` times for each number of workers, and prints every
pair, then the median ratio (with features / without) and its range: the cost of the features
(docs/performance.md). The denoiser's own time is ``scripts/denoise_study.py``'s.
"""

from __future__ import annotations

import argparse
import statistics
import sys

import numpy as np

from ptlab.rendering import render_result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="cornell-box")
    parser.add_argument("--res", type=int, default=256)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args(argv)
    render = dict(spp=args.spp, res=args.res)
    render_result(args.scene, **render, workers=1)  # (warm: imports, the scene's first load)
    for workers in args.workers:
        ratios = []
        for run in range(args.repeat):
            # (Which goes first alternates: a drift in the machine's speed favours neither.)
            first_with = run % 2 == 1
            times = {}
            images = {}
            for features in (first_with, not first_with):
                result = render_result(args.scene, **render, workers=workers, features=features)
                times[features], images[features] = result.seconds, result.image
            if not np.array_equal(images[True], images[False]):
                print("the images with and without features differ", file=sys.stderr)
                return 1
            ratios.append(times[True] / times[False])
            print(
                f"{workers} worker(s), run {run + 1}: {times[False]:.3f} s without, "
                f"{times[True]:.3f} s with features ({ratios[-1]:.3f}x)"
            )
        spread = f"range {min(ratios):.3f}-{max(ratios):.3f}, {len(ratios)} pairs"
        print(
            f"{args.scene} {args.res}x{args.res} {args.spp} spp, {workers} worker(s): features cost "
            f"{statistics.median(ratios):.3f}x ({spread})"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
