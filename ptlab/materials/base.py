"""The ``Material`` interface: how a surface scatters light.

A material answers three questions about directions at a surface point (pbrt-v4's
BxDF ``f`` / ``PDF`` / ``Sample_f``; GAMES101 Homework 7's ``eval`` / ``pdf`` / ``sample``):

* ``eval(wo, wi, n)``: the BSDF value f_r, *without* the cosine factor;
* ``pdf(wo, wi, n)``: the solid-angle density with which ``sample`` picks ``wi``;
* ``sample(wo, n, u)``: a direction ``wi`` drawn from that density.

Conventions (the whole library's): every direction is a unit vector pointing *away* from the
surface; ``wo`` toward the viewer, ``wi`` toward the light; ``n`` the unit shading normal.
Arrays are (N, 3), colours (N, 3). (GAMES101 passes the incoming ray direction, which
points *toward* the surface, as its first argument: its ``wi`` is our ``-wo``.)

**front.** ``sample`` and ``sample_weight`` also take ``front``, (N,) bool or None: True
where ``wo`` is on the side the surface's geometric normal points to (its outside), as the
renderer knows it (``SurfaceHit.front``, with ``n`` turned toward ``wo``). Only materials
that let light through (``Dielectric``) need it; the others ignore it, and a material may
leave it out of its own ``sample``, as the homework's ``sample(wo, n, u)`` does: the
renderer gives ``front`` to ``sample_weight`` only, and the ``sample_weight`` below calls
``sample(wo, n, u)`` without it.

A material's parameters (its sampling, its rows when the renderer shades many materials of
one kind in one call, its textures) are ``ptlab.materials.parameters``'s business.
"""

from __future__ import annotations

import numpy as np

from ptlab.materials.parameters import MaterialParameters
from ptlab.vectors import dot

__all__ = ["HOMEWORK_METHODS", "DeltaMaterial", "Material"]

#: The three functions GAMES101 Homework 7 asks of a material, and all that the graders and
#: the renderer need of one (``ptlab.grading.material.as_material`` supplies the rest).
HOMEWORK_METHODS = ("eval", "pdf", "sample")


class Material(MaterialParameters):
    """Base class: subclasses implement ``eval``, ``pdf`` and ``sample``.

    Attributes:
        emission: (3,) emitted radiance, or None for a surface that does not glow.
        is_delta: True for perfect mirrors and glass, whose eval/pdf are Dirac deltas.
    """

    emission: np.ndarray | None = None
    is_delta: bool = False

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N, 3) BSDF value f_r(wo, wi), cosine not included."""
        raise NotImplementedError

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N,) solid-angle density with which ``sample`` picks ``wi``."""
        raise NotImplementedError

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        """(N, 3) unit directions drawn with density ``pdf``; u: (N, 2) in [0, 1)."""
        raise NotImplementedError

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Sample ``wi`` and return it with its Monte Carlo weight f_r cos / pdf.

        This is the factor by which a path's throughput is multiplied at a bounce
        (pbrt-v4 ``Sample_f``). Where the pdf is 0 the weight is 0, never NaN. Made of the
        three functions, with ``sample(wo, n, u)``: a material whose directions depend on
        ``front`` gives its own.
        """
        # (Called as Material.sample_weight(obj, ...) by graders, on objects with only the
        # three functions: so Material's own helper, by name.)
        wi, weight, _ = Material._sampled(self, wo, n, u)
        return wi, weight

    def sample_weight_pdf(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``sample_weight``'s (wi, weight) and the pdf with which ``wi`` was chosen, which
        multiple importance sampling weighs the emission found along ``wi`` by. The sample
        carries its pdf, as pbrt-v4's ``BSDFSample`` and Mitsuba 3's ``BSDFSample3f`` do, so
        that the renderer need not ask ``pdf`` again: the generic ``sample_weight`` has it
        already. A material with a ``sample_weight`` of its own (a closed form, a delta) is
        asked for its pdf afterwards.
        """
        if type(self).sample_weight is not Material.sample_weight:
            wi, weight = self.sample_weight(wo, n, u, front)
            return wi, weight, self.pdf(wo, wi, n)
        return self._sampled(wo, n, u)

    def _sampled(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(wi, f_r cos / pdf, pdf) from the three functions."""
        wi = self.sample(wo, n, u)
        f = self.eval(wo, wi, n)
        pdf = self.pdf(wo, wi, n)
        cos_theta_i = np.abs(dot(wi, n))
        ok = pdf > 0
        scale = np.where(ok, cos_theta_i / np.where(ok, pdf, 1), 0).astype(f.dtype)
        return wi, scale[:, None] * f, pdf


class DeltaMaterial(Material):
    """Base of perfect mirrors and glass: they scatter into single directions only.

    Their BSDF is a Dirac delta, which no direction chosen apart from it can hit, so by
    pbrt-v4's convention ``eval`` and ``pdf`` are 0 and ``sample_weight`` does all the work.
    """

    is_delta = True

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N, 3) zeros: a delta BSDF has no value at directions chosen apart from it."""
        return np.zeros(wi.shape, dtype=wi.dtype, order="F")

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N,) zeros (see ``eval``)."""
        return np.zeros(len(wi), dtype=wi.dtype)
