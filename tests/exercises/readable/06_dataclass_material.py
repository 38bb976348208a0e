"""A right answer an honest student could write, whose material is a ``@dataclass`` with a
default factory and a ``__post_init__``."""

import math
from dataclasses import dataclass, field

import numpy as np

from ptlab.materials import Material
from ptlab.sampling import to_world
from ptlab.vectors import dot


def _cosine_local(u):
    r = np.sqrt(u[:, 0])
    phi = 2.0 * math.pi * u[:, 1]
    z = np.sqrt(np.maximum(0.0, 1.0 - u[:, 0]))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


@dataclass
class Lambertian(Material):
    albedo: np.ndarray = field(default_factory=lambda: np.full(3, 0.8, dtype=np.float32))

    def __post_init__(self):
        self.albedo = np.asarray(self.albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        up = (dot(wo, n) > 0) & (dot(wi, n) > 0)
        return (up / math.pi)[:, None].astype(wi.dtype) * self.albedo.astype(wi.dtype)

    def sample(self, wo, n, u):
        return to_world(_cosine_local(u.astype(n.dtype, copy=False)), n).astype(n.dtype, copy=False)

    def pdf(self, wo, wi, n):
        c = dot(wi, n)
        return np.where((dot(wo, n) > 0) & (c > 0), c / math.pi, 0.0).astype(wi.dtype, copy=False)
