"""The pinhole camera and its primary rays.

A pinhole camera at ``position`` looks along ``forward``; the image plane sits at
distance 1, spanning ``tan(fov_y / 2)`` up and down (GAMES101 lecture 13, and Homework 5's
``Renderer::Render``). Pixel (0, 0) is the top-left corner. Each camera sample is jittered
uniformly inside its pixel, which is a box reconstruction filter.

The camera frame is right-handed: ``right = forward x up``. Looking along +z with +y up,
+x is therefore on the *left* of the image, as in the GAMES101 Cornell box (red wall, at
x = 556, on the left).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ptlab.vectors import cross, normalize, vec3


@dataclass(frozen=True)
class Camera:
    """A pinhole camera.

    Attributes:
        position: (3,) eye position.
        forward: (3,) unit viewing direction.
        up: (3,) unit vector, the image's up, orthogonal to ``forward``.
        fov_y: vertical field of view in degrees, 0 < fov_y < 180.
    """

    position: np.ndarray
    forward: np.ndarray
    up: np.ndarray
    fov_y: float

    @classmethod
    def look_at(cls, position, target, up=(0.0, 1.0, 0.0), fov_y: float = 40.0) -> Camera:
        """A camera at ``position`` looking at ``target``, ``up`` roughly up."""
        position = np.asarray(position, dtype=np.float64)
        forward = normalize(np.asarray(target, dtype=np.float64) - position)
        right = normalize(cross(forward, np.asarray(up, dtype=np.float64)))
        true_up = cross(right, forward)
        return cls(position=position, forward=forward, up=true_up, fov_y=float(fov_y))

    @property
    def right(self) -> np.ndarray:
        """(3,) unit vector pointing to the right of the image."""
        return cross(self.forward, self.up)


def generate_rays(
    camera: Camera, width: int, height: int, pixel_x: np.ndarray, pixel_y: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Primary rays through jittered points of the given pixels.

    Args:
        camera: the pinhole camera.
        width, height: image resolution in pixels.
        pixel_x, pixel_y: (N,) integer pixel coordinates, (0, 0) at the top left.
        u: (N, 2) uniforms in [0, 1): the sample's position inside its pixel.

    Returns:
        origins (N, 3) float32 (all the eye position) and unit directions (N, 3) float32.
    """
    scale = math.tan(math.radians(camera.fov_y) / 2)
    aspect = width / height
    # Image-plane coordinates in [-1, 1], y up (Homework 5's Renderer::Render).
    x = (2.0 * (pixel_x + u[:, 0]) / width - 1.0) * (scale * aspect)
    y = (1.0 - 2.0 * (pixel_y + u[:, 1]) / height) * scale
    f, r, up = camera.forward, camera.right, camera.up
    dirs = vec3(*(float(f[k]) + x * float(r[k]) + y * float(up[k]) for k in range(3)))
    dirs = normalize(dirs).astype(np.float32)
    origins = np.broadcast_to(camera.position.astype(np.float32), dirs.shape)
    return origins, dirs
