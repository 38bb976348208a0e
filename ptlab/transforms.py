"""Transforms that place a mesh in a scene: scale, rotate, translate, or a 4 x 4 matrix.

An affine transform maps a point p to A p + t (A: 3 x 3, t: 3), the matrix [[A, t], [0 0 0
1]] acting on (p, 1) (pbrt-v4 section 3.9). A scene file composes it as pbrt-v4 and Mitsuba 3
do: ``scale`` first, then each ``rotate`` in the order given, then ``translate`` (Mitsuba's
``<transform>`` left-multiplies each step onto the ones before it; pbrt's ``Translate``,
``Rotate``, ``Scale`` statements, in that order, apply to the object in reverse), or gives the
whole matrix.

What a transform does to a triangle mesh:

- corners p -> A p + t;
- shading normals n -> A^-T n, renormalised (the inverse transpose keeps a normal
  perpendicular to the transformed surface, pbrt-v4 section 3.10.3);
- where det A < 0 (a mirror), (A e1) x (A e2) = det A A^-T (e1 x e2) turns each triangle's
  winding normal to the other side of the surface: two corners of every triangle swap (with
  their uv and normals), so that the front face, which emits light and is the outside of a
  glass, stays on the side it was (pbrt-v4 flips the normal of such a mesh instead,
  ``transformSwapsHandedness``, section 3.10.7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Transform:
    """p -> ``linear`` p + ``offset``.

    Attributes:
        linear: (3, 3) float64 A, invertible.
        offset: (3,) float64 t.
    """

    linear: np.ndarray
    offset: np.ndarray

    @classmethod
    def identity(cls) -> Transform:
        return cls(np.eye(3), np.zeros(3))

    @classmethod
    def from_matrix(cls, matrix: np.ndarray) -> Transform:
        """From a (4, 4) row-major affine matrix [[A, t], [0, 0, 0, 1]]."""
        matrix = np.asarray(matrix, dtype=np.float64)
        return cls(matrix[:3, :3].copy(), matrix[:3, 3].copy())

    @classmethod
    def compose(cls, scale: np.ndarray, rotations: list[np.ndarray], translate: np.ndarray) -> Transform:
        """Scale by ``scale`` (3,) first, then rotate by each (3, 3) of ``rotations`` in turn,
        then translate by ``translate`` (3,)."""
        linear = np.diag(np.asarray(scale, dtype=np.float64))
        for rotation in rotations:
            linear = rotation @ linear
        return cls(linear, np.asarray(translate, dtype=np.float64))

    @property
    def is_identity(self) -> bool:
        return bool((self.linear == np.eye(3)).all() and not self.offset.any())

    @property
    def swaps_handedness(self) -> bool:
        """det A < 0: a mirror, which turns windings over."""
        return bool(np.linalg.slogdet(self.linear)[0] < 0)  # (the sign alone: no overflow)

    def points(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) ``points`` transformed: A p + t."""
        diagonal = np.diag(self.linear)
        # (A scale alone: each coordinate times its factor, exactly what a mesh's `scale`
        # gave before transforms, and a third of a matrix product's work.)
        scale_alone = (self.linear == np.diag(diagonal)).all()
        moved = points * diagonal if scale_alone else points @ self.linear.T
        return moved + self.offset if self.offset.any() else moved

    def normals(self, normals: np.ndarray) -> np.ndarray:
        """(..., 3) unit ``normals`` transformed: A^-T n, renormalised (pbrt-v4 section 3.10.3)."""
        # (A^-T n as a row vector is n^T A^-1.)
        turned = normals @ np.linalg.inv(self.linear)
        return turned / np.linalg.norm(turned, axis=-1, keepdims=True)

    def mesh(
        self, triangles: np.ndarray, uv: np.ndarray | None, normals: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """A mesh transformed: (T, 3, 3) ``triangles``, their (T, 3, 2) ``uv`` and (T, 3, 3)
        corner ``normals`` (either may be None), with two corners of each triangle swapped
        where the transform is a mirror (module docstring)."""
        with np.errstate(over="ignore", invalid="ignore"):  # (the caller checks the size)
            triangles = self.points(triangles)
            if normals is not None:
                normals = self.normals(normals)
        if self.swaps_handedness:
            order = [0, 2, 1]
            triangles = triangles[:, order]
            uv = None if uv is None else uv[:, order]
            normals = None if normals is None else normals[:, order]
        return triangles, uv, normals


def rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    """(3, 3) the rotation by ``degrees`` about ``axis`` (3,), any length but 0:
    counter-clockwise seen from the axis' tip (right-handed), Rodrigues' formula
    R = cos(theta) I + sin(theta) [a]x + (1 - cos(theta)) a a^T (pbrt-v4 section 3.9.7)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.abs(a).max()  # (first: the square of a tiny or huge axis would underflow or overflow)
    a = a / np.linalg.norm(a)
    theta = math.radians(degrees)
    cross = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return math.cos(theta) * np.eye(3) + math.sin(theta) * cross + (1 - math.cos(theta)) * np.outer(a, a)
