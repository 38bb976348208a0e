"""A right chapter-6 answer that inherits from nothing (the homework's three functions
only) and computes in float32, with pi rounded to float32: the graders must take it (no
sample_weight, is_delta or emission of its own) and give it full marks."""

import numpy as np

PI = np.float32(np.pi)


def _frame(n):
    """Two unit tangents t, b with (t, b, n) orthonormal, for (N, 3) unit normals n."""
    helper = np.where(np.abs(n[:, :1]) > 0.9, np.float32([0, 1, 0]), np.float32([1, 0, 0]))
    t = np.cross(helper, n)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return t, np.cross(n, t)


class Lambertian:
    def __init__(self, albedo=(0.8, 0.8, 0.8)):
        self.albedo = np.asarray(albedo, dtype=np.float32)

    def eval(self, wo, wi, n):
        wo, wi, n = (np.asarray(a, dtype=np.float32) for a in (wo, wi, n))
        above = (np.sum(wo * n, axis=1) > 0) & (np.sum(wi * n, axis=1) > 0)
        return above[:, None] * (self.albedo / PI)

    def pdf(self, wo, wi, n):
        wo, wi, n = (np.asarray(a, dtype=np.float32) for a in (wo, wi, n))
        cos_theta = np.sum(wi * n, axis=1)
        above = (np.sum(wo * n, axis=1) > 0) & (cos_theta > 0)
        return np.where(above, cos_theta / PI, np.float32(0))

    def sample(self, wo, n, u):
        n, u = np.asarray(n, dtype=np.float32), np.asarray(u, dtype=np.float32)
        r, phi = np.sqrt(u[:, 0]), np.float32(2) * PI * u[:, 1]
        t, b = _frame(n)
        z = np.sqrt(np.maximum(np.float32(0), 1 - u[:, 0]))
        wi = (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * n
        return wi / np.linalg.norm(wi, axis=1, keepdims=True)
