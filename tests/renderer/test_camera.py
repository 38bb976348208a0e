"""The pinhole camera: orientation, field of view, jitter inside the pixel."""

from __future__ import annotations

import math

import numpy as np

from ptlab.camera import Camera, generate_rays


def test_centre_ray_looks_forward_and_edges_span_the_field_of_view():
    camera = Camera.look_at((0, 0, 0), (0, 0, 1), fov_y=90)
    # 2x2 image: the corner sample (0, 0) of pixel (0, 0) is the top-left image corner.
    x = np.array([0, 1, 0])
    y = np.array([0, 1, 0])
    u = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 1.0]], dtype=np.float32)
    origins, dirs = generate_rays(camera, 2, 2, x, y, u)
    np.testing.assert_allclose(origins, 0)
    corner = np.array([1.0, 1.0, 1.0]) / math.sqrt(3)  # +x is left, +y up (fov 90)
    np.testing.assert_allclose(dirs[0], corner, atol=1e-6)
    np.testing.assert_allclose(dirs[1], [-corner[0], -corner[1], corner[2]], atol=1e-6)
    np.testing.assert_allclose(dirs[2], [0, 0, 1], atol=1e-6)


def test_look_at_builds_an_orthonormal_right_handed_frame():
    camera = Camera.look_at((1, 2, 3), (4, 0, 8), up=(0, 1, 0), fov_y=40)
    frame = np.array([camera.right, camera.up, camera.forward])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(np.cross(camera.forward, camera.up), camera.right)
    assert camera.up[1] > 0
