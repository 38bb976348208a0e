"""Chapter 2, the library's own answer: ``ptlab.accel.triangle.ray_triangle``."""

from ptlab.accel.triangle import ray_triangle

__all__ = ["ray_triangle"]
