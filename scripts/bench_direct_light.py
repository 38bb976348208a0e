"""CPU milliseconds of ``direct_light`` on one batch of 2^18 Cornell-box first hits, with
``"nee"`` and ``"mis"`` (median of 15 calls each; not run in CI).

    PYTHONPATH=/tmp/before python scripts/bench_direct_light.py   # a checkout before a change
    python scripts/bench_direct_light.py                          # and after it; alternate them

CPU time (``time.process_time``), not wall time, so that other work on the machine disturbs
it less (docs/performance.md).
"""

from __future__ import annotations

import time

import numpy as np

import ptlab
from ptlab.accel import make_accelerator
from ptlab.camera import generate_rays
from ptlab.integrators.path import PathSettings, direct_light
from ptlab.integrators.wavefront import Paths, surface_hit
from ptlab.samplers import BounceUniforms, make_sampler

WIDTH = HEIGHT = 512
N = 1 << 18


def main() -> None:
    scene = ptlab.load_scene("cornell-box")
    accel = make_accelerator(scene.triangles, "embree")
    pixel = np.arange(N) % (WIDTH * HEIGHT)
    sampler = make_sampler("sobol", 0)
    keys = sampler.keys(pixel, np.zeros(N, dtype=np.int64))
    jitter = sampler.get(keys, BounceUniforms.PIXEL, 2)
    origins, dirs = generate_rays(scene.camera, WIDTH, HEIGHT, pixel % WIDTH, pixel // WIDTH, jitter)
    paths = Paths.camera(origins, dirs, pixel, keys)
    hit = surface_hit(scene, paths, accel.intersect(paths.origins, paths.dirs))
    u = BounceUniforms(sampler, hit.sample, 0).light()
    film = np.zeros((WIDTH * HEIGHT, 3))
    for strategy in ("nee", "mis"):
        settings = PathSettings(strategy=strategy)
        seconds = []
        for _ in range(15):
            start = time.process_time()
            direct_light(film, scene, accel, hit, u, settings)
            seconds.append(time.process_time() - start)
        print(f"{strategy} {np.median(seconds) * 1e3:.1f} ms", end="  ")
    print()


if __name__ == "__main__":
    main()
