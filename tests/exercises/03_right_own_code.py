"""A right chapter-3 answer written as a student would from the homework: its refract and
fresnel work with etai / etat, taken here from eta = eta_t / eta_i (etai = 1, etat = eta),
in float64."""

import numpy as np


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def _column(x):
    return x[:, None] if np.ndim(x) else x


def reflect(wo, n):
    return (2 * _dot(wo, n))[:, None] * n - wo


def refract(wo, n, eta):
    ratio = 1 / np.asarray(eta, dtype=np.float64)  # the homework's etai / etat
    cos_i = _dot(wo, n)
    k = 1 - ratio * ratio * (1 - cos_i * cos_i)
    return -_column(ratio) * wo + (ratio * cos_i - np.sqrt(np.maximum(k, 0)))[:, None] * n


def fresnel(cos_theta_i, eta):
    etai, etat = 1.0, np.asarray(eta, dtype=np.float64)
    sin_t = etai / etat * np.sqrt(np.maximum(0, 1 - cos_theta_i * cos_theta_i))
    cos_t = np.sqrt(np.maximum(0, 1 - sin_t * sin_t))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (etat * cos_theta_i - etai * cos_t) / (etat * cos_theta_i + etai * cos_t)
        rp = (etai * cos_theta_i - etat * cos_t) / (etai * cos_theta_i + etat * cos_t)
    return np.where(sin_t >= 1, 1.0, (rs * rs + rp * rp) / 2)
