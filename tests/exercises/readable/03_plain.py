"""A right answer an honest student could write: plain functions."""

import numpy as np
from ptlab.vectors import dot


def reflect(wo, n):
    c = dot(wo, n)
    return 2.0 * c[:, None] * n - wo


def refract(wo, n, eta):
    e = np.asarray(eta, dtype=np.float64)
    ci = dot(wo, n)
    s2 = (1.0 - ci * ci) / (e * e)
    ct = np.sqrt(np.clip(1.0 - s2, 0.0, None))
    ecol = e[:, None] if e.ndim == 1 else e
    return -wo / ecol + (ci / e - ct)[:, None] * n


def fresnel(cos_theta_i, eta):
    ci = cos_theta_i
    s2 = (1.0 - ci * ci) / (eta * eta)
    ct = np.sqrt(np.clip(1.0 - s2, 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (eta * ci - ct) / (eta * ci + ct)
        rp = (ci - eta * ct) / (ci + eta * ct)
        f = 0.5 * (rs * rs + rp * rp)
    return np.where(s2 >= 1.0, 1.0, f).astype(np.result_type(ci), copy=False)
