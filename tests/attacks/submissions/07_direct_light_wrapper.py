"""An attack of the first round: ``direct_light`` whose body is one call of the library's
``ptlab.integrators.path.direct_light`` (under another name, with the settings the library's
needs); the other functions are not written. It earned 2 points."""

from ptlab.integrators import path
from ptlab.integrators.path import PathSettings


def direct_light(film, scene, accel, hit, u):
    return path.direct_light(film, scene, accel, hit, u, PathSettings(strategy="nee"))


def russian_roulette(throughput, p_rr, u):
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    raise NotImplementedError("scatter")


def trace_paths(film, scene, accel, paths, sampler, settings):
    raise NotImplementedError("trace_paths")
