"""Textures: a material parameter that varies over a surface, looked up by the hit's uv.

A mesh may carry texture coordinates ``uv`` at its vertices (an OBJ file's ``vt`` lines, or a
scene file's ``quad``); the renderer interpolates them at each hit with the hit's
barycentric coordinates, uv = (1 - b1 - b2) uv0 + b1 uv1 + b2 uv2 (GAMES101 lecture 9), and
a textured material turns them into its parameter for that hit (``Material.take``).

Only what ptlab's scenes need is here: the checkerboard of GAMES101 Homework 5's floor.
"""

from __future__ import annotations

import numpy as np

from ptlab.vectors import vec3


class Texture:
    """Base class: a colour for every point of a surface, given its (N, 2) uv."""

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        """(N, 3) float32 colours at texture coordinates ``uv`` (N, 2)."""
        raise NotImplementedError


class Checkerboard(Texture):
    """Two colours in squares of side 1 / (2 ``scale``) over uv (Homework 5's floor).

    The homework's ``evalDiffuseColor``: pattern = (frac(scale u) > 0.5) xor
    (frac(scale v) > 0.5), colour ``colours[1]`` where the pattern is 1 and ``colours[0]``
    where it is 0, so the square at the uv origin has ``colours[0]``. (frac is u - floor(u),
    so the squares continue past [0, 1]; the homework's ``fmodf`` mirrors them at 0.)

    Args:
        colours: (2, 3) the two colours.
        scale: pairs of squares per unit of u and of v (the homework's 5: ten squares across
            a quad whose uv runs from 0 to 1).
    """

    def __init__(self, colours, scale: float = 5.0):
        self.colours = np.asarray(colours, dtype=np.float64).reshape(2, 3)
        self.scale = float(scale)

    def __repr__(self) -> str:
        return f"Checkerboard(colours={self.colours.tolist()}, scale={self.scale!r})"

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        scaled = np.asarray(uv, dtype=np.float64) * self.scale
        odd = (scaled - np.floor(scaled)) > 0.5
        pattern = odd[:, 0] ^ odd[:, 1]
        a, b = self.colours.astype(np.float32)
        return vec3(*(np.where(pattern, b[c], a[c]) for c in range(3)))
