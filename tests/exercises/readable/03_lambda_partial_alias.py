"""A right answer an honest student could write, with a lambda, a ``functools.partial`` and
an alias at the top level."""

import numpy as np
from ptlab.vectors import dot


def _col(e):
    e = np.asarray(e, dtype=np.float64)
    return e[:, None] if e.ndim == 1 else e


def _refract(wo, n, eta):
    ci = dot(wo, n)
    s2 = (1.0 - ci * ci) / (np.asarray(eta) ** 2)
    ct = np.sqrt(np.clip(1.0 - s2, 0.0, None))
    return -wo / _col(eta) + (ci / eta - ct)[:, None] * n


def _fresnel(ci, eta):
    s2 = (1.0 - ci * ci) / (eta * eta)
    ct = np.sqrt(np.clip(1.0 - s2, 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        a = (eta * ci - ct) / (eta * ci + ct)
        b = (ci - eta * ct) / (ci + eta * ct)
    return np.where(s2 >= 1.0, 1.0, 0.5 * (a * a + b * b)).astype(np.result_type(ci), copy=False)

import functools

reflect = lambda wo, n: 2.0 * dot(wo, n)[:, None] * n - wo  # noqa: E731
refract = functools.partial(_refract)
fresnel = _fresnel  # a module-level alias
