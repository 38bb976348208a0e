"""Materials (see ``ptlab.materials.base`` for the interface and its conventions)."""

from ptlab.materials.base import Material
from ptlab.materials.diffuse import Diffuse

__all__ = ["Material", "Diffuse"]
