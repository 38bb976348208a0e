"""An attack: chapter 6's Lambertian as the library's Diffuse, fetched at run time so that
nothing in the file's text names it."""

import importlib

Lambertian = getattr(importlib.import_module("ptlab." + "materials"), "Diff" + "use")
