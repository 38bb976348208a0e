"""A trivial chapter-1 answer: every ray starts at the eye and goes along forward, whatever
its pixel. It does none of the work (no image plane, no field of view, no pixel mapping),
yet the centre ray is forward and every direction has length 1."""

import numpy as np


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    n = len(pixel_x)
    origins = np.tile(np.asarray(camera.position, dtype=np.float32), (n, 1))
    dirs = np.tile(np.asarray(camera.forward, dtype=np.float32), (n, 1))
    return origins, dirs
