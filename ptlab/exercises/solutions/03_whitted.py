"""Chapter 3, the library's own answer: ``ptlab.vectors.reflect`` and, from
``ptlab.materials.dielectric``, ``refract`` and ``fresnel_dielectric`` (the same signatures)."""

from ptlab.materials.dielectric import fresnel_dielectric as fresnel
from ptlab.materials.dielectric import refract
from ptlab.vectors import reflect

__all__ = ["reflect", "refract", "fresnel"]
