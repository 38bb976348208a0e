"""A right chapter-1 answer written as a student would, not the library's code: it must
get full marks (and its progress is recorded)."""

import math

import numpy as np


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    half_height = math.tan(math.radians(camera.fov_y) / 2)
    half_width = half_height * width / height
    x = (2 * (pixel_x + u[:, 0]) / width - 1) * half_width
    y = (1 - 2 * (pixel_y + u[:, 1]) / height) * half_height
    dirs = camera.forward + x[:, None] * camera.right + y[:, None] * camera.up
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = np.tile(camera.position, (len(dirs), 1))
    return origins.astype(np.float32), dirs.astype(np.float32)
