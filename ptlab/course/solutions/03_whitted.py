"""Chapter 3, the library's own answer: ``reflect``, ``refract`` and ``fresnel_dielectric``
from ``ptlab.scattering`` (the same signatures)."""

from ptlab.scattering import fresnel_dielectric as fresnel
from ptlab.scattering import reflect, refract

__all__ = ["fresnel", "reflect", "refract"]
