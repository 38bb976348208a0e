"""An attack: ``scatter`` sets ``survive[:] = False`` and returns nothing. The old grader
copied the change back into its own ``survive``, computed the library's bounce afterwards
from it (no path survived there either), and the two "matched": 2/2."""

import numpy as np


def direct_light(film, scene, accel, hit, u):
    raise NotImplementedError("direct_light")


def russian_roulette(throughput, p_rr, u):
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    survive[:] = False
    from ptlab.integrators.path import Paths
    empty = np.zeros((0, 3), np.float32)
    return Paths(empty, empty, empty, np.zeros(0, np.intp), np.zeros(0, bool), np.zeros(0, np.uint64))


def trace_paths(film, scene, accel, paths, sampler, settings):
    raise NotImplementedError("trace_paths")
