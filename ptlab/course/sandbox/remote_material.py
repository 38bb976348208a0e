"""A student's material, shaded in the student's process, in as few requests as can be.

``ptlab.grading.material.as_material`` makes any object with the homework's three functions a
full ``Material``, each shading its own rows. A student's materials live in the student's
process (``RemoteObject`` stand-ins), where one request costs a round trip: the materials
of one process that the renderer shades in one batch of hits are grouped
(``MaterialGroup``), so one request shades all the rows, each with its own material.
"""

from __future__ import annotations

import copy
from typing import Self

import numpy as np

from ptlab.course.sandbox import RemoteObject, submission_of
from ptlab.grading.material import AdaptedMaterial, as_material
from ptlab.materials.base import Material


def as_student_material(material) -> Material:
    """``as_material(material)``, grouped with its process's others if it is a stand-in."""
    if isinstance(material, RemoteObject):
        return RemoteMaterial(material)
    return as_material(material)


class RemoteMaterial(AdaptedMaterial):
    """An ``AdaptedMaterial`` around a stand-in of the student's process."""

    def batch_key(self) -> object:
        """Stand-ins of one student's process, alike in what they define, shade together."""
        return (
            "student",
            id(submission_of(self.material)),
            self.is_delta,
            self._sample_weight is None,
            self._weight_takes_front,
        )

    # (Not a RemoteMaterial as Material.stack's Self says: stand-ins stack into a group that
    # shades each row with its own member, as the renderer needs no more of a stack.)
    @classmethod
    def stack(cls, materials: list[AdaptedMaterial]) -> Material:  # type: ignore[override]
        return materials[0] if len(materials) == 1 else MaterialGroup(materials)


class MaterialGroup(Material):
    """Several ``AdaptedMaterial``s of one student's process with the same ``batch_key``;
    after ``take(index)``, row k is shaded by member ``index[k]``, all rows in one request."""

    def __init__(self, members: list[AdaptedMaterial]):
        self.members = members
        self.is_delta = members[0].is_delta
        self.which: np.ndarray | None = None
        self._derived_weight = members[0]._sample_weight is None
        self._takes_front = members[0]._weight_takes_front

    def take(self, index: np.ndarray, uv: np.ndarray | None = None) -> Self:
        taken = copy.copy(self)
        taken.which = index
        return taken

    def _each(self, method: str, *arrays):
        if self.which is None:
            raise ValueError("a group of materials shades the rows take() gives it, and it has none")
        objects = [m.material for m in self.members]
        return submission_of(objects[0]).call_each(objects, self.which, method, *arrays)

    def eval(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        return self._each("eval", wo, wi, n)

    def pdf(self, wo: np.ndarray, wi: np.ndarray, n: np.ndarray) -> np.ndarray:
        return self._each("pdf", wo, wi, n)

    def sample(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> np.ndarray:
        # The homework's sample(wo, n, u) has no front (ptlab.materials.base): it is not passed on.
        return self._each("sample", wo, n, u)

    def sample_weight(
        self, wo: np.ndarray, n: np.ndarray, u: np.ndarray, front: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        if self._derived_weight:
            return super().sample_weight(wo, n, u, front)
        if front is not None and self._takes_front:
            return self._each("sample_weight", wo, n, u, front)
        return self._each("sample_weight", wo, n, u)
