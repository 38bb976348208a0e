"""Chapter 1: cameras and primary rays.

The chapter's page: ``ptlab exercise docs 1`` (中文: ``--zh``).

Write ``generate_rays``: one ray from the eye through a point of each pixel. Check your work
with

    ptlab exercise check 1 01_cameras.py

Everything is whole arrays: ``pixel_x`` holds the x of every ray at once, and so on. Write
it with NumPy operations on those arrays, never a Python loop over rays (a loop would be
thousands of times slower, and the render check has a time limit).
"""

import math

import numpy as np


def generate_rays(camera, width, height, pixel_x, pixel_y, u):
    """Primary rays through jittered points of the given pixels.

    Args:
        camera: a ``ptlab.camera.Camera`` with ``position``, ``forward``, ``up``, ``right``
            (each a (3,) unit vector, except ``position``) and ``fov_y`` (vertical field of
            view in degrees).
        width, height: the image size in pixels.
        pixel_x, pixel_y: (N,) integer pixel coordinates; (0, 0) is the top-left pixel.
        u: (N, 2) uniforms in [0, 1): where in its pixel each ray goes (0.5, 0.5 is the
            pixel's centre).

    Returns:
        origins: (N, 3) float32, every row the camera's position.
        dirs: (N, 3) float32 unit directions.

    Hints:
        * The image plane is at distance 1 in front of the eye and spans tan(fov_y / 2) up
          and down; left-right it spans that times the aspect ratio width / height.
        * Turn the pixel point (pixel_x + u[:, 0], pixel_y + u[:, 1]) into image-plane
          coordinates x, y in [-1, 1] first; mind that pixel rows go *down* while y goes up.
        * A direction is forward + x * (scale * aspect) * right + y * scale * up,
          normalised. ``np.outer`` or broadcasting with ``[:, None]`` builds (N, 3) arrays.
    """
    raise NotImplementedError("generate_rays")
