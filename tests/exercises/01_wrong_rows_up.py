"""A typical wrong chapter-1 answer: pixel rows taken as going up (the image comes out
upside down), and u ignored (no jitter)."""

import math

import numpy as np

EXPECTED_FAILURES = ("field of view", "image orientation", "jittered rays", "render")


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    scale = math.tan(math.radians(camera.fov_y) / 2)
    x = (2.0 * (pixel_x + 0.5) / width - 1.0) * scale * width / height
    y = (2.0 * (pixel_y + 0.5) / height - 1.0) * scale
    dirs = camera.forward + x[:, None] * camera.right + y[:, None] * camera.up
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = np.tile(camera.position, (len(dirs), 1))
    return origins.astype(np.float32), dirs.astype(np.float32)
