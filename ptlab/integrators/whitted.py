"""Whitted-style ray tracing (GAMES101 Homework 5), vectorised. (Stub: to be written.)"""

from __future__ import annotations

import numpy as np

from ptlab.accel.base import Accelerator
from ptlab.integrators.path import Paths, PathSettings
from ptlab.scene import Scene


def trace_whitted(film: np.ndarray, scene: Scene, accel: Accelerator, paths: Paths,
                  rng: np.random.Generator, settings: PathSettings) -> int:
    """Add the Whitted estimate of each camera ray into ``film``; return the rays traced."""
    raise NotImplementedError("whitted")
