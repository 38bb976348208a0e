"""A right answer an honest student could write, with a callable object, a decorator of its
own (``functools.wraps``) and ``functools.lru_cache``."""

import functools

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

class _Mirror:
    """A callable object."""

    def __init__(self, k):
        self.k = k

    def __call__(self, wo, n):
        return self.k * dot(wo, n)[:, None] * n - wo


def _logged(f):
    import functools

    @functools.wraps(f)
    def inner(*args):
        return f(*args)

    return inner


reflect = _Mirror(2.0)
refract = _logged(_refract)


@functools.lru_cache(maxsize=None)
def _unity():
    return 1.0


@_logged
def fresnel(cos_theta_i, eta):
    return _unity() * _fresnel(cos_theta_i, eta)
