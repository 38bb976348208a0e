"""Chapter 1, the library's own answer: ``ptlab.camera.generate_rays``."""

from ptlab.camera import generate_rays

__all__ = ["generate_rays"]
