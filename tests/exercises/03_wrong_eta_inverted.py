"""A typical wrong chapter-3 answer: entering and leaving glass mixed up. The homework's
refract and fresnel work with eta = eta_i / eta_t (their etai / etat); copied here, where
eta is eta_t / eta_i, the index is inverted: rays bend away from the normal as they enter
glass, total internal reflection happens on the way *in* instead of on the way out, and the
glass sphere shows the room wrongly. Reflection is right."""

import numpy as np

from ptlab.vectors import dot

EXPECTED_FAILURES = ("refract", "fresnel", "total internal reflection", "render")


def _column(eta):
    return eta[:, None] if np.ndim(eta) else eta


def reflect(wo, n):
    return (2 * dot(wo, n))[:, None] * n - wo


def refract(wo, n, eta):
    eta = np.asarray(eta, dtype=wo.dtype)            # the bug: taken as eta_i / eta_t
    cos_i = dot(wo, n)
    k = 1 - eta * eta * (1 - cos_i * cos_i)
    return -_column(eta) * wo + (eta * cos_i - np.sqrt(np.maximum(k, 0)))[:, None] * n


def fresnel(cos_theta_i, eta):
    eta = np.asarray(eta, dtype=np.float64)          # the same mix-up: etai / etat
    sin_t = eta * np.sqrt(np.maximum(0, 1 - cos_theta_i * cos_theta_i))
    cos_t = np.sqrt(np.maximum(0, 1 - sin_t * sin_t))
    etai, etat = eta, 1.0
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (etat * cos_theta_i - etai * cos_t) / (etat * cos_theta_i + etai * cos_t)
        rp = (etai * cos_theta_i - etat * cos_t) / (etai * cos_theta_i + etat * cos_t)
    return np.where(sin_t >= 1, 1.0, (rs * rs + rp * rp) / 2)
