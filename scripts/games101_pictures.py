"""Draw the pictures of the Homework 5 and 6 scenes: the Whitted tracer's beside the path tracer's.

    python scripts/games101_pictures.py                  # writes docs/games101-hw5.png, -hw6.png
    python scripts/games101_pictures.py --res 120 --spp 16 --out /tmp

Each picture is two renders of one scene side by side, at the homework's 4:3 shape: on the
left ``--integrator whitted`` (the homework's tracer: the point lights' direct light, mirror
and glass; the sky only seen), on the right the path tracer with MIS (every light path; the
sky lights the scene too).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import ptlab
from ptlab.image import write_image

SCENES = ("games101-hw5", "games101-hw6")


def side_by_side(name: str, height: int, spp: int, whitted_spp: int) -> np.ndarray:
    """(height, 2 width, 3) the Whitted render of a scene beside its path-traced one."""
    res = (height * 4 // 3, height)
    whitted = ptlab.render(name, spp=whitted_spp, res=res, integrator="whitted")
    path = ptlab.render(name, spp=spp, res=res, strategy="mis")
    return np.concatenate([whitted, path], axis=1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--res", type=int, default=240, help="height of each render (default 240)")
    parser.add_argument(
        "--spp",
        type=int,
        default=256,
        help="samples per pixel of the path tracer (default 256; Whitted's: 16)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path(__file__).resolve().parent.parent / "docs",
        help="the folder to write into (default docs/)",
    )
    args = parser.parse_args(argv)
    if not 8 <= args.res <= 2048 or not 1 <= args.spp <= 65536:
        parser.error("--res must be from 8 to 2048 and --spp from 1 to 65536")
    args.out.mkdir(parents=True, exist_ok=True)
    for name in SCENES:
        path = args.out / f"{name}.png"
        write_image(path, side_by_side(name, args.res, args.spp, min(args.spp, 16)))
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
