"""Chapter 7, the library's own answer: the pieces of ``ptlab.integrators.path``.

``scatter`` and ``trace_paths`` are the library's functions as they are; ``direct_light`` and
``russian_roulette`` are thin adapters to the exercise's simpler signatures (the library's
take the path settings, which also serve MIS and pbrt-v4's throughput roulette).
"""

from types import SimpleNamespace

import numpy as np

from ptlab.integrators.path import PathSettings, scatter, trace_paths
from ptlab.integrators.path import direct_light as library_direct_light
from ptlab.integrators.path import russian_roulette as library_russian_roulette

__all__ = ["direct_light", "russian_roulette", "scatter", "trace_paths"]


def direct_light(film, scene, accel, hit, u) -> int:
    """``ptlab.integrators.path.direct_light`` with light sampling only (the homework's)."""
    return library_direct_light(film, scene, accel, hit, u, PathSettings(strategy="nee"))


def russian_roulette(throughput, p_rr, u) -> tuple[np.ndarray, np.ndarray]:
    """``ptlab.integrators.path.russian_roulette`` with a fixed survival probability."""
    hit = SimpleNamespace(throughput=throughput.copy(order="F"), depth=0)
    survive = library_russian_roulette(hit, PathSettings(rr=float(p_rr)), u)
    return survive, hit.throughput
