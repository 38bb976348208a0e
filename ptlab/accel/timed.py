"""An accelerator wrapper that adds up the time spent in ray queries.

The renderer wraps every backend in it, so each render can say which share of its time
went to tracing rays (a good wavefront tracer spends over half of it inside Embree).
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ptlab.accel.base import Accelerator, Hits


class TimedAccelerator:
    """The ``Accelerator`` interface around another one, timing each query.

    Attributes:
        seconds: the summed wall time of all queries so far (from every thread).
    """

    def __init__(self, inner: Accelerator):
        self.inner = inner
        self.name = inner.name
        self.seconds = 0.0
        self._lock = threading.Lock()

    def __reduce__(self):
        # A lock cannot be pickled: a copy in another process times its own queries anew.
        return (TimedAccelerator, (self.inner,))

    def _add(self, start: float) -> None:
        with self._lock:
            self.seconds += time.perf_counter() - start

    def intersect(
        self,
        origins: np.ndarray,
        dirs: np.ndarray,
        tmin: float | np.ndarray = 0.0,
        tmax: float | np.ndarray = np.inf,
    ) -> Hits:
        start = time.perf_counter()
        try:
            return self.inner.intersect(origins, dirs, tmin, tmax)
        finally:
            self._add(start)

    def occluded(self, origins: np.ndarray, dirs: np.ndarray, tmax: float | np.ndarray) -> np.ndarray:
        start = time.perf_counter()
        try:
            return self.inner.occluded(origins, dirs, tmax)
        finally:
            self._add(start)
