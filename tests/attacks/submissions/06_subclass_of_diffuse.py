"""An attack: chapter 6's Lambertian as the library's Diffuse, subclassed with nothing of
its own."""

import ptlab.materials


class Lambertian(ptlab.materials.Diffuse):
    pass
