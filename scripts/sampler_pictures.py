"""Draw the picture of docs/samplers.md: one pixel's samples in one pair of dimensions, per sampler.

    python scripts/sampler_pictures.py                       # writes docs/samplers-points.png
    python scripts/sampler_pictures.py --spp 16 --out /tmp/points.png

Each panel shows the first ``--spp`` samples of one pixel in the light pair of the first
bounce (``ptlab.samplers.BounceUniforms``), with the grid of the strata a stratified pattern
fills: 8 x 8 cells for 64 samples, and for sobol the elementary intervals of one shape
(1/64 wide and 1 high, and 1/8 x 1/8) in which each interval holds exactly one point.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ptlab.samplers import SAMPLERS, BounceUniforms, make_sampler


def points(name: str, spp: int, pixel: int = 12_345, seed: int = 0) -> np.ndarray:
    """(spp, 2) the first ``spp`` samples of ``pixel`` in the first bounce's light pair."""
    sampler = make_sampler(name, seed, spp)
    keys = sampler.keys(np.full(spp, pixel), np.arange(spp))
    return BounceUniforms(sampler, keys, 0).light()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path(__file__).resolve().parent.parent / "docs" / "samplers-points.png",
        help="the PNG to write",
    )
    args = parser.parse_args(argv)
    if not 1 <= args.spp <= 4096:
        parser.error(f"--spp {args.spp}: must be from 1 to 4096")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    side = round(np.sqrt(args.spp))
    figure, axes = plt.subplots(1, len(SAMPLERS), figsize=(3.2 * len(SAMPLERS), 3.4), dpi=100)
    for axis, name in zip(axes, SAMPLERS, strict=True):
        u = points(name, args.spp)
        for k in range(1, side):
            axis.axvline(k / side, color="0.85", linewidth=0.6)
            axis.axhline(k / side, color="0.85", linewidth=0.6)
        axis.scatter(u[:, 0], u[:, 1], s=9, color="tab:blue", zorder=3)
        axis.set(
            xlim=(0, 1),
            ylim=(0, 1),
            aspect="equal",
            xticks=[0, 1],
            yticks=[0, 1],
            title=f"{name}, {args.spp} samples",
        )
    figure.tight_layout()
    figure.savefig(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
