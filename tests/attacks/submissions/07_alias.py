"""An attack: every function of chapter 7 is the library's, called through an alias made at
import (``_lib = path.trace_paths``), which neither an import of the name nor a wrapper of
the same name shows. It had full marks."""

from types import SimpleNamespace

from ptlab.integrators import path

_lib = SimpleNamespace(**{name: getattr(path, name) for name in
                          ("direct_light", "russian_roulette", "scatter", "trace_paths")})


def direct_light(film, scene, accel, hit, u):
    return _lib.direct_light(film, scene, accel, hit, u, path.PathSettings(strategy="nee"))


def russian_roulette(throughput, p_rr, u):
    hit = SimpleNamespace(throughput=throughput.copy(order="F"))
    survive = _lib.russian_roulette(hit, 0, path.PathSettings(rr=float(p_rr)), u)
    return survive, hit.throughput


def scatter(scene, hit, u, survive):
    return _lib.scatter(scene, hit, u, survive)


def trace_paths(film, scene, accel, paths, sampler, settings):
    return _lib.trace_paths(film, scene, accel, paths, sampler, settings)
