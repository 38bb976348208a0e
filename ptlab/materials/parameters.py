"""A material's parameters, apart from how it scatters light: its sampling, rows and textures.

``ptlab.materials.base`` says what a material answers (``eval``, ``pdf``, ``sample``); this
module holds what the renderer does with the parameters behind those answers, as pbrt-v4
keeps its ``Material`` (parameters and textures, evaluated at each hit) apart from the
``BxDF`` it makes there (the scattering function alone):

* **which sampling** a material uses, among those its class offers (``samplings``,
  ``with_sampling``);
* **batching**: the renderer shades all hits on materials of one kind with one call.
  Materials with equal ``batch_key``s are ``stack``ed into one whose ``batched`` parameters
  are rows, one per material (float32, like the renderer's arrays), and ``take`` picks each
  hit's row: pbrt-v4's ``GetBxDF``, for a whole batch of hits at once;
* **textures**: a ``batched`` parameter may be a ``ptlab.textures.Texture`` instead, which
  ``take`` looks up at each hit's uv (``textured``).

The defaults suit a material of the homework's three functions: it samples one way, and
shades alone, in a group of its own.
"""

from __future__ import annotations

import copy
from typing import Self

import numpy as np

from ptlab.textures import Texture
from ptlab.vectors import columns, take_rows


class MaterialParameters:
    """The parameters' side of ``ptlab.materials.Material``."""

    #: The sampling strategies a subclass offers, and the one it uses.
    samplings: tuple[str, ...] = ()
    sampling: str
    #: The parameters that may differ between materials of one kind: ``stack`` makes them
    #: rows, ``take`` picks a row (or looks a texture up) per hit.
    batched: tuple[str, ...] = ()

    def with_sampling(self, sampling: str) -> Self:
        """This material if it samples by ``sampling`` already, else a copy (of the same class)
        that does."""
        if sampling not in self.samplings:
            raise ValueError(
                f"unknown sampling {sampling!r} for {type(self).__name__}; "
                f"choose one of {', '.join(self.samplings) or 'none'}"
            )
        if self.sampling == sampling:
            return self
        twin = copy.copy(self)
        twin.sampling = sampling
        return twin

    @property
    def textured(self) -> bool:
        """True if a parameter varies over the surface (a ``Texture``): it needs the hits' uv."""
        return any(isinstance(getattr(self, name), Texture) for name in self.batched)

    def batch_key(self) -> object:
        """Materials with equal keys can be ``stack``ed into one; the default is none."""
        return id(self)

    @classmethod
    def stack(cls, materials: list[Self]) -> Self:
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

    def take(self, index: np.ndarray, uv: np.ndarray | None = None) -> Self:
        """The stacked material's parameters for each hit: row ``index[k]`` for hit k, or a
        texture's value at ``uv[k]`` ((N, 2) texture coordinates of the hits)."""
        taken = copy.copy(self)
        for name in self.batched:
            value = getattr(self, name)
            if isinstance(value, Texture):
                if uv is None:
                    raise ValueError(
                        f"{type(self).__name__}.{name} is a texture: it needs the hits' uv coordinates"
                    )
                setattr(taken, name, value(uv))
            else:
                setattr(taken, name, take_rows(value, index))
        return taken
