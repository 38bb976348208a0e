"""Materials (see ``ptlab.materials.base`` for the interface and its conventions, and
``ptlab.materials.parameters`` for what the renderer does with their parameters)."""

from ptlab.materials.base import Material
from ptlab.materials.dielectric import Dielectric
from ptlab.materials.diffuse import Diffuse
from ptlab.materials.microfacet import METALS, Microfacet
from ptlab.materials.mirror import Mirror

__all__ = ["METALS", "Dielectric", "Diffuse", "Material", "Microfacet", "Mirror"]
