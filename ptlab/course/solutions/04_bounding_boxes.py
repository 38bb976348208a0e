"""Chapter 4, the library's own answer: ``ptlab.accel.numpy_bvh.slab_test``."""

from ptlab.accel.numpy_bvh import slab_test

__all__ = ["slab_test"]
