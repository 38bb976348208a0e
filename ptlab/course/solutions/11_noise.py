"""Chapter 11, the library's own answer: ``ptlab.rendering.adaptive``'s ``variance_of_mean``,
``allocation_weights`` and ``allocate``, which a render to a noise target calls."""

from ptlab.rendering.adaptive import allocate, allocation_weights, variance_of_mean

__all__ = ["allocate", "allocation_weights", "variance_of_mean"]
