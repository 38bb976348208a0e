"""Chapter 5, the library's own answer: ``split_costs``, ``best_split`` and ``child_order``
of ``ptlab.accel.numpy_bvh``."""

from ptlab.accel.numpy_bvh import best_split, child_order, split_costs

__all__ = ["best_split", "child_order", "split_costs"]
