"""A right answer an honest student could write, with ``np.vectorize`` of a function of its
own, and ``eval`` and ``exec`` in the ``__main__`` block, which grading never runs."""

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

import math


def _fresnel_one(ci, eta):
    s2 = (1.0 - ci * ci) / (eta * eta)
    if s2 >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - s2)
    a = (eta * ci - ct) / (eta * ci + ct)
    b = (ci - eta * ct) / (ci + eta * ct)
    return 0.5 * (a * a + b * b)


_vf = np.vectorize(_fresnel_one, otypes=[np.float64])


def reflect(wo, n):
    return 2.0 * dot(wo, n)[:, None] * n - wo


refract = _refract


def fresnel(cos_theta_i, eta):
    return _vf(cos_theta_i, eta).astype(np.result_type(cos_theta_i), copy=False)


if __name__ == "__main__":
    print(eval("fresnel(np.array([1.0]), 1.5)"))
    exec("print(reflect(np.eye(3), np.eye(3)))")
