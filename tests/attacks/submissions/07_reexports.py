"""An attack: chapter 7 with the library's own trace_paths imported under its name; the
other three functions are not written."""

from ptlab.integrators.path import trace_paths  # noqa: F401


def direct_light(film, scene, accel, hit, u):
    raise NotImplementedError("direct_light")


def russian_roulette(throughput, p_rr, u):
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    raise NotImplementedError("scatter")
