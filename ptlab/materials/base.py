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
"""

from __future__ import annotations

import copy

import numpy as np

from ptlab.textures import Texture
from ptlab.vectors import columns, dot, take_rows

__all__ = ["DeltaMaterial", "Material", "dot"]


class Material:
    """Base class: subclasses implement ``eval``, ``pdf`` and ``sample``.

    Attributes:
        emission: (3,) emitted radiance, or None for a surface that does not glow.
        is_delta: True for perfect mirrors and glass, whose eval/pdf are Dirac deltas.
    """

    emission: np.ndarray | None = None
    is_delta: bool = False
    #: The sampling strategies a subclass offers (its ``sampling`` attribute picks one).
    samplings: tuple[str, ...] = ()

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N, 3) BSDF value f_r(wo, wi), cosine not included."""
        raise NotImplementedError

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        """(N,) solid-angle density with which ``sample`` picks ``wi``."""
        raise NotImplementedError

    def sample(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(N, 3) unit directions drawn with density ``pdf``; u: (N, 2) in [0, 1)."""
        raise NotImplementedError

    def sample_weight(self, wo: np.ndarray, n: np.ndarray, u: np.ndarray,
                      front: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Sample ``wi`` and return it with its Monte Carlo weight f_r cos / pdf.

        This is the factor by which a path's throughput is multiplied at a bounce
        (pbrt-v4 ``Sample_f``). Where the pdf is 0 the weight is 0, never NaN.

        ``front``, (N,) bool or None, says where ``wo`` is on the side the surface's
        geometric normal points to (its outside). Only materials that let light through
        (``Dielectric``) need it; the others ignore it.
        """
        wi = self.sample(wo, n, u)
        f = self.eval(wo, wi, n)
        pdf = self.pdf(wo, wi, n)
        cos_theta_i = np.abs(dot(wi, n))
        ok = pdf > 0
        scale = np.where(ok, cos_theta_i / np.where(ok, pdf, 1), 0).astype(f.dtype)
        return wi, scale[:, None] * f

    def with_sampling(self, sampling: str) -> Material:
        """A copy of this material (of the same class) that samples by ``sampling``."""
        if sampling not in self.samplings:
            raise ValueError(f"unknown sampling {sampling!r} for {type(self).__name__}; "
                             f"choose one of {', '.join(self.samplings) or 'none'}")
        twin = copy.copy(self)
        twin.sampling = sampling
        return twin

    # Batching: the renderer shades all hits on materials of one kind with one call.
    #: The parameters that may differ between materials of one kind: ``stack`` makes them
    #: rows (float32, like the renderer's arrays), ``take`` picks a row per hit. One of them
    #: may also be a ``ptlab.textures.Texture``, which ``take`` looks up at each hit's uv.
    batched: tuple[str, ...] = ()

    @property
    def textured(self) -> bool:
        """True if a parameter varies over the surface (a ``Texture``): it needs the hits' uv."""
        return any(isinstance(getattr(self, name), Texture) for name in self.batched)

    def batch_key(self) -> object:
        """Materials with equal keys can be ``stack``ed into one; the default is none."""
        return id(self)

    @classmethod
    def stack(cls, materials: list[Material]) -> Material:
        """One material whose ``batched`` parameters are rows, one per input material.

        A textured material is alone in its group (its ``batch_key`` is its own): its
        textures stay textures."""
        if not cls.batched or materials[0].textured:
            if len(materials) != 1:
                raise TypeError(f"{cls.__name__} cannot be batched")
            return materials[0]
        stacked = copy.copy(materials[0])
        for name in cls.batched:
            rows = np.stack([np.asarray(getattr(m, name)) for m in materials]).astype(np.float32)
            setattr(stacked, name, columns(rows) if rows.ndim == 2 else rows)
        return stacked

    def take(self, index: np.ndarray, uv: np.ndarray | None = None) -> Material:
        """The stacked material's parameters for each hit: row ``index[k]`` for hit k, or a
        texture's value at ``uv[k]`` ((N, 2) texture coordinates of the hits)."""
        taken = copy.copy(self)
        for name in self.batched:
            value = getattr(self, name)
            if isinstance(value, Texture):
                if uv is None:
                    raise ValueError(f"{type(self).__name__}.{name} is a texture: it needs the "
                                     f"hits' uv coordinates")
                setattr(taken, name, value(uv))
            else:
                setattr(taken, name, take_rows(value, index))
        return taken


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
