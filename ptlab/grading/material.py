"""Any object with the homework's three functions, as a full ``ptlab.materials.Material``.

The homework asks for ``eval(wo, wi, n)``, ``pdf(wo, wi, n)`` and ``sample(wo, n, u)`` and
nothing else ("do not change how the three functions are defined"). The graders and the
renderer also use ``sample_weight``, ``is_delta`` and ``emission``, and group materials
with ``batch_key``, ``stack`` and ``take``. ``as_material`` supplies what an object lacks:
the weight f_r |cos theta_i| / pdf from the three functions (``Material.sample_weight``),
``is_delta`` False and ``emission`` None.

Each adapted material shades its own rows (``batch_key`` is the material itself); the
course groups the materials of one student's process into one request
(``ptlab.course.sandbox.remote_material``).
"""

from __future__ import annotations

import inspect
from typing import Self

import numpy as np

from ptlab.materials.base import HOMEWORK_METHODS, Material


class NotAMaterialError(TypeError):
    """The object lacks one of ``eval``, ``pdf`` and ``sample``."""


def as_material(material) -> Material:
    """``material`` itself if it is a ``Material``, else a ``Material`` that calls it."""
    if isinstance(material, Material):
        return material
    return AdaptedMaterial(material)


class AdaptedMaterial(Material):
    """A ``Material`` around an object with ``eval``, ``pdf`` and ``sample`` (and perhaps
    ``sample_weight``, ``is_delta``, ``emission``)."""

    def __init__(self, material):
        missing = [name for name in HOMEWORK_METHODS if not callable(getattr(material, name, None))]
        if missing:
            raise NotAMaterialError(f"it has no {', '.join(missing)} (a material has eval, pdf and sample)")
        self.material = material
        self._eval, self._pdf, self._sample = (getattr(material, name) for name in HOMEWORK_METHODS)
        weight = getattr(material, "sample_weight", None)
        self._sample_weight = weight if callable(weight) else None
        self._weight_takes_front = self._sample_weight is not None and _takes_front(weight)
        is_delta = getattr(material, "is_delta", False)
        self.is_delta = bool(is_delta) if isinstance(is_delta, bool | np.bool_) else False
        self.emission = _emission(getattr(material, "emission", None))

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        return self._eval(wo, wi, n)

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        return self._pdf(wo, wi, n)

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        # The homework's sample(wo, n, u) has no front (ptlab.materials.base): it is not passed on.
        return self._sample(wo, n, u)

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        if self._sample_weight is None:
            return super().sample_weight(wo, n, u, front)
        if front is not None and self._weight_takes_front:
            return self._sample_weight(wo, n, u, front)
        return self._sample_weight(wo, n, u)

    def take(self, index: np.ndarray, uv: np.ndarray | None = None) -> Self:
        return self

    def __getattr__(self, name: str):
        # Other attributes (a glass's ``eta``, which the delta checks read) are the object's.
        if name.startswith("_") or name == "material":
            raise AttributeError(name)
        return getattr(self.material, name)

    def __repr__(self) -> str:
        return repr(self.material)


def derives_sample_weight(material) -> bool:
    """Whether ``material``'s sample_weight is the graders' own, made of its three functions."""
    return isinstance(material, AdaptedMaterial) and material._sample_weight is None


def _takes_front(method) -> bool:
    try:
        parameters = inspect.signature(method).parameters.values()
    except (TypeError, ValueError):
        return True
    return any(p.name == "front" or p.kind == p.VAR_POSITIONAL for p in parameters)


def _emission(value) -> np.ndarray | None:
    """A (3,) emitted radiance, or None for anything else."""
    if value is None:
        return None
    try:
        emission = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return emission if emission.shape == (3,) and np.isfinite(emission).all() else None
