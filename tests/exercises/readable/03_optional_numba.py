"""A right answer an honest student could write, with ``importlib.util.find_spec("numba")
is not None`` at the top level, to tell whether a package is installed."""

import importlib.util

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

#: numba, if installed, would speed this up; plain NumPy otherwise.
HAVE_NUMBA = importlib.util.find_spec("numba") is not None


def reflect(wo, n):
    return 2.0 * dot(wo, n)[:, None] * n - wo


def refract(wo, n, eta):
    return _refract(wo, n, eta)


def fresnel(cos_theta_i, eta):
    return _fresnel(cos_theta_i, eta)
