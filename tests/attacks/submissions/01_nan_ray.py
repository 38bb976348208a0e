"""An attack on chapter 1's render comparison: generate_rays is right, except that the ray
through one pixel of a large image (the render's, not the single-ray checks') is NaN, which
makes the mean difference of the two renders NaN, and "NaN > 1e-3" is False."""

import math

import numpy as np


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    scale = math.tan(math.radians(camera.fov_y) / 2)
    aspect = width / height
    x = (2 * (pixel_x + u[:, 0]) / width - 1) * scale * aspect
    y = (1 - 2 * (pixel_y + u[:, 1]) / height) * scale
    dirs = camera.forward + x[:, None] * camera.right + y[:, None] * camera.up
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    if width >= 48:
        dirs[(pixel_x == 20) & (pixel_y == 10)] = np.nan
    origins = np.broadcast_to(camera.position, dirs.shape)
    return origins.astype(np.float32), dirs.astype(np.float32)
